//! The ECU on NXP's S32K144EVB (`cw-s32k144`): the board's drivers named for the ECU's
//! [`Board`] (FlexCAN0, the RGB LED as the two warning LEDs, WDOG, and the sensor: the
//! HC-SR04 on a GPIO and FTM0's input capture ([`EvbBoard`]), or a UART ranging module on
//! LPUART0 ([`EvbUartBoard`], feature `s32k144evb-uart`)), the Port driver, and the
//! image's entry points: the ECU and nothing else (no scenario, trace or report), as on
//! the mps2 production image.
//!
//! Build, check and flash: `cargo xtask s32k144` (the book: `docs/src/nxp-boards.md`).

use cw_bsp::chip::access::Mmio;
use cw_bsp::chip::flexcan::ClockSource;
use cw_bsp::chip::s32k144::port::Gpio;
use cw_bsp::cortex_m::{App, CortexMPort};
use cw_bsp::port::preempt::PortFault;
#[cfg(feature = "s32k144evb-uart")]
use cw_bsp::s32k144evb::SensorUart;
use cw_bsp::s32k144evb::{self as evb, CoreDelay, EchoCapture, EvbCan, EvbWatchdog, Led};
use cw_core::os::TaskId;

use crate::board::{
    Board, CanEvents, CanInterrupt, EchoSensor, NoFaults, PortDriver, PulseCapture, TiedOn,
};
use crate::config::{self, Kernel};
use crate::cortex_m::{isr_priority, report_supervision, shutdown_report};
use crate::ecu::Ecu;

/// The name the image logs under.
const NAME: &str = "cw-s32k144";

/// The ECU's FlexCAN on FlexCAN0: the paper's 8 MHz oscillator clock (`SOSCDIV2_CLK`).
pub const CAN_CONFIG: cw_bsp::chip::flexcan::FlexcanConfig<'static> =
    config::flexcan(ClockSource::Oscillator, evb::CAN_CLOCK_HZ);

/// The S32K144EVB as the image wires it: FlexCAN0, the RGB LED, the HC-SR04 on PTC1 and
/// PTC0 (FTM0 channel 0), WDOG, and the mode inputs tied on.
pub struct EvbBoard;

/// The HC-SR04 on the EVB.
pub type EvbSonar = EchoSensor<Gpio<Mmio>, Gpio<Mmio>, CoreDelay, EchoCapture>;

impl Board for EvbBoard {
    type Can = EvbCan;
    type Led = Led;
    type Sensor = EvbSonar;
    type ModeInput = TiedOn;
    type Port = EvbPortDriver;
    type Watchdog = EvbWatchdog;
    type Faults = NoFaults;
}

/// The S32K144EVB with a UART ranging module (A02YYUW) on LPUART0 instead of the
/// HC-SR04 (feature `s32k144evb-uart`); everything else as [`EvbBoard`].
#[cfg(feature = "s32k144evb-uart")]
pub struct EvbUartBoard;

#[cfg(feature = "s32k144evb-uart")]
impl Board for EvbUartBoard {
    type Can = EvbCan;
    type Led = Led;
    type Sensor = crate::board::SerialSensor<SensorUart>;
    type ModeInput = TiedOn;
    type Port = EvbPortDriver;
    type Watchdog = EvbWatchdog;
    type Faults = NoFaults;
}

#[cfg(feature = "s32k144evb-uart")]
impl crate::board::SerialRx for SensorUart {
    fn read_byte(&mut self) -> Option<u8> {
        SensorUart::read_byte(self)
    }
}

/// The UART ranging module on LPUART0, silent after the configuration's samples without
/// a good frame.
#[cfg(feature = "s32k144evb-uart")]
pub fn uart_sensor() -> crate::board::SerialSensor<SensorUart> {
    crate::board::SerialSensor::new(SensorUart::lpuart0(), config::SENSOR_SILENT_AFTER_SAMPLES)
}

impl CanEvents for EvbCan {
    fn take_event(&mut self) -> Option<CanInterrupt> {
        EvbCan::take_event(self).map(CanInterrupt::from)
    }
}

impl PulseCapture for EchoCapture {
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32> {
        EchoCapture::high_time_us(self, timeout_us)
    }
}

/// The Port driver: the LEDs dark (start-up muxed every pin; `evb::start_up`).
pub struct EvbPortDriver;

impl PortDriver for EvbPortDriver {
    fn port_init(&mut self) {
        evb::leds_safe();
    }
}

/// The HC-SR04's lines, delay and capture.
pub fn sonar() -> EvbSonar {
    EchoSensor {
        trigger: evb::sonar_trigger(),
        echo: evb::sonar_echo(),
        delay: CoreDelay,
        capture: EchoCapture::ftm0(),
    }
}

/// The image's entry points: the ECU and nothing else. It runs until the OS shuts down
/// (a stack fault), logging its start and its faults over RTT.
pub struct EvbApp<B: Board> {
    /// The ECU.
    pub ecu: Ecu<CortexMPort<Kernel>, B>,
    /// Whether the sensor is the UART module (its receive interrupt is enabled at start).
    pub uart_sensor: bool,
}

impl<B: Board + Sync> App for EvbApp<B>
where
    Ecu<CortexMPort<Kernel>, B>: Sync,
{
    fn start_os(&self) {
        cortex_m::interrupt::disable();
        defmt::println!(
            "{=str}: stack guards {=str}",
            NAME,
            if cw_bsp::cortex_m::stack_guards_enforced() {
                "enforced by the MPU"
            } else {
                "checked at every task switch and OS tick (the core has no Arm MPU)"
            }
        );
        evb::start_tick(isr_priority(config::os::SYS_TICK_ISR));
        evb::enable_can_interrupts(isr_priority(config::os::CAN_ISR));
        #[cfg(feature = "s32k144evb-uart")]
        if self.uart_sensor {
            SensorUart::enable_interrupt(isr_priority(config::os::SENSOR_RX_ISR));
        }
        self.ecu.start_os();
    }

    fn run_job(&self, task: TaskId) {
        self.ecu.run_job(task);
    }

    fn idle(&self) {
        report_supervision(NAME, &self.ecu);
    }

    fn tick(&self) {
        self.ecu.tick();
    }

    fn irq(&self, line: u16) {
        if evb::CAN_IRQS.contains(&line) {
            self.ecu.can_isr();
        } else {
            evb::fatal("an interrupt line the ECU does not use");
        }
    }

    fn report(&self, fault: &PortFault) {
        report_supervision(NAME, &self.ecu);
        evb::report(fault);
    }

    fn halt(&self) -> ! {
        evb::halt()
    }

    fn shut_down(&self) -> ! {
        // EcuM's reset after the shutdown.
        shutdown_report(NAME, &self.ecu, evb::leds_safe);
        evb::halt()
    }
}
