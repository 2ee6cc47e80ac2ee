//! Live feeds: a thread reads the bus and pushes each `DistanceFrame` into the view's
//! [`Live`] feed as it arrives; the sender panel's frames go the other way.
//!
//! - [`simulation`]: the ECU's host simulation (`cw-ecu`), paced to real time, with the PC
//!   on its bus; its frames are stamped as `cw-ecu --can-log` stamps them.
//! - [`slcan`]: an SLCAN adapter (a serial device, or `socket://` such as the QEMU image's
//!   UART); its frames are stamped by this PC's clock, as python-can stamps them.

use std::sync::mpsc;
use std::sync::{Arc, Mutex, PoisonError};
use std::thread;
use std::time::{Duration, Instant};

use cw_bsp::host::candump::DEFAULT_EPOCH_S;
use cw_core::can::CanFrame;
use cw_firmware::host::{Scenario, Simulation};

use super::feed::{Feed, Live, Shared};
use super::state::ViewFrames;
use crate::dbc::Database;
use crate::frame::Frame;
use crate::log::Entry;
use crate::slcan::{Limits, SlcanSource};

fn with_live(feed: &Mutex<Feed>, f: impl FnOnce(&mut Live)) {
    if let Feed::Live(live) = &mut *feed.lock().unwrap_or_else(PoisonError::into_inner) {
        f(live);
    }
}

/// What one entry from the bus makes of the live feed: a sample, thresholds, a bad frame,
/// or nothing (another message).
fn take(live: &mut Live, frame: &ViewFrames<'_>, name: &str, entry: &Entry) {
    if let Some(thresholds) = frame.thresholds(entry) {
        live.configure(thresholds);
    }
    match frame.sample(entry) {
        None => {}
        Some(Ok(sample)) => live.push(sample),
        Some(Err(e)) => live.bad(format!("{name}: {}: {e}", entry.frame)),
    }
}

/// Starts a source's thread.
fn spawn(name: &str, body: impl FnOnce() + Send + 'static) -> Result<(), String> {
    thread::Builder::new()
        .name(format!("view-{name}"))
        .spawn(body)
        .map(|_| ())
        .map_err(|e| format!("cannot start the {name} thread: {e}"))
}

/// The host simulation of `scenario` (named `name`), in real time from now, as a live
/// feed; the sender panel's frames go on its bus from the PC. When the scenario ends, the
/// simulation stops and the view shows no signal.
///
/// # Errors
/// The DBC has no `DistanceFrame`.
pub fn simulation(
    db: &Database,
    scenario: Scenario,
    seed: u64,
    name: &str,
) -> Result<Shared, String> {
    ViewFrames::find(db)?;
    let (to_bus, from_pc) = mpsc::channel::<CanFrame>();
    let send = move |frame: &Frame| {
        let frame = frame.to_classic().ok_or_else(|| {
            format!("{frame}: the simulated bus carries classic data frames only")
        })?;
        to_bus
            .send(frame)
            .map_err(|_| "the simulation has ended".to_string())
    };
    let live = Live::new("simulation", name, Some(Box::new(send)), false)
        .with_origin(DEFAULT_EPOCH_S as f64);
    let feed: Shared = Arc::new(Mutex::new(Feed::Live(live)));
    let (db, shared, name) = (db.clone(), Arc::clone(&feed), name.to_string());
    spawn("simulation", move || {
        let Ok(frame) = ViewFrames::find(&db) else {
            return;
        };
        // The simulation holds shared handles of one thread: it is made in its own.
        let mut sim = match Simulation::new(scenario, seed) {
            Ok(sim) => sim,
            Err(e) => {
                with_live(&shared, |live| live.bad(format!("{name}: {e}")));
                return;
            }
        };
        let end_ms = sim.scenario().duration_ms();
        let started = Instant::now();
        let epoch = DEFAULT_EPOCH_S as f64;
        while sim.now_ms() < end_ms {
            while let Ok(frame) = from_pc.try_recv() {
                sim.send_from_pc(&frame);
            }
            let next = (sim.now_ms() + 10).min(end_ms);
            sim.run_until_ms(next);
            let records = sim.take_frames();
            // Hours in real time, constant memory.
            sim.forget_history();
            let now = epoch + next as f64 / 1000.0;
            with_live(&shared, |live| {
                for record in &records {
                    let id = record.frame.can_id();
                    let entry = Entry {
                        timestamp: epoch + record.time_us as f64 / 1e6,
                        channel: "sim".into(),
                        frame: Frame::classic(id.raw(), id.is_extended(), record.frame.bytes()),
                    };
                    take(live, &frame, &name, &entry);
                }
                live.set_now(now);
            });
            if let Some(wait) = Duration::from_millis(next).checked_sub(started.elapsed()) {
                thread::sleep(wait);
            }
        }
        // The scenario is over: nothing more goes on its bus, the clock goes on, and the
        // view says "no signal".
        drop(from_pc);
        while Arc::strong_count(&shared) > 1 {
            let now = epoch + started.elapsed().as_secs_f64();
            with_live(&shared, |live| live.set_now(now));
            thread::sleep(Duration::from_millis(10));
        }
    })?;
    Ok(feed)
}

/// An SLCAN adapter at `url` (`socket://HOST:PORT` or a serial device at `baud`; the
/// bit rate set first when `bitrate` is given) as a live feed; the sender panel's frames
/// are written to it. When the adapter's stream ends, that is a bad line and the view
/// shows no signal.
///
/// # Errors
/// The DBC has no `DistanceFrame`, or the adapter cannot be opened.
pub fn slcan(db: &Database, url: &str, baud: u32, bitrate: Option<u8>) -> Result<Shared, String> {
    ViewFrames::find(db)?;
    let (source, mut sender) =
        SlcanSource::open_with_sender(url, baud, bitrate, Limits::default())?;
    let feed: Shared = Arc::new(Mutex::new(Feed::Live(Live::new(
        "slcan",
        url,
        Some(Box::new(move |frame: &Frame| sender.send(frame))),
        true,
    ))));
    let (db, shared, name) = (db.clone(), Arc::clone(&feed), url.to_string());
    spawn("slcan", move || {
        let Ok(frame) = ViewFrames::find(&db) else {
            return;
        };
        for item in source {
            with_live(&shared, |live| match item {
                Ok((_, entry)) => take(live, &frame, &name, &entry),
                Err(e) => live.bad(format!("{name}:{e}")),
            });
        }
        with_live(&shared, |live| {
            live.bad(format!("{name}: the adapter's stream ended"));
        });
    })?;
    Ok(feed)
}

#[cfg(test)]
mod tests;
