//! The PC's view of the bus (paper §4.4, its Figure 8): a local web page that shows the
//! scene from above and from the side, the ECU's LEDs, the distance and the level, and a
//! chart of the last seconds, all from the `DistanceFrame`s on the bus, decoded with the
//! DBC.
//!
//! - [`state`]: what the page shows, from the frames alone (no signal, fault, the LEDs the
//!   level names), and a log under a replay clock;
//! - [`feed`]: a replayed log or a live bus, and the snapshot the page draws;
//! - `live` (feature `server`, on by default): live feeds, the host simulation in real
//!   time and an SLCAN adapter;
//! - `server` (feature `server`): the HTTP server (the page, its event stream, its
//!   requests).

pub mod feed;
#[cfg(feature = "server")]
pub mod live;
#[cfg(feature = "server")]
pub mod server;
pub mod state;

use std::path::Path;

use crate::dbc::Database;
use crate::log::LogFormat;
use feed::Feed;
use state::{Replay, ViewFrames};

/// A log, read whole and paused at its start, as a feed.
///
/// # Errors
/// The DBC has no `DistanceFrame`, or the log cannot be opened. Bad lines are not errors:
/// the replay names them and plays the rest.
pub fn replay(db: &Database, log: &Path, format: Option<LogFormat>) -> Result<Feed, String> {
    let frame = ViewFrames::find(db)?;
    let name = log.display().to_string();
    let entries = crate::log::open(log, format)?;
    Ok(Feed::Replay(Replay::new(&frame, entries, &name), name))
}
