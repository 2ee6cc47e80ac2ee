//! The MPC574XG-MB's bring-up, built for the Book E target (feature `mpc5748g`): the
//! start-up code, the boot header, the clocks, the pads, FlexCAN_0, the PIT and the STM.
//! It links for the chip's memory map (`mpc5748g.ld`) and never runs: see the module
//! above.

use core::sync::atomic::{AtomicBool, Ordering};

use super::{
    BootHeader, CAN_RX, CAN_RX_IMCR, CAN_TX, CAN_TX_SSS, CLOCK_PLAN, FLEXCAN0, LED_RED, LED_YELLOW,
    PCTL_FLEXCAN0, PCTL_PIT, RUN_PC, SONAR_ECHO, SONAR_ECHO_IMCR, SONAR_TRIGGER, TICK_CHANNEL,
};
use crate::chip::access::Mmio;
use crate::chip::flexcan::{Flexcan, FlexcanConfig, LayoutError};
use crate::chip::mpc5748g::mc_cgm::{self, Cgm};
use crate::chip::mpc5748g::mc_me::{self, McMe, Mode, ModeConfig};
use crate::chip::mpc5748g::pit::{self, Pit};
use crate::chip::mpc5748g::siul2::{self, Output, Siul2, OBE, SRC_FULL};
use crate::chip::mpc5748g::stm::{self, Stm};
use crate::chip::mpc5748g::swt::{self, Swt};

/// The peripheral at `base`, for volatile accesses.
fn at(base: usize) -> Mmio {
    // SAFETY: every `base` passed here is a peripheral of the MPC5748G's memory map (the
    // chip modules' `BASE`s and FLEXCAN0), mapped for the chip's whole life. Two values
    // for one block exist only for SIUL2, whose pads are configured at bring-up, before
    // anything drives them, and driven afterwards under the ECU's LED resource.
    unsafe { Mmio::new(base as *mut u8) }
}

/// What failed at bring-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BringUpError {
    /// SWT_0 would not stop.
    Watchdog(swt::SwtError),
    /// The clock plan was refused.
    Clocks(mc_cgm::CgmError),
    /// The mode transition to the PLL failed.
    Mode(mc_me::MeError),
}

/// Brings the board up: SWT_0 stopped, the dividers and the PLL prepared, DRUN
/// reconfigured to run from the PLL with FlexCAN_0 and the PIT clocked (run
/// configuration [`RUN_PC`]) and entered, the LED pads outputs (dark), the sensor's trigger
/// an output (low) and its echo routed to eMIOS_1 channel 6, FlexCAN_0's pads routed,
/// STM_0 counting microseconds, the PIT's tick channel started.
///
/// # Errors
/// [`BringUpError`] names the step.
pub fn bring_up() -> Result<(), BringUpError> {
    Swt::new(at(swt::BASE))
        .disable()
        .map_err(BringUpError::Watchdog)?;
    Cgm::new(at(mc_cgm::BASE), at(mc_cgm::PLLDIG_BASE))
        .prepare(&CLOCK_PLAN)
        .map_err(BringUpError::Clocks)?;
    let me = McMe::new(at(mc_me::BASE));
    me.configure(Mode::Drun, &ModeConfig::PLL)
        .map_err(BringUpError::Mode)?;
    me.run_configuration(RUN_PC, Mode::Drun.bit() | Mode::Run0.bit());
    me.peripheral(PCTL_FLEXCAN0, RUN_PC);
    me.peripheral(PCTL_PIT, RUN_PC);
    me.enter(Mode::Drun).map_err(BringUpError::Mode)?;
    let siul2 = Siul2::new(at(siul2::BASE));
    siul2.configure(CAN_TX, OBE | SRC_FULL | CAN_TX_SSS);
    siul2.input(CAN_RX);
    siul2.route_input(CAN_RX_IMCR.0, CAN_RX_IMCR.1);
    siul2.output(SONAR_TRIGGER, false);
    siul2.input(SONAR_ECHO);
    siul2.route_input(SONAR_ECHO_IMCR.0, SONAR_ECHO_IMCR.1);
    let _ = (led(LED_RED), led(LED_YELLOW));
    Stm::new(at(stm::BASE)).start(160);
    Pit::new(at(pit::BASE)).start_periodic(TICK_CHANNEL, 1000);
    Ok(())
}

/// A warning LED (lit low), made an output at dark.
pub fn led(pad: siul2::Pad) -> Output<Mmio> {
    Output::new(Siul2::new(at(siul2::BASE)), pad, true)
}

/// FlexCAN_0 with `config`'s buffers.
///
/// # Errors
/// [`LayoutError`] when the buffers cannot hold the configuration.
pub fn flexcan0(config: &FlexcanConfig<'_>) -> Result<Flexcan<Mmio>, LayoutError> {
    Flexcan::new(at(FLEXCAN0), config)
}

/// Whether the OS tick's period has passed since the last call (the PIT's flag).
pub fn tick_elapsed() -> bool {
    Pit::new(at(pit::BASE)).take_flag(TICK_CHANNEL)
}

/// Microseconds on STM_0 (wraps after 71 minutes).
pub fn now_us() -> u32 {
    Stm::new(at(stm::BASE)).now()
}

/// Both LEDs dark.
pub fn leds_safe() {
    let siul2 = Siul2::new(at(siul2::BASE));
    siul2.drive(LED_RED, true);
    siul2.drive(LED_YELLOW, true);
}

extern "C" {
    fn _start() -> !;
}

/// The boot header, which the linker script places at 0x00F9_0000.
#[link_section = ".boot_header"]
#[used]
#[no_mangle]
static BOOT_HEADER: BootHeader = BootHeader {
    id: super::BOOT_ID_Z4A,
    z2: None,
    reserved: [0; 2],
    z4a: Some(_start),
    z4b: None,
};

// The start-up code, in the Book E encoding. First SWT_0, which runs out of reset, is
// stopped (its unlock keys, then `CR` with `WEN` clear, as NXP's start-up does), before
// the long RAM loop could outlast its time-out. Then the SRAM's ECC: a store narrower
// than the ECC's 64 bits would read the never-written word first, so the whole RAM region
// is written with `stmw 30`, two zeroed registers (8 bytes) a store; the address register
// is not among them, so the RAM, `.bss` with it, is all zeros. Then the stack, `.data`
// copied from flash, and `cw_mpc5748g_main`.
core::arch::global_asm!(
    ".section .text._start,\"ax\",@progbits",
    ".globl _start",
    ".type _start,@function",
    "_start:",
    "    lis 3, 0xFC05",
    "    li 4, 0",
    "    ori 4, 4, 0xC520",
    "    stw 4, 0x10(3)",
    "    li 4, 0",
    "    ori 4, 4, 0xD928",
    "    stw 4, 0x10(3)",
    "    lis 4, 0xFF00",
    "    ori 4, 4, 0x010A",
    "    stw 4, 0(3)",
    "    lis 3, __ram_start@ha",
    "    addi 3, 3, __ram_start@l",
    "    lis 4, __ram_end@ha",
    "    addi 4, 4, __ram_end@l",
    "    subf 4, 3, 4",
    "    srwi 4, 4, 3",
    "    mtctr 4",
    "    li 30, 0",
    "    li 31, 0",
    "1:",
    "    stmw 30, 0(3)",
    "    addi 3, 3, 8",
    "    bdnz 1b",
    "    lis 1, __stack_top@ha",
    "    addi 1, 1, __stack_top@l",
    "    li 0, 0",
    "    stwu 0, -16(1)",
    "    lis 3, __sdata@ha",
    "    addi 3, 3, __sdata@l",
    "    lis 4, __edata@ha",
    "    addi 4, 4, __edata@l",
    "    lis 5, __sidata@ha",
    "    addi 5, 5, __sidata@l",
    "2:",
    "    cmplw 3, 4",
    "    bge 3f",
    "    lwz 6, 0(5)",
    "    stw 6, 0(3)",
    "    addi 3, 3, 4",
    "    addi 5, 5, 4",
    "    b 2b",
    "3:",
    "    bl cw_mpc5748g_main",
    "4:",
    "    b 4b",
);

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    if !PANICKED.swap(true, Ordering::Relaxed) {
        leds_safe();
    }
    loop {
        core::hint::spin_loop();
    }
}
