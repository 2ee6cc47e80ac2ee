//! The production image on mps2-an386 (`cw-mps2`): the ECU as it would be flashed, with
//! the ranging module on UART1, the CAN controller on UART0 (SLCAN), the CMSDK watchdog,
//! and the mode inputs tied on; no scenario, trace or report.

use cw_bsp::cortex_m::{App, CortexMPort};
use cw_bsp::mps2::{self, Led, SensorUart, SlcanCan};
use cw_bsp::port::preempt::PortFault;
use cw_core::os::TaskId;

use super::{
    board_irq, isr_priority, report_supervision, shutdown_report, start_os_with_devices,
    Mps2PortDriver,
};
pub use crate::board::TiedOn;
use crate::board::{Board, NoFaults, SerialSensor};
use crate::config::{self, Kernel};
use crate::ecu::Ecu;

/// The mps2-an386 board as the production image (`cw-mps2`) wires it: the ranging module
/// on UART1 is the sensor, and the mode inputs are tied on (the board has no ignition or
/// bus-enable line: ignition on, communication enabled; a vehicle's ECU reads pins).
pub struct Mps2FlashBoard;

impl Board for Mps2FlashBoard {
    type Can = SlcanCan;
    type Led = Led;
    type Sensor = SerialSensor<SensorUart>;
    type ModeInput = TiedOn;
    type Port = Mps2PortDriver;
    type Watchdog = mps2::CmsdkWatchdog;
    type Faults = NoFaults;
}

/// The production image's entry points: the ECU and nothing else. No scenario, no task
/// trace or spans (cw-bsp without `trace`), no end-of-run report: it runs until the OS
/// shuts down (a stack fault), logging its start and its faults.
pub struct Mps2FlashApp {
    /// The ECU.
    pub ecu: Ecu<CortexMPort<Kernel>, Mps2FlashBoard>,
}

impl App for Mps2FlashApp {
    fn start_os(&self) {
        cortex_m::interrupt::disable();
        mps2::start_tick(isr_priority(config::os::SYS_TICK_ISR));
        start_os_with_devices(&self.ecu, true);
    }

    fn run_job(&self, task: TaskId) {
        self.ecu.run_job(task);
    }

    fn idle(&self) {
        report_supervision("cw-mps2", &self.ecu);
    }

    fn tick(&self) {
        mps2::on_tick();
        self.ecu.tick();
    }

    fn irq(&self, line: u16) {
        board_irq(&self.ecu, line);
    }

    fn report(&self, fault: &PortFault) {
        report_supervision("cw-mps2", &self.ecu);
        mps2::report(fault);
    }

    fn halt(&self) -> ! {
        mps2::halt()
    }

    fn shut_down(&self) -> ! {
        // EcuM's reset after the shutdown (QEMU, run with -no-reboot, exits).
        shutdown_report("cw-mps2", &self.ecu);
        mps2::halt()
    }
}
