//! How the runs in virtual time drive QEMU's mps2-an386, which the host tools (`cargo
//! xtask qemu`, the emulator-in-the-loop tests) and the measuring image agree on.
//!
//! Under `-icount shift=N` every instruction advances QEMU's virtual clock by 2^N ns, so
//! time in the image is a function of the instructions it executes, not of the host's
//! speed. The trace's clock is SysTick at the board's 25 MHz (40 ns per count): at
//! `shift=5` (32 ns per instruction, a 31.25 MHz core, close to the board's 25 MHz) one
//! count is 0.8 instructions, so a path is measured to about one instruction. (At
//! `shift=0`, one instruction per ns, a count was 40 instructions.)

/// QEMU's `-icount` shift of the runs in virtual time.
pub const SHIFT: u32 = 5;

/// Virtual nanoseconds per instruction.
pub const NS_PER_INSTRUCTION: u64 = 1 << SHIFT;

/// Nanoseconds per SysTick count (the board's 25 MHz clock).
pub const NS_PER_SYSTICK_COUNT: u64 = 40;

/// QEMU's `-icount` argument for a run in virtual time (the virtual clock jumps over the
/// time the core sleeps).
pub const VIRTUAL: &str = "shift=5,sleep=off";

/// QEMU's `-icount` argument for a run in real time (the virtual clock follows the host's
/// while the core sleeps, for the live tests against python-can and the sensor).
pub const REAL_TIME: &str = "shift=5,sleep=on";

/// The trace keeps lengths in sixteenths of a SysTick count, so that a mean taken off
/// (the measuring's own cost) keeps its fraction.
pub const SIXTEENTHS: u64 = 16;

/// Instructions in `sixteenths` sixteenths of a SysTick count, rounded to nearest.
pub const fn instructions(sixteenths: u64) -> u64 {
    let per = SIXTEENTHS * NS_PER_INSTRUCTION;
    (sixteenths * NS_PER_SYSTICK_COUNT + per / 2) / per
}

/// The mean instructions of `count` lengths whose sixteenths of a SysTick count add up to
/// `sum`, rounded to nearest (0 for no length).
pub const fn mean_instructions(sum: u64, count: u32) -> u64 {
    if count == 0 {
        return 0;
    }
    let ns16 = sum.saturating_mul(NS_PER_SYSTICK_COUNT) / count as u64;
    let per = SIXTEENTHS * NS_PER_INSTRUCTION;
    (ns16 + per / 2) / per
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_argument_names_the_shift_and_counts_convert_to_instructions() {
        let shift = VIRTUAL
            .strip_prefix("shift=")
            .and_then(|rest| rest.split(',').next())
            .and_then(|n| n.parse::<u32>().ok());
        assert_eq!(shift, Some(SHIFT));
        assert_eq!(REAL_TIME.split(',').next(), VIRTUAL.split(',').next());
        // 4 counts are 160 ns: 5 instructions of 32 ns.
        assert_eq!(instructions(4 * SIXTEENTHS), 5);
        assert_eq!(instructions(0), 0);
        assert_eq!(instructions(800 * SIXTEENTHS), 1000);
        // A sixteenth of a count is 2.5 ns: twelve are 30 ns, one instruction rounded;
        // six are 15 ns, none.
        assert_eq!(instructions(12), 1);
        assert_eq!(instructions(6), 0);
        // Three spans of 173 counts together: 2,306 ns each on average, 72.1 instructions;
        // of 174: 2,320 ns, 72.5, rounded up.
        assert_eq!(mean_instructions(173 * SIXTEENTHS, 3), 72);
        assert_eq!(mean_instructions(174 * SIXTEENTHS, 3), 73);
        assert_eq!(mean_instructions(5, 0), 0);
    }
}
