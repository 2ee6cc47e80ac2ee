//! The bus trace in the `candump -l` log format (can-utils), readable by `canplayer`,
//! python-can (`can.CanutilsLogReader`) and cantools.
//!
//! One line per frame: `(1700000000.123456) can0 100#DC05000000000000`
//!
//! - timestamp: a configurable epoch in seconds (default 1 700 000 000, so logs look like
//!   real captures and stay reproducible) plus the virtual time, seconds zero-padded to 10
//!   digits and exactly 6 decimal digits, as candump prints them;
//! - interface name (default `can0`);
//! - id: standard ids as 3 uppercase hex digits, extended ids as 8;
//! - `#`, then the data as uppercase hex without separators (nothing for an empty frame:
//!   `100#`). Remote frames print `R` and, for a non-zero DLC, its digit (`100#R2`).
//!
//! Frames come from [`VirtualBus::take_trace`](super::VirtualBus::take_trace) (turn
//! tracing on first) or from anything implementing [`embedded_can::Frame`].
//!
//! Units: `time_us` microseconds of virtual time, `epoch_s` seconds.

use core::fmt::Write as _;
use std::io;
use std::string::String;

use embedded_can::{Frame, Id};

use super::can::{BusRecord, VirtualBus};

/// The default epoch, seconds: 2023-11-14 22:13:20 UTC.
pub const DEFAULT_EPOCH_S: u64 = 1_700_000_000;

/// One candump log line for `frame`, without the line feed.
pub fn candump_line<F: Frame>(epoch_s: u64, interface: &str, time_us: u64, frame: &F) -> String {
    let mut line = String::with_capacity(48);
    let seconds = epoch_s.saturating_add(time_us / 1_000_000);
    let micros = time_us % 1_000_000;
    // Writing into a String cannot fail.
    let _ = write!(line, "({seconds:010}.{micros:06}) {interface} ");
    let _ = match frame.id() {
        Id::Standard(id) => write!(line, "{:03X}#", id.as_raw()),
        Id::Extended(id) => write!(line, "{:08X}#", id.as_raw()),
    };
    if frame.is_remote_frame() {
        line.push('R');
        let dlc = frame.dlc();
        if (1..=8).contains(&dlc) {
            let _ = write!(line, "{dlc}");
        }
    } else {
        for byte in frame.data() {
            let _ = write!(line, "{byte:02X}");
        }
    }
    line
}

/// Writes frames as a candump log to any [`io::Write`].
#[derive(Debug)]
pub struct CandumpLog<W: io::Write> {
    out: W,
    epoch_s: u64,
    interface: String,
}

impl<W: io::Write> CandumpLog<W> {
    /// A log on `out`, epoch [`DEFAULT_EPOCH_S`], interface `can0`.
    pub fn new(out: W) -> Self {
        Self {
            out,
            epoch_s: DEFAULT_EPOCH_S,
            interface: String::from("can0"),
        }
    }

    /// Sets the epoch added to the virtual time, seconds.
    pub fn with_epoch_s(mut self, epoch_s: u64) -> Self {
        self.epoch_s = epoch_s;
        self
    }

    /// Sets the interface name written on each line.
    pub fn with_interface(mut self, interface: &str) -> Self {
        self.interface = String::from(interface);
        self
    }

    /// Writes one frame seen at `time_us` of virtual time.
    ///
    /// # Errors
    /// Whatever the writer reports.
    pub fn record<F: Frame>(&mut self, time_us: u64, frame: &F) -> io::Result<()> {
        let line = candump_line(self.epoch_s, &self.interface, time_us, frame);
        writeln!(self.out, "{line}")
    }

    /// Writes bus records in order.
    ///
    /// # Errors
    /// Whatever the writer reports; records before the failing one are written.
    pub fn record_all(&mut self, records: &[BusRecord]) -> io::Result<()> {
        records
            .iter()
            .try_for_each(|r| self.record(r.time_us, &r.frame))
    }

    /// Writes the frames the bus completed since the last trace was taken (tracing must
    /// be on, see [`VirtualBus::set_tracing`]); returns how many.
    ///
    /// # Errors
    /// Whatever the writer reports.
    pub fn drain_from(&mut self, bus: &VirtualBus) -> io::Result<usize> {
        let records = bus.take_trace();
        self.record_all(&records)?;
        Ok(records.len())
    }

    /// Flushes the writer.
    ///
    /// # Errors
    /// Whatever the writer reports.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The writer.
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// Gives the writer back.
    pub fn into_inner(self) -> W {
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::host::clock::VirtualClock;
    use cw_core::can::{CanFrame, CanId};
    use std::vec::Vec;

    fn frame(id: Option<CanId>, data: &[u8]) -> CanFrame {
        id.and_then(|id| CanFrame::from_parts(id, data))
            .unwrap_or_else(|| panic!("bad test frame"))
    }

    fn text(log: CandumpLog<Vec<u8>>) -> String {
        String::from_utf8(log.into_inner()).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn standard_extended_and_empty_frames_print_exactly() {
        let mut log = CandumpLog::new(Vec::new());
        // 1500 mm, little-endian u32, in an 8-byte PDU.
        let distance = frame(CanId::standard(0x100), &[0xDC, 0x05, 0, 0, 0, 0, 0, 0]);
        let extended = frame(CanId::extended(0x18DA_F110), &[0x02, 0x3E, 0x00]);
        let empty = frame(CanId::standard(0x100), &[]);
        assert!(log.record(123_456, &distance).is_ok());
        assert!(log.record(2_000_001, &extended).is_ok());
        assert!(log.record(5, &empty).is_ok());
        assert_eq!(
            text(log),
            "(1700000000.123456) can0 100#DC05000000000000\n\
             (1700000002.000001) can0 18DAF110#023E00\n\
             (1700000000.000005) can0 100#\n"
        );
    }

    #[test]
    fn small_ids_are_zero_padded_and_epoch_and_interface_are_configurable() {
        let mut log = CandumpLog::new(Vec::new())
            .with_epoch_s(0)
            .with_interface("vcan1");
        let low_std = frame(CanId::standard(0x7), &[0xab]);
        let low_ext = frame(CanId::extended(0x7), &[]);
        assert!(log.record(1_000_000, &low_std).is_ok());
        assert!(log.record(0, &low_ext).is_ok());
        assert_eq!(
            text(log),
            "(0000000001.000000) vcan1 007#AB\n(0000000000.000000) vcan1 00000007#\n"
        );
    }

    #[test]
    fn remote_frames_use_the_r_notation() {
        struct Remote;
        impl Frame for Remote {
            fn new(_: impl Into<Id>, _: &[u8]) -> Option<Self> {
                None
            }
            fn new_remote(_: impl Into<Id>, _: usize) -> Option<Self> {
                None
            }
            fn is_extended(&self) -> bool {
                false
            }
            fn is_remote_frame(&self) -> bool {
                true
            }
            fn id(&self) -> Id {
                Id::Standard(embedded_can::StandardId::ZERO)
            }
            fn dlc(&self) -> usize {
                2
            }
            fn data(&self) -> &[u8] {
                &[]
            }
        }
        assert_eq!(
            candump_line(DEFAULT_EPOCH_S, "can0", 0, &Remote),
            "(1700000000.000000) can0 000#R2"
        );
    }

    #[test]
    fn logs_what_completed_on_the_bus() {
        let clock = VirtualClock::new();
        let bus = VirtualBus::new(&clock);
        bus.set_tracing(true);
        let mut a = bus.attach_tester();
        let _b = bus.attach_tester();
        a.send(&frame(CanId::standard(0x100), &[0xDC, 0x05, 0, 0]));
        bus.run_until(1_000);
        let mut log = CandumpLog::new(Vec::new());
        assert_eq!(log.drain_from(&bus).ok(), Some(1));
        assert_eq!(log.drain_from(&bus).ok(), Some(0), "each frame logged once");
        let end_us = bus
            .frame_duration_ns(&frame(CanId::standard(0x100), &[0xDC, 0x05, 0, 0]))
            .div_ceil(1_000);
        assert_eq!(
            text(log),
            std::format!("(1700000000.{end_us:06}) can0 100#DC050000\n")
        );
    }
}
