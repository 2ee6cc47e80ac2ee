//! Com against a recording lower layer: transmission modes, transfer properties, MDT,
//! update bits, deadline monitoring with replace-by-init, invalidation.
extern crate std;

use super::*;
use crate::com::signal::{ByteOrder, Signedness};
use std::vec::Vec;

const fn layout(start: u16, len: u8) -> SignalLayout<8> {
    match SignalLayout::new(start, len, ByteOrder::Intel, Signedness::Unsigned) {
        Ok(l) => l,
        Err(_) => panic!("test layout does not fit"),
    }
}

const DISTANCE: SignalId = SignalId(0);
const LEVEL: SignalId = SignalId(1);
const RX_DISTANCE: SignalId = SignalId(3);
const RX_FLAG: SignalId = SignalId(4);

// TX 0: mixed, 100 ms period, 2 repetitions every 20 ms, MDT 20 ms (the distance frame).
// TX 1: periodic 50 ms, offset 10 ms. RX 0: deadline 50 ms, one signal with an update bit.
static CFG: ComConfig<8, 2, 1, 5> = match ComConfig::new(
    10,
    [
        TxIpduConfig {
            name: "Distance",
            len: 8,
            mode: TxMode::Mixed {
                period_ms: 100,
                offset_ms: 0,
                repetitions: 2,
                repetition_period_ms: 20,
            },
            mdt_ms: 20,
        },
        TxIpduConfig {
            name: "Status",
            len: 2,
            mode: TxMode::Periodic {
                period_ms: 50,
                offset_ms: 10,
            },
            mdt_ms: 0,
        },
    ],
    [RxIpduConfig {
        name: "Echo",
        len: 8,
        deadline_ms: 50,
    }],
    [
        SignalConfig {
            name: "Distance",
            direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::TriggeredOnChange),
            layout: layout(0, 32),
            init: 0,
            invalid: Some(0xFFFF_FFFF),
            update_bit: None,
        },
        SignalConfig {
            name: "Level",
            direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::Pending),
            layout: layout(32, 8),
            init: 3,
            invalid: None,
            update_bit: Some(63),
        },
        SignalConfig {
            name: "Status",
            direction: SignalDirection::Tx(TxIpduId(1), TransferProperty::Triggered),
            layout: layout(0, 16),
            init: 0xBEEF,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "RxDistance",
            direction: SignalDirection::Rx(RxIpduId(0)),
            layout: layout(0, 32),
            init: 7,
            invalid: Some(0xFFFF_FFFF),
            update_bit: None,
        },
        SignalConfig {
            name: "RxFlag",
            direction: SignalDirection::Rx(RxIpduId(0)),
            layout: layout(32, 8),
            init: 1,
            invalid: None,
            update_bit: Some(40),
        },
    ],
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

type TestCom = Com<8, 2, 1, 5>;

/// Runs `cycles` main-function periods, recording (cycle, I-PDU, bytes) of each transmission.
fn run(com: &mut TestCom, cycles: u32, log: &mut Vec<(u32, u16, Vec<u8>)>) {
    for _ in 0..cycles {
        let now = com.tx_now + 1;
        com.main_function_tx(|id, data| {
            log.push((now, id.0, data.to_vec()));
            true
        });
    }
}

fn send(
    com: &mut TestCom,
    sig: SignalId,
    v: u64,
    log: &mut Vec<(u32, u16, Vec<u8>)>,
) -> Result<(), ComError> {
    let now = com.tx_now;
    com.send_signal(sig, SignalValue::Unsigned(v), |id, data| {
        log.push((now, id.0, data.to_vec()));
        true
    })
}

#[test]
fn init_values_and_periodic_timing() {
    let mut com = Com::new(&CFG);
    assert_eq!(com.tx_ipdu(TxIpduId(1)), Some(&[0xEF, 0xBE][..]));
    assert_eq!(
        com.receive_signal(RX_DISTANCE),
        Ok(SignalValue::Unsigned(7))
    );
    let mut log = Vec::new();
    run(&mut com, 25, &mut log);
    let status: Vec<u32> = log
        .iter()
        .filter(|(_, id, _)| *id == 1)
        .map(|(t, _, _)| *t)
        .collect();
    // Main-function calls are numbered from 1, every 10 ms.
    assert_eq!(
        status,
        [2, 7, 12, 17, 22],
        "50 ms period after a 10 ms offset"
    );
    let distance: Vec<u32> = log
        .iter()
        .filter(|(_, id, _)| *id == 0)
        .map(|(t, _, _)| *t)
        .collect();
    assert_eq!(
        distance,
        [1, 11, 21],
        "100 ms period; offset 0 sends in the first call"
    );
}

#[test]
fn triggered_on_change_sends_at_once_then_repeats_within_the_mdt() {
    let mut com = Com::new(&CFG);
    let mut log = Vec::new();
    run(&mut com, 3, &mut log);
    log.clear();
    assert_eq!(send(&mut com, DISTANCE, 1500, &mut log), Ok(()));
    assert_eq!(
        log,
        [(3, 0, std::vec![0xDC, 0x05, 0, 0, 3, 0, 0, 0])],
        "sent within the call"
    );
    // Same value again: on-change does not trigger.
    assert_eq!(send(&mut com, DISTANCE, 1500, &mut log), Ok(()));
    assert_eq!(log.len(), 1);
    // Two repetitions, 20 ms (2 cycles) apart.
    run(&mut com, 6, &mut log);
    let times: Vec<u32> = log
        .iter()
        .filter(|(_, id, _)| *id == 0)
        .map(|(t, _, _)| *t)
        .collect();
    assert_eq!(times, [3, 5, 7]);
    // A change 1 cycle after a transmission waits for the 20 ms MDT.
    log.clear();
    run(&mut com, 0, &mut log);
    let now = com.tx_now; // 9
    assert_eq!(send(&mut com, DISTANCE, 900, &mut log), Ok(()));
    assert_eq!(
        log.first().map(|l| l.0),
        Some(now),
        "9 >= 7 + 2: allowed at once"
    );
    assert_eq!(send(&mut com, DISTANCE, 800, &mut log), Ok(()));
    assert_eq!(log.len(), 1, "held back by the MDT");
    run(&mut com, 2, &mut log);
    assert_eq!(log[1].0, now + 2);
    assert_eq!(&log[1].2[..4], &800u32.to_le_bytes());
}

#[test]
fn pending_signals_wait_for_the_next_transmission_and_update_bits_clear_after_it() {
    let mut com = Com::new(&CFG);
    let mut log = Vec::new();
    assert_eq!(send(&mut com, LEVEL, 2, &mut log), Ok(()));
    assert!(log.is_empty(), "pending never triggers");
    assert_eq!(
        com.tx_ipdu(TxIpduId(0)).map(|b| b[7] & 0x80),
        Some(0x80),
        "update bit set"
    );
    run(&mut com, 1, &mut log);
    let sent = log
        .iter()
        .find(|(_, id, _)| *id == 0)
        .map(|(_, _, d)| d.clone());
    assert_eq!(
        sent.as_ref().map(|d| (d[4], d[7] & 0x80)),
        Some((2, 0x80)),
        "periodic send carries it"
    );
    assert_eq!(
        com.tx_ipdu(TxIpduId(0)).map(|b| b[7] & 0x80),
        Some(0),
        "cleared after sending"
    );
}

#[test]
fn errors_change_nothing() {
    let mut com = Com::new(&CFG);
    let before = com;
    let mut log = Vec::new();
    assert_eq!(
        send(&mut com, SignalId(9), 1, &mut log),
        Err(ComError::UnknownSignal)
    );
    assert_eq!(
        send(&mut com, RX_DISTANCE, 1, &mut log),
        Err(ComError::UnknownSignal)
    );
    assert_eq!(
        send(&mut com, LEVEL, 256, &mut log),
        Err(ComError::OutOfRange)
    );
    assert_eq!(com, before);
    assert!(log.is_empty());
    assert_eq!(
        com.invalidate_signal(LEVEL, |_, _| true),
        Err(ComError::NoInvalidValue)
    );
}

#[test]
fn invalidation_value_travels_and_is_reported() {
    let mut com = Com::new(&CFG);
    let mut sent = Vec::new();
    assert_eq!(
        com.invalidate_signal(DISTANCE, |_, d| {
            sent.extend_from_slice(d);
            true
        }),
        Ok(())
    );
    assert_eq!(&sent[..4], &[0xFF; 4]);
    com.rx_indication(RxIpduId(0), &sent);
    assert_eq!(com.receive_signal(RX_DISTANCE), Err(ComError::Invalid));
}

#[test]
fn update_bits_and_deadline_monitoring_on_reception() {
    let mut com = Com::new(&CFG);
    let mut timeouts = Vec::new();
    // Update bit (bit 40) clear: the flag keeps its value; the distance is taken.
    com.rx_indication(RxIpduId(0), &[0xE8, 0x03, 0, 0, 9, 0, 0, 0]);
    assert_eq!(
        com.receive_signal(RX_DISTANCE),
        Ok(SignalValue::Unsigned(1000))
    );
    assert_eq!(com.receive_signal(RX_FLAG), Ok(SignalValue::Unsigned(1)));
    com.rx_indication(RxIpduId(0), &[0xE8, 0x03, 0, 0, 9, 1, 0, 0]);
    assert_eq!(com.receive_signal(RX_FLAG), Ok(SignalValue::Unsigned(9)));
    // Receptions every 40 ms keep the 50 ms deadline from expiring.
    for cycle in 1..=20u32 {
        if cycle % 4 == 0 {
            com.rx_indication(RxIpduId(0), &[0xE8, 0x03, 0, 0, 9, 1, 0, 0]);
        }
        com.main_function_rx(|id| timeouts.push((cycle, id)));
    }
    assert!(timeouts.is_empty(), "{timeouts:?}");
    // Silence: after 50 ms the signals fall back to their init values, once per deadline.
    for cycle in 21..=32u32 {
        com.main_function_rx(|id| timeouts.push((cycle, id)));
    }
    // Last reception just before call 20; the 5th call without one (24) times out, and the
    // monitoring restarts (29).
    assert_eq!(timeouts, [(24, RxIpduId(0)), (29, RxIpduId(0))]);
    assert!(com.rx_timed_out(RxIpduId(0)));
    assert_eq!(
        com.receive_signal(RX_DISTANCE),
        Ok(SignalValue::Unsigned(7))
    );
    assert_eq!(com.receive_signal(RX_FLAG), Ok(SignalValue::Unsigned(1)));
    com.rx_indication(RxIpduId(0), &[1, 0, 0, 0, 0, 0, 0, 0]);
    assert!(!com.rx_timed_out(RxIpduId(0)));
}

#[test]
fn configuration_rules() {
    let tx = |mode, mdt_ms| TxIpduConfig {
        name: "t",
        len: 8,
        mode,
        mdt_ms,
    };
    let sig = |start, update_bit| SignalConfig {
        name: "s",
        direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::Triggered),
        layout: layout(start, 8),
        init: 0,
        invalid: None,
        update_bit,
    };
    let periodic = TxMode::Periodic {
        period_ms: 100,
        offset_ms: 0,
    };
    assert!(ComConfig::<8, 1, 0, 1>::new(10, [tx(periodic, 0)], [], [sig(0, Some(8))]).is_ok());
    assert_eq!(
        ComConfig::<8, 1, 0, 0>::new(
            10,
            [tx(
                TxMode::Periodic {
                    period_ms: 15,
                    offset_ms: 0
                },
                0
            )],
            [],
            []
        )
        .err(),
        Some(ComConfigError::Timing { ipdu: 0 })
    );
    assert_eq!(
        ComConfig::<8, 1, 0, 1>::new(10, [tx(periodic, 0)], [], [sig(0, Some(3))]).err(),
        Some(ComConfigError::Signal { signal: 0 }),
        "update bit inside the signal"
    );
    assert_eq!(
        ComConfig::<8, 1, 0, 0>::new(0, [tx(periodic, 0)], [], []).err(),
        Some(ComConfigError::Limits)
    );
}

/// Any sequence of writes and main-function cycles: every transmission respects the MDT,
/// and the number of Mixed-mode transmissions is bounded by what the writes and the period
/// allow.
#[test]
fn any_write_sequence_respects_the_mdt() {
    bolero::check!()
        .with_type::<std::vec::Vec<(bool, u8)>>()
        .for_each(|ops| {
            let mut com = Com::new(&CFG);
            let mut log = Vec::new();
            for &(write, value) in ops.iter().take(200) {
                if write {
                    let _ = send(&mut com, DISTANCE, u64::from(value), &mut log);
                } else {
                    run(&mut com, 1, &mut log);
                }
            }
            let times: Vec<u32> = log
                .iter()
                .filter(|(_, id, _)| *id == 0)
                .map(|(t, _, _)| *t)
                .collect();
            for pair in times.windows(2) {
                assert!(pair[1] >= pair[0] + 2, "MDT of 2 cycles broken: {times:?}");
            }
        });
}
