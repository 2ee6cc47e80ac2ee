//! Fuzz targets. Each is a bolero test: `cargo test -p cw-fuzz` runs it on random inputs
//! and its committed corpus, `cargo bolero test -p cw-fuzz <target>` runs it under
//! libFuzzer (coverage-guided, AddressSanitizer), and the check command runs each for a
//! short smoke time. The properties checked are the core's own contracts
//! (`cw_core::com::signal::spec::codec_contract`, `cw_core::os::spec::call_and_check`).
//!
//! Corpora live under `src/__fuzz__/<target>/corpus` and are committed.

use cw_core::os::spec::Service;
use cw_core::os::{AlarmId, CounterId, ResourceId, TaskId, RES_SCHEDULER};

/// Decodes four fuzzer bytes into a scheduler service. Ids range a little beyond every
/// configuration used here so that `E_OS_ID` paths are exercised.
pub fn decode_service(op: u8, a: u8, b: u8, c: u8) -> Service {
    let task = TaskId(a % 8);
    let res = if b % 4 == 3 {
        RES_SCHEDULER
    } else {
        ResourceId(b % 4)
    };
    let mask = u32::from(b % 4);
    match op % 18 {
        0 => Service::ActivateTask(task),
        1 => Service::TerminateTask,
        2 => Service::ChainTask(task),
        3 => Service::Schedule,
        4 => Service::SetEvent(task, mask),
        5 => Service::ClearEvent(mask),
        6 => Service::WaitEvent(mask),
        7 => Service::GetResource(res),
        8 => Service::ReleaseResource(res),
        9 => Service::SetRelAlarm(AlarmId(a % 6), u32::from(b), u32::from(c % 50)),
        10 => Service::SetAbsAlarm(AlarmId(a % 6), u32::from(b), u32::from(c % 50)),
        11 => Service::CancelAlarm(AlarmId(a % 6)),
        12 => Service::IncrementCounter(CounterId(a % 2)),
        13 => Service::EnterIsr,
        14 => Service::ExitIsr,
        15 => Service::IsrTick(CounterId(a % 2)),
        16 => Service::IsrActivateTask(task),
        _ => Service::IsrSetEvent(task, mask),
    }
}

#[cfg(test)]
mod targets {
    use super::decode_service;
    use cw_core::com::signal::{spec, ByteOrder, SignalLayout, Signedness};
    use cw_core::os::spec::call_and_check;
    use cw_core::os::Os;
    use cw_proofs::configs;

    fn codec_case<const N: usize>(
        start: u16,
        len: u8,
        moto: bool,
        signed: bool,
        value: i128,
        bg: &[u8; 64],
    ) {
        let order = if moto {
            ByteOrder::Motorola
        } else {
            ByteOrder::Intel
        };
        let sign = if signed {
            Signedness::Signed
        } else {
            Signedness::Unsigned
        };
        let mut background = [0u8; N];
        background.copy_from_slice(&bg[..N]);
        let made = SignalLayout::<N>::new(start % (8 * N as u16 + 8), len % 66, order, sign);
        assert_eq!(
            made.is_ok(),
            spec::layout_fits(N, start % (8 * N as u16 + 8), len % 66, order)
        );
        if let Ok(layout) = made {
            let (lo, hi) = spec::value_range(layout.length_bits(), sign);
            // Half the inputs near the range, half anywhere.
            let value = if value & 1 == 0 {
                (value >> 1).rem_euclid(hi - lo + 3) + lo - 1
            } else {
                value >> 1
            };
            if let Err(broken) = spec::codec_contract(&layout, value, &background) {
                panic!("{broken}: {layout:?} value {value}");
            }
        }
    }

    /// Any layout, any value, any background, for a classic, an odd and a CAN FD PDU.
    #[test]
    fn codec_roundtrip() {
        bolero::check!()
            .with_type::<(u8, u16, u8, bool, bool, i128, [u8; 64])>()
            .for_each(
                |(size, start, len, moto, signed, value, bg)| match size % 4 {
                    0 => codec_case::<8>(*start, *len, *moto, *signed, *value, bg),
                    1 => codec_case::<3>(*start, *len, *moto, *signed, *value, bg),
                    2 => codec_case::<12>(*start, *len, *moto, *signed, *value, bg),
                    _ => codec_case::<64>(*start, *len, *moto, *signed, *value, bg),
                },
            );
    }

    fn run_services<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const Q: usize,
    >(
        cfg: &'static cw_core::os::OsConfig<T, R, C, A>,
        calls: &[(u8, u8, u8, u8)],
    ) {
        let Ok(mut os) = Os::<T, R, C, A, Q>::new(cfg) else {
            panic!("configuration refused");
        };
        assert_eq!(os.start(), Ok(()));
        for &(op, a, b, c) in calls.iter().take(256) {
            let service = decode_service(op, a, b, c);
            if let Err(rule) = call_and_check(&mut os, service) {
                panic!("{service:?}: {rule}");
            }
        }
    }

    /// Any sequence of services on the paper's task set and on the event-heavy set: every
    /// transition rule and kernel invariant holds after every call.
    #[test]
    fn scheduler_api() {
        bolero::check!()
            .with_type::<(bool, Vec<(u8, u8, u8, u8)>)>()
            .for_each(|(paper, calls)| {
                if *paper {
                    run_services::<6, 1, 1, 4, 6>(&configs::PAPER, calls);
                } else {
                    run_services::<3, 1, 1, 2, 4>(&configs::EVENTS, calls);
                }
            });
    }
}
