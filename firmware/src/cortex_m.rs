//! What every Cortex-M image of the ECU needs, whatever its board: the const check of the
//! configuration against the port, the ISRs' priorities, and the WdgM and shutdown
//! reports on the log.

use cw_bsp::cortex_m::{now_ms, CortexMPort};
use cw_core::os::{status_name, E_OK};

use crate::board::Board;
use crate::config::{self, Kernel};
use crate::ecu::Ecu;

// The ECU's configuration fits the Cortex-M port (task count, ISR priorities the NVIC
// tells apart): checked when the image is built; a refusal names the task or ISR.
const _: () = cw_bsp::port::preempt::assert_fits(
    config::OS.tasks(),
    config::OS.isrs(),
    cw_bsp::cortex_m::ISR_PRIORITIES,
);

/// The OSEK priority of ISR `isr` in the configuration.
pub fn isr_priority(isr: cw_core::os::IsrId) -> u8 {
    config::OS
        .isrs()
        .get(usize::from(isr.0))
        .map_or(1, |c| c.priority)
}

/// Logs WdgM's failure once, from the idle loop (no job under way): which task's alive
/// supervision failed, when, and that the watchdog is no longer triggered.
pub fn report_supervision<B: Board>(name: &str, ecu: &Ecu<CortexMPort<Kernel>, B>) {
    static REPORTED: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);
    if REPORTED.load(core::sync::atomic::Ordering::Relaxed) {
        return;
    }
    if let Some((_, Some(f))) = ecu.supervision() {
        REPORTED.store(true, core::sync::atomic::Ordering::Relaxed);
        defmt::println!(
            "{=str}: WdgM: the alive supervision of {=str} failed at {} ms ({} of {} alive indications): LEDs dark, the watchdog no longer triggered",
            name,
            f.name,
            u64::from(f.main_function) * u64::from(config::BSW_PERIOD_MS),
            f.counted,
            f.expected
        );
        // What the kernel refused until then: an activation refused by E_OS_LIMIT (a
        // task that had not ended when its alarm came again) explains an extra or a
        // missing alive indication.
        let hooks = ecu.hooks();
        let (service, status) = hooks
            .last_error
            .map_or((u8::MAX, E_OK), |(s, e)| (s as u8, e as u8));
        defmt::println!(
            "{=str}: kernel errors {}, ISR entries refused {}; the last error: service {}, status {}",
            name,
            hooks.errors,
            hooks.port_errors,
            service,
            status
        );
    }
}

/// `App::shut_down`: the LEDs' safe state (`leds_safe`: whatever shut the OS down; EcuM's
/// post-run has set it already on a normal shutdown) and the log line `NAME: ShutdownOS at
/// MS ms: ShutdownHook saw STATUS`. Returns whether the status was `E_OK`.
pub fn shutdown_report<B: Board>(
    name: &str,
    ecu: &Ecu<CortexMPort<Kernel>, B>,
    leds_safe: fn(),
) -> bool {
    leds_safe();
    let status = ecu.hooks().shutdown.unwrap_or(E_OK);
    defmt::println!(
        "{=str}: ShutdownOS at {} ms: ShutdownHook saw {}; no task or interrupt runs from here on",
        name,
        now_ms(),
        status_name(status).unwrap_or("an application's code")
    );
    status == E_OK
}
