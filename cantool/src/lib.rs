//! `cw-can`, the engineer's PC on the bus (paper §4.4): read CAN logs and decode them
//! with a DBC, encode signal values into a frame, as cantools and python-can do.
//!
//! The book: [CAN tools](../../book/cw-can.html) and [the view of the bus](../../book/view.html).
//!
//! - [`frame`]: a frame as logs hold it (classic, FD, remote, error; up to 64 bytes) and
//!   can-utils' compact text form;
//! - [`log`]: candump logs, line by line, a bad line named and skipped;
//! - [`asc`] and [`blf`]: Vector's ASC (text) and BLF (binary, zlib containers) logs;
//! - [`dbc`]: a DBC checked once at load (sizes, layouts, floats, multiplexers);
//! - [`codec`]: signals decoded and encoded with cantools' semantics, the bits by the
//!   ECU's own proved codec;
//! - [`slcan`]: a live bus through an SLCAN adapter (serial device or `socket://`);
//! - [`report`]: the decoded frames as text lines, JSON objects or CSV rows;
//! - [`view`]: what the PC's view of the bus shows, from the `DistanceFrame`s alone.

#![forbid(unsafe_code)]
// Input from outside (a DBC, a log line, a value typed by the engineer) is an error value
// with its line, never a panic.
#![cfg_attr(
    not(test),
    warn(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod asc;
pub mod blf;
pub mod codec;
pub mod dbc;
pub mod frame;
pub mod log;
pub mod report;
pub mod slcan;
pub mod view;
