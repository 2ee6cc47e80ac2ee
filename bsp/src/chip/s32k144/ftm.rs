//! The S32K144's FlexTimer (FTM; S32K1xx RM, chapter "FlexTimer Module") as an input
//! capture: the HC-SR04's echo pulse timed by the hardware, as AUTOSAR's Icu measures a
//! signal's high time.
//!
//! The counter runs free over its 16 bits from the FTM input clock (the system clock)
//! divided by `2^PS`; one channel captures the counter on both edges of the echo
//! ([`Ftm::capture_both_edges`]). [`Ftm::high_time_ticks`] takes the rising edge's capture
//! and then the falling edge's, and their difference modulo 2^16 is the pulse's width: up
//! to 65,535 ticks (at 80 MHz / 128, 1.6 us a tick, 104 ms: the HC-SR04's 38 ms
//! no-echo pulse fits). A channel's flag (`CnSC[CHF]`) is cleared by reading it set and
//! then writing 0 to it.

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::{CNSC, SC};

/// The registers' bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `SC`, status and control.
    pub SC [
        /// Counter overflowed.
        TOF OFFSET(9) NUMBITS(1) [],
        /// Clock source: 0 none (stopped), 1 the FTM input clock.
        CLKS OFFSET(3) NUMBITS(2) [
            Stopped = 0,
            FtmInput = 1
        ],
        /// Prescaler: divide by 2^PS.
        PS OFFSET(0) NUMBITS(3) []
    ],
    /// `CnSC`, a channel's status and control.
    pub CNSC [
        /// An edge was captured (read it set, then write 0).
        CHF OFFSET(7) NUMBITS(1) [],
        /// The channel's interrupt.
        CHIE OFFSET(6) NUMBITS(1) [],
        /// Mode select B.
        MSB OFFSET(5) NUMBITS(1) [],
        /// Mode select A.
        MSA OFFSET(4) NUMBITS(1) [],
        /// Edge select B (falling, in input capture).
        ELSB OFFSET(3) NUMBITS(1) [],
        /// Edge select A (rising, in input capture).
        ELSA OFFSET(2) NUMBITS(1) []
    ]
    ];
}

/// Register offsets.
pub mod offset {
    /// `SC`.
    pub const SC: usize = 0x00;
    /// `CNT`, the counter (a write restarts it from `CNTIN`).
    pub const CNT: usize = 0x04;
    /// `MOD`, the counter's last value.
    pub const MOD: usize = 0x08;
    /// `C0SC`; channel `n`'s is 8 bytes further per channel.
    pub const C0SC: usize = 0x0C;
    /// `C0V`, channel 0's captured value.
    pub const C0V: usize = 0x10;
    /// `CNTIN`, the counter's first value.
    pub const CNTIN: usize = 0x4C;
}

/// The FTMs' base addresses.
pub mod base {
    /// FTM0.
    pub const FTM0: usize = 0x4003_8000;
    /// FTM1.
    pub const FTM1: usize = 0x4003_9000;
    /// FTM2.
    pub const FTM2: usize = 0x4003_A000;
    /// FTM3.
    pub const FTM3: usize = 0x4002_6000;
}

/// Polls of a channel's flag while waiting for an edge, per microsecond of the timeout
/// (a poll is a few bus cycles: at 40 MHz, a dozen polls a microsecond is conservative).
pub const POLLS_PER_US: u32 = 12;

/// A FlexTimer used for input capture.
pub struct Ftm<A> {
    access: A,
}

impl<A: Access> Ftm<A> {
    /// The FTM behind `access` (its clock gate on, its channel's pin muxed).
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn sc(&self) -> Reg<'_, A, SC::Register> {
        Reg::new(&self.access, offset::SC)
    }

    fn cnsc(&self, channel: u8) -> Reg<'_, A, CNSC::Register> {
        Reg::new(&self.access, offset::C0SC + 8 * usize::from(channel % 8))
    }

    /// Starts the counter free-running over 16 bits from the FTM input clock divided by
    /// `2^prescale_log2` (0..=7): stopped, its range set, restarted.
    pub fn start(&self, prescale_log2: u8) {
        self.sc().write(SC::CLKS::Stopped);
        self.access.write(offset::CNTIN, 0);
        self.access.write(offset::MOD, 0xFFFF);
        self.access.write(offset::CNT, 0);
        self.sc()
            .write(SC::CLKS::FtmInput + SC::PS.val(u32::from(prescale_log2.min(7))));
    }

    /// Channel `channel` (0..=7) captures the counter on both edges of its pin.
    pub fn capture_both_edges(&self, channel: u8) {
        self.cnsc(channel).write(CNSC::ELSA::SET + CNSC::ELSB::SET);
    }

    /// The counter captured by `channel`'s last edge, if one came since the last call
    /// (its flag read set, then cleared).
    pub fn take_capture(&self, channel: u8) -> Option<u16> {
        let cnsc = self.cnsc(channel);
        if !cnsc.is_set(CNSC::CHF) {
            return None;
        }
        let value = self.access.read(offset::C0V + 8 * usize::from(channel % 8));
        cnsc.modify(CNSC::CHF::CLEAR);
        u16::try_from(value & 0xFFFF).ok()
    }

    /// Forgets an edge captured before the measurement begins.
    pub fn discard_capture(&self, channel: u8) {
        let _ = self.take_capture(channel);
    }

    /// The width of the next pulse on `channel`, in counter ticks: the rising edge's
    /// capture, then the falling edge's, their difference modulo 2^16. `None` when either
    /// edge does not come within `timeout_us` (counted in polls, [`POLLS_PER_US`]).
    pub fn high_time_ticks(&self, channel: u8, timeout_us: u32) -> Option<u16> {
        let polls = timeout_us.saturating_mul(POLLS_PER_US);
        let edge = || (0..polls).find_map(|_| self.take_capture(channel));
        let rise = edge()?;
        let fall = edge()?;
        Some(fall.wrapping_sub(rise))
    }
}

/// Microseconds of `ticks` counter ticks at `tick_hz` (rounded to nearest).
pub const fn ticks_to_us(ticks: u16, tick_hz: u32) -> u32 {
    if tick_hz == 0 {
        return 0;
    }
    ((ticks as u64 * 1_000_000 + tick_hz as u64 / 2) / tick_hz as u64) as u32
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    type Words = Recorder<{ 0x50 / 4 }, 32>;

    #[test]
    fn start_stops_the_counter_sets_its_range_then_runs_it() {
        let ftm = Ftm::new(Words::new());
        ftm.start(7);
        let writes: Vec<_> = ftm.access().writes().collect();
        assert_eq!(
            writes,
            [
                (offset::SC, 0),
                (offset::CNTIN, 0),
                (offset::MOD, 0xFFFF),
                (offset::CNT, 0),
                (offset::SC, 1 << 3 | 7),
            ]
        );
        ftm.capture_both_edges(2);
        assert_eq!(ftm.access().word(offset::C0SC + 16), 1 << 3 | 1 << 2);
    }

    #[test]
    fn a_pulse_is_the_falling_capture_minus_the_rising_one_across_the_wrap() {
        let ftm = Ftm::new(Words::new());
        ftm.capture_both_edges(0);
        // The flag reads set at each edge's check and at its clear (read, then 0 written);
        // the captures: the rising edge just before the counter wraps, the falling after.
        let flagged = 1 << 7 | 1 << 3 | 1 << 2;
        assert!(ftm
            .access()
            .script(offset::C0SC, &[flagged, flagged, flagged, flagged]));
        assert!(ftm.access().script(offset::C0V, &[0xFFF0, 0x0010]));
        assert_eq!(ftm.high_time_ticks(0, 100), Some(0x20));
        // Each flag cleared by writing 0 to it, the edge settings kept.
        let clears = ftm
            .access()
            .writes()
            .filter(|&w| w == (offset::C0SC, 1 << 3 | 1 << 2))
            .count();
        assert_eq!(clears, 1 + 2, "the set-up, then one clear per edge");
    }

    #[test]
    fn a_missing_edge_times_out() {
        let ftm = Ftm::new(Words::new());
        ftm.capture_both_edges(0);
        assert_eq!(ftm.high_time_ticks(0, 10), None);
        let flagged = 1 << 7 | 1 << 3 | 1 << 2;
        assert!(ftm.access().script(offset::C0SC, &[flagged, flagged]));
        assert!(ftm.access().script(offset::C0V, &[5]));
        assert_eq!(
            ftm.high_time_ticks(0, 10),
            None,
            "a rising edge, no falling one"
        );
    }

    #[test]
    fn ticks_convert_to_microseconds_at_the_ftm_clock() {
        // 80 MHz / 128 = 625 kHz: 1.6 us a tick; the HC-SR04's 38 ms no-echo pulse.
        assert_eq!(ticks_to_us(23_750, 625_000), 38_000);
        assert_eq!(ticks_to_us(1, 625_000), 2);
        assert_eq!(ticks_to_us(u16::MAX, 625_000), 104_856);
        assert_eq!(ticks_to_us(5, 0), 0);
    }
}
