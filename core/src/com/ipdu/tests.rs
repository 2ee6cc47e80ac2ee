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
const STATUS: SignalId = SignalId(2);
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
    assert_eq!(CFG.main_period_ms(), 10);
    assert_eq!(Com::new(&CFG).signedness(LEVEL), Some(Signedness::Unsigned));
    assert_eq!(Com::new(&CFG).signedness(SignalId(5)), None);
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

// ---------------------------------------------------------------------------------------
// Timing against the timer wheel: events far beyond the wheel's 64 slots.

/// A reference main function that looks at every TX I-PDU in every cycle instead of only
/// at the wheel's slot: the wheel must give the same transmissions in the same cycles.
/// (It files into the wheel as a side effect, but never takes from it.)
fn scan_all_tx<const TX: usize, const RX: usize, const S: usize>(
    com: &mut Com<8, TX, RX, S>,
    mut transmit: impl FnMut(TxIpduId, &[u8]) -> bool,
) {
    com.tx_now += 1;
    let now = com.tx_now;
    for i in 0..TX {
        com.tx_due(i, now, &mut transmit);
    }
}

/// The reference for `main_function_rx`: every monitored RX I-PDU checked every cycle.
fn scan_all_rx<const TX: usize, const RX: usize, const S: usize>(
    com: &mut Com<8, TX, RX, S>,
    mut on_timeout: impl FnMut(RxIpduId),
) {
    com.rx_now += 1;
    let now = com.rx_now;
    for i in 0..RX {
        let deadline = com.cfg().rx_deadline[i];
        if deadline > 0 && com.rx_due[i] <= now {
            com.replace_by_init(i);
            com.rx_timed_out[i] = true;
            on_timeout(RxIpduId(i as u16));
            com.rx_due[i] = now + deadline;
        }
    }
}

/// What one main-function cycle did: (cycle, I-PDU, bytes) of each transmission and the
/// timed-out RX I-PDUs, in I-PDU order (the order within a cycle is not specified).
type Cycle = (u32, Vec<(u16, Vec<u8>)>, Vec<u16>);

/// One cycle of both main functions, through the wheel or through the reference.
fn cycle<const TX: usize, const RX: usize, const S: usize>(
    com: &mut Com<8, TX, RX, S>,
    reference: bool,
) -> Cycle {
    let mut sent = Vec::new();
    let mut timeouts = Vec::new();
    let transmit = |id: TxIpduId, data: &[u8]| {
        sent.push((id.0, data.to_vec()));
        true
    };
    let on_timeout = |id: RxIpduId| timeouts.push(id.0);
    if reference {
        scan_all_tx(com, transmit);
        scan_all_rx(com, on_timeout);
    } else {
        com.main_function_tx(transmit);
        com.main_function_rx(on_timeout);
    }
    sent.sort();
    timeouts.sort();
    (com.tx_now, sent, timeouts)
}

// Main period 10 ms. Near and far I-PDUs, exact multiples of the wheel size and of its
// square, repetitions and MDTs longer than the wheel.
// TX 0: mixed, 100 ms, 2 repetitions every 20 ms, MDT 20 ms.   (near)
// TX 1: periodic 50 s, offset 10 ms.                              (5000 cycles)
// TX 2: mixed 700 s, offset 650 ms, 3 repetitions every 1 s, MDT 300 ms.
// TX 3: direct, 1 repetition after 2 s.
// TX 4: periodic 640 ms (64 cycles), offset 630 ms.
// TX 5: periodic 1000 s, offset 40.95 s (first sent in cycle 4096 = 64 * 64).
// RX 0: deadline 50 ms; RX 1: 45 s; RX 2: not monitored; RX 3: 640 ms.
static FAR: ComConfig<8, 6, 4, 7> = match ComConfig::new(
    10,
    [
        TxIpduConfig {
            name: "Near",
            len: 2,
            mode: TxMode::Mixed {
                period_ms: 100,
                offset_ms: 0,
                repetitions: 2,
                repetition_period_ms: 20,
            },
            mdt_ms: 20,
        },
        TxIpduConfig {
            name: "Slow",
            len: 1,
            mode: TxMode::Periodic {
                period_ms: 50_000,
                offset_ms: 10,
            },
            mdt_ms: 0,
        },
        TxIpduConfig {
            name: "SlowMixed",
            len: 2,
            mode: TxMode::Mixed {
                period_ms: 700_000,
                offset_ms: 650,
                repetitions: 3,
                repetition_period_ms: 1_000,
            },
            mdt_ms: 300,
        },
        TxIpduConfig {
            name: "Direct",
            len: 2,
            mode: TxMode::Direct {
                repetitions: 1,
                repetition_period_ms: 2_000,
            },
            mdt_ms: 0,
        },
        TxIpduConfig {
            name: "Wheel",
            len: 1,
            mode: TxMode::Periodic {
                period_ms: 640,
                offset_ms: 630,
            },
            mdt_ms: 0,
        },
        TxIpduConfig {
            name: "VerySlow",
            len: 1,
            mode: TxMode::Periodic {
                period_ms: 1_000_000,
                offset_ms: 40_950,
            },
            mdt_ms: 0,
        },
    ],
    [
        RxIpduConfig {
            name: "Fast",
            len: 2,
            deadline_ms: 50,
        },
        RxIpduConfig {
            name: "Slow",
            len: 2,
            deadline_ms: 45_000,
        },
        RxIpduConfig {
            name: "Unmonitored",
            len: 2,
            deadline_ms: 0,
        },
        RxIpduConfig {
            name: "Wheel",
            len: 1,
            deadline_ms: 640,
        },
    ],
    [
        SignalConfig {
            name: "NearValue",
            direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::Triggered),
            layout: layout(0, 16),
            init: 0,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "SlowMixedValue",
            direction: SignalDirection::Tx(TxIpduId(2), TransferProperty::TriggeredOnChange),
            layout: layout(0, 16),
            init: 0,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "DirectValue",
            direction: SignalDirection::Tx(TxIpduId(3), TransferProperty::Triggered),
            layout: layout(0, 16),
            init: 0,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "VerySlowValue",
            direction: SignalDirection::Tx(TxIpduId(5), TransferProperty::Pending),
            layout: layout(0, 8),
            init: 0,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "RxFast",
            direction: SignalDirection::Rx(RxIpduId(0)),
            layout: layout(0, 16),
            init: 5,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "RxSlow",
            direction: SignalDirection::Rx(RxIpduId(1)),
            layout: layout(0, 16),
            init: 6,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "RxWheel",
            direction: SignalDirection::Rx(RxIpduId(3)),
            layout: layout(0, 8),
            init: 7,
            invalid: None,
            update_bit: None,
        },
    ],
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

type FarCom = Com<8, 6, 4, 7>;

/// One step of a scenario on the FAR configuration.
#[derive(Debug, Clone, Copy)]
enum Step {
    /// Write `value` to TX signal `signal % 4`.
    Send(u8, u16),
    /// Receive RX I-PDU `ipdu % 4`.
    Receive(u8, u16),
    /// Run this many cycles.
    Run(u32),
}

/// Runs `steps` on the wheel and on the reference; both must do the same in every cycle.
fn same_as_reference(steps: impl IntoIterator<Item = Step>) {
    let mut wheel = FarCom::new(&FAR);
    let mut reference = FarCom::new(&FAR);
    for step in steps {
        match step {
            Step::Send(signal, value) => {
                let signal = SignalId(u16::from(signal % 4));
                let value = SignalValue::Unsigned(u64::from(value & 0xFF));
                let mut a = Vec::new();
                let mut b = Vec::new();
                let ra = wheel.send_signal(signal, value, |id, d| {
                    a.push((id.0, d.to_vec()));
                    true
                });
                let rb = reference.send_signal(signal, value, |id, d| {
                    b.push((id.0, d.to_vec()));
                    true
                });
                assert_eq!((ra, a), (rb, b), "cycle {}: {step:?}", wheel.tx_now);
            }
            Step::Receive(ipdu, value) => {
                let data = value.to_le_bytes();
                wheel.rx_indication(RxIpduId(u16::from(ipdu % 4)), &data);
                reference.rx_indication(RxIpduId(u16::from(ipdu % 4)), &data);
            }
            Step::Run(cycles) => {
                for _ in 0..cycles {
                    assert_eq!(cycle(&mut wheel, false), cycle(&mut reference, true));
                }
            }
        }
        assert_eq!(wheel.tx_buf, reference.tx_buf);
        assert_eq!(wheel.rx_buf, reference.rx_buf);
        assert_eq!(wheel.rx_timed_out, reference.rx_timed_out);
    }
}

/// Without writes or receptions every event follows from the configuration alone: each
/// I-PDU, near or far, sends and times out exactly in its cycles.
#[test]
#[cfg_attr(
    miri,
    ignore = "walks up to a million cycles: too slow to interpret; safe arithmetic only, run natively"
)]
fn far_events_fire_exactly_on_their_cycles() {
    let mut com = FarCom::new(&FAR);
    let end = 250_000u32;
    let mut sent: [Vec<u32>; 6] = Default::default();
    let mut timeouts: [Vec<u32>; 4] = Default::default();
    for _ in 0..end {
        let (now, tx, rx) = cycle(&mut com, false);
        for (id, _) in tx {
            sent[usize::from(id)].push(now);
        }
        for id in rx {
            timeouts[usize::from(id)].push(now);
        }
    }
    // First transmission in call `offset + 1`, then every period (in cycles).
    let expect =
        |first: u32, period: u32| -> Vec<u32> { (first..=end).step_by(period as usize).collect() };
    assert_eq!(sent[0], expect(1, 10));
    assert_eq!(sent[1], expect(2, 5_000));
    assert_eq!(sent[2], expect(66, 70_000));
    assert!(sent[3].is_empty(), "direct: never without a write");
    assert_eq!(sent[4], expect(64, 64));
    assert_eq!(sent[5], [4_096, 104_096, 204_096]);
    // Timeouts every deadline, counted from the start.
    assert_eq!(timeouts[0], expect(5, 5));
    assert_eq!(timeouts[1], expect(4_500, 4_500));
    assert!(timeouts[2].is_empty());
    assert_eq!(timeouts[3], expect(64, 64));
}

/// A long scenario with writes (repetitions and MDTs far beyond the wheel) and receptions
/// (deadline restarts), against the reference.
#[test]
#[cfg_attr(
    miri,
    ignore = "walks up to a million cycles: too slow to interpret; safe arithmetic only, run natively"
)]
fn far_events_match_a_main_function_that_checks_every_ipdu() {
    let mut steps = Vec::new();
    let mut seed = 0x2545_F491u32;
    let mut rand = move |n: u32| {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed % n
    };
    let mut cycles = 0;
    while cycles < 400_000 {
        match rand(5) {
            0 | 1 => steps.push(Step::Send(rand(4) as u8, rand(256) as u16)),
            2 => steps.push(Step::Receive(rand(4) as u8, rand(65_536) as u16)),
            3 => {
                let n = rand(100);
                cycles += n;
                steps.push(Step::Run(n));
            }
            _ => {
                let n = rand(10_000);
                cycles += n;
                steps.push(Step::Run(n));
            }
        }
    }
    same_as_reference(steps);
}

/// Any sequence of writes, receptions and runs gives the reference's cycles.
#[test]
fn any_scenario_matches_the_reference() {
    bolero::check!()
        .with_type::<Vec<(u8, u8, u16)>>()
        .for_each(|ops| {
            // Miri interprets every cycle: a shorter walk there, the full one natively.
            let (mut budget, max_ops) = if cfg!(miri) {
                (120u32, 20)
            } else {
                (20_000, 100)
            };
            let steps = ops
                .iter()
                .take(max_ops)
                .map(|&(kind, x, y)| match kind % 4 {
                    0 => Step::Send(x, y),
                    1 => Step::Receive(x, y),
                    // Short and long runs, all within the cycle budget.
                    k => {
                        let wanted = if k == 2 {
                            u32::from(y % 100)
                        } else {
                            u32::from(y) * 4
                        };
                        let n = wanted.min(budget);
                        budget -= n;
                        Step::Run(n)
                    }
                });
            same_as_reference(steps);
        });
}

/// Many I-PDUs (main period 1 ms, so cycles are ms) whose periods, offsets and deadlines
/// lie on and around every power of the wheel size up to 64^3: each one sends and times
/// out exactly in its cycles.
#[test]
#[cfg_attr(
    miri,
    ignore = "walks up to a million cycles: too slow to interpret; safe arithmetic only, run natively"
)]
fn many_ipdus_with_mixed_far_and_near_times_fire_exactly_on_their_cycles() {
    const TIMES: [u32; 24] = [
        1, 2, 3, 7, 63, 64, 65, 100, 127, 128, 129, 1_000, 4_095, 4_096, 4_097, 5_000, 8_191,
        65_537, 100_000, 262_143, 262_144, 262_145, 300_000, 999_999,
    ];
    const K: usize = TIMES.len();
    static MANY: ComConfig<8, K, K, 0> = {
        let mut tx = [TxIpduConfig {
            name: "t",
            len: 1,
            mode: TxMode::None,
            mdt_ms: 0,
        }; K];
        let mut rx = [RxIpduConfig {
            name: "r",
            len: 1,
            deadline_ms: 0,
        }; K];
        let mut i = 0;
        while i < K {
            tx[i].mode = TxMode::Periodic {
                period_ms: TIMES[i],
                // Offsets from the other end of the table: near periods start far away.
                offset_ms: TIMES[K - 1 - i] - 1,
            };
            rx[i].deadline_ms = TIMES[(i + 5) % K];
            i += 1;
        }
        match ComConfig::new(1, tx, rx, []) {
            Ok(cfg) => cfg,
            Err(e) => panic!("{}", e.describe()),
        }
    };
    let mut com = Com::new(&MANY);
    let end = 1_100_000u32;
    let mut sent: [u32; K] = [0; K];
    let mut timeouts: [u32; K] = [0; K];
    for now in 1..=end {
        com.main_function_tx(|id, _| {
            let i = usize::from(id.0);
            let (first, period) = (TIMES[K - 1 - i], TIMES[i]);
            assert!(
                now >= first && (now - first) % period == 0,
                "TX {i} sent in cycle {now}"
            );
            sent[i] += 1;
            true
        });
        com.main_function_rx(|id| {
            let i = usize::from(id.0);
            assert_eq!(
                now % TIMES[(i + 5) % K],
                0,
                "RX {i} timed out in cycle {now}"
            );
            timeouts[i] += 1;
        });
    }
    for i in 0..K {
        let (first, period) = (TIMES[K - 1 - i], TIMES[i]);
        let expected = if end >= first {
            (end - first) / period + 1
        } else {
            0
        };
        assert_eq!(sent[i], expected, "transmissions of TX {i}");
        assert_eq!(timeouts[i], end / TIMES[(i + 5) % K], "timeouts of RX {i}");
    }
}

// ---------------------------------------------------------------------------------------
// The hierarchical wheel on its own.

#[test]
fn lists_by_distance_from_the_next_cycle() {
    let next = 1_000u32;
    let level = |due: u32| list_for(due, next) / WHEEL;
    assert_eq!(list_for(next, next), next as usize % WHEEL, "due next");
    assert_eq!(list_for(next + 63, next), (next + 63) as usize % WHEEL);
    assert_eq!(list_for(7, next), 7, "a cycle already past: level 0");
    for (distance, expected) in [
        (64, 1),
        (4_095, 1),
        (4_096, 2),
        (262_143, 2),
        (262_144, 3),
        ((1 << 24) - 1, 3),
        (1 << 24, 4),
        (1 << 30, 5),
        (u32::MAX - next, 5),
    ] {
        assert_eq!(level(next + distance), expected, "distance {distance}");
    }
    // The slot is the due cycle's block on that level.
    assert_eq!(
        list_for(next + 5_000, next),
        2 * WHEEL + (6_000 >> 12) % WHEEL
    );
    assert_eq!(list_for(u32::MAX, 0), 5 * WHEEL + (u32::MAX >> 30) as usize);
    assert!(list_for(u32::MAX, 0) < LEVELS * WHEEL);
}

/// An xorshift generator for the wheel tests.
struct Rng(u32);

impl Rng {
    fn below(&mut self, n: u32) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0 % n
    }

    /// A distance of 1 to `2^max_bits - 1` cycles, with as many short as long ones.
    fn distance(&mut self, max_bits: u32) -> u32 {
        let bits = 1 + self.below(max_bits);
        1 + self.below((1u32 << bits) - 1)
    }
}

/// A wheel with what the tests expect of it.
struct Driven<const K: usize> {
    wheel: Wheel<K>,
    /// Expected due cycle of each entry.
    due: [Option<u32>; K],
    /// The entries per expected due cycle.
    by_due: std::collections::BTreeMap<u32, Vec<usize>>,
    /// Moves an entry may still make: the level it was filed on.
    moves_left: [usize; K],
}

impl<const K: usize> Driven<K> {
    fn file(&mut self, k: usize, due: u32, now: u32) {
        self.wheel.file(k, due, now);
        self.due[k] = Some(due);
        self.by_due.entry(due).or_default().push(k);
        self.moves_left[k] = usize::from(self.wheel.list[k]) / WHEEL;
    }
}

/// Runs a wheel of `K` entries from cycle `start` (taken) through cycle `end` as the main
/// functions do, filing each entry `first[k]` cycles ahead at the start and, when it is
/// taken, `again(k)` cycles ahead (0: not again). Checks that every entry is taken
/// exactly in its cycle; that a cycle `busy` calls idle has nothing to take or move; and
/// that entries move only on block starts, at most once per level they were filed above
/// level 0. Returns how many entries were taken.
fn drive<const K: usize>(
    start: u32,
    end: u32,
    first: [u32; K],
    mut again: impl FnMut(usize) -> u32,
) -> usize {
    let mut d = Driven {
        wheel: Wheel::<K>::new(),
        due: [None; K],
        by_due: Default::default(),
        moves_left: [0; K],
    };
    for (k, &distance) in first.iter().enumerate() {
        d.file(k, start + distance, start);
    }
    let mut taken = 0;
    let mut now = start;
    while now < end {
        now += 1;
        let expected = d.by_due.remove(&now).unwrap_or_default();
        if !d.wheel.busy(now) {
            assert!(expected.is_empty(), "cycle {now}: {expected:?} due, idle");
            if now % WHEEL as u32 == 0 {
                // An idle block start really has nothing to move.
                let mut copy = d.wheel;
                assert_eq!(copy.take(now), NIL);
                assert_eq!(copy, d.wheel, "cycle {now}: idle, but entries to move");
            }
            continue;
        }
        let before = d.wheel.list;
        let mut list = d.wheel.take(now);
        for (k, &was) in before.iter().enumerate() {
            if d.wheel.list[k] != was {
                assert_eq!(now % WHEEL as u32, 0, "entry {k} moved in cycle {now}");
                assert!(d.moves_left[k] > 0, "entry {k} moved too often");
                d.moves_left[k] -= 1;
            }
        }
        let mut got = Vec::new();
        while let Some(k) = d.wheel.pop(&mut list) {
            assert_eq!(d.due[k], Some(now), "entry {k} taken in cycle {now}");
            got.push(k);
        }
        got.sort();
        let mut want = expected;
        want.sort();
        assert_eq!(got, want, "cycle {now}");
        taken += got.len();
        for k in got {
            d.due[k] = None;
            let distance = again(k);
            if distance > 0 {
                d.file(k, now + distance, now);
            }
        }
    }
    // What is not due yet is still filed.
    for (k, due) in d.due.iter().enumerate() {
        assert_eq!(due.is_some(), d.wheel.list[k] != UNFILED, "entry {k}");
    }
    taken
}

/// Entries at every level boundary and at random distances up to 2^20 cycles, re-filed
/// when taken, from a start just before a level-3 block (2^18) and one just before a
/// level-4 block (2^24): each is taken exactly in its cycle, and idle cycles do nothing.
#[test]
#[cfg_attr(
    miri,
    ignore = "walks up to a million cycles: too slow to interpret; safe arithmetic only, run natively"
)]
fn wheel_takes_every_entry_exactly_in_its_cycle() {
    const BOUNDARIES: [u32; 16] = [
        1, 2, 63, 64, 65, 127, 128, 129, 4_095, 4_096, 4_097, 4_159, 262_143, 262_144, 262_145,
        1_000_000,
    ];
    for start in [0, (1 << 18) - 70, (1 << 24) - 5_000] {
        let mut rng = Rng(0x9E37_79B9 ^ start);
        let mut first = [0u32; 64];
        for (k, d) in first.iter_mut().enumerate() {
            *d = match BOUNDARIES.get(k) {
                Some(&b) => b,
                None => rng.distance(20),
            };
        }
        let taken = drive(start, start + 1_100_000, first, |k| {
            // Boundary entries keep their distance; the others draw a new one (or stop).
            match BOUNDARIES.get(k) {
                Some(&b) => b,
                None if rng.below(8) == 0 => 0,
                None => rng.distance(20),
            }
        });
        assert!(taken > 100_000, "{taken}");
    }
}

/// Entries on level 4 (2^24 cycles and more ahead, 46 h at 10 ms) come down through every
/// level and are taken exactly in their cycle.
#[test]
#[cfg_attr(
    miri,
    ignore = "walks up to a million cycles: too slow to interpret; safe arithmetic only, run natively"
)]
fn wheel_takes_an_entry_far_beyond_the_wheel_exactly_in_its_cycle() {
    let far = [
        1 << 24,
        (1 << 24) + 1,
        (1 << 24) + 4_097,
        (1 << 24) + 262_211,
        70,
    ];
    let start = 123_456;
    let taken = drive(start, start + (1 << 24) + 262_300, far, |k| {
        if k == 4 {
            70
        } else {
            0
        }
    });
    assert_eq!(taken, 4 + ((1 << 24) + 262_300) / 70);
}

/// Filing for an earlier cycle moves an entry; for a later one it stays.
#[test]
fn wheel_filing_earlier_moves_and_later_stays() {
    let mut wheel = Wheel::<2>::new();
    wheel.file(0, 5_000, 0);
    wheel.file(0, 6_000, 0);
    assert_eq!(wheel.due[0], 5_000, "a later cycle: stays");
    wheel.file(0, 30, 0);
    assert_eq!((wheel.due[0], usize::from(wheel.list[0])), (30, 30));
    assert_eq!(wheel.head[2 * WHEEL + 1], NIL, "no longer on level 2");
    wheel.file(1, 30, 0);
    wheel.file(0, 10, 0);
    assert_eq!(wheel.head[30], 1, "unlinked behind the head");
    assert_eq!(wheel.next[1], NIL);
    // Third in its list (2 -> 1 -> 0): the walk passes an entry that is not it.
    let mut wheel = Wheel::<3>::new();
    for k in 0..3 {
        wheel.file(k, 30, 0);
    }
    wheel.file(0, 10, 0);
    assert_eq!((wheel.head[30], wheel.next[2], wheel.next[1]), (2, 1, NIL));
    assert_eq!((wheel.head[10], usize::from(wheel.list[0])), (0, 10));
}

/// The entries due in one cycle are taken last-filed first, also when some of them came
/// down from coarser levels (as the one-level wheel did for entries up to 64 cycles
/// ahead). Also with room for 255 entries, the most an I-PDU table holds, where the
/// list end `NIL` is one past the last entry.
#[test]
fn wheel_takes_the_entries_of_one_cycle_last_filed_first() {
    last_filed_first::<6>();
    last_filed_first::<255>();
}

fn last_filed_first<const K: usize>() {
    // Natively the entries are due in the fourth 4,096-cycle block; Miri, which interprets
    // every cycle, walks to the second (the level-2 entries still move down at a block
    // start, through level 1 to level 0).
    let blocks = if cfg!(miri) { 1 } else { 3 };
    let due = blocks * 4_096 + 5 * 64 + 7;
    let mut wheel = Wheel::<K>::new();
    // (entry, filed in cycle, level): from further to nearer.
    let filings = [
        (0, 1, 2),
        (1, 2, 2),
        (2, due - 4_000, 1),
        (3, due - 3_000, 1),
        (4, due - 64, 0),
        (5, due - 1, 0),
    ];
    let mut now = 0;
    let mut order = Vec::new();
    while now < due {
        now += 1;
        if wheel.busy(now) {
            let mut list = wheel.take(now);
            while let Some(k) = wheel.pop(&mut list) {
                order.push((now, k));
            }
        }
        // As Com files: after the cycle's slot is taken.
        for &(k, at, level) in &filings {
            if at == now {
                wheel.file(k, due, now);
                assert_eq!(usize::from(wheel.list[k]) / WHEEL, level, "entry {k}");
            }
        }
    }
    let expected: Vec<(u32, usize)> = [5, 4, 3, 2, 1, 0].iter().map(|&k| (due, k)).collect();
    assert_eq!(order, expected);
}

/// A one-signal I-PDU of `len` bytes (the signal: the low `bits` bits of byte 0) whose
/// update bit is `bit`.
const fn update_bit_config<const N: usize>(len: u8, bits: u8, bit: u16) -> ComConfig<N, 1, 0, 1> {
    let layout = match SignalLayout::new(0, bits, ByteOrder::Intel, Signedness::Unsigned) {
        Ok(l) => l,
        Err(_) => panic!("test layout does not fit"),
    };
    match ComConfig::new(
        10,
        [TxIpduConfig {
            name: "t",
            len,
            mode: TxMode::Periodic {
                period_ms: 10,
                offset_ms: 0,
            },
            mdt_ms: 0,
        }],
        [],
        [SignalConfig {
            name: "s",
            direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::Pending),
            layout,
            init: 0,
            invalid: None,
            update_bit: Some(bit),
        }],
    ) {
        Ok(cfg) => cfg,
        Err(_) => panic!("update bit configuration refused"),
    }
}

/// [`update_bit_config`] for every update bit outside the signal: 8..64.
static UPDATE_BIT_CONFIGS: [ComConfig<8, 1, 0, 1>; 56] = {
    let mut configs = [update_bit_config(8, 8, 8); 56];
    let mut i = 1;
    while i < configs.len() {
        configs[i] = update_bit_config(8, 8, 8 + i as u16);
        i += 1;
    }
    configs
};

/// An update bit anywhere in the I-PDU outside its signal: sending the signal sets exactly
/// that bit (byte `bit / 8`, bit `bit % 8`), the transmission carries it, and it is
/// cleared afterwards with nothing else changed.
#[test]
fn tx_update_bits_are_set_in_their_own_byte_and_cleared_after_sending() {
    for (bit, cfg) in (8u16..).zip(&UPDATE_BIT_CONFIGS) {
        let mut com = Com::new(cfg);
        let mut expected = [0x5A, 0, 0, 0, 0, 0, 0, 0];
        expected[usize::from(bit / 8)] |= 1 << (bit % 8);
        let sent = com.send_signal(SignalId(0), SignalValue::Unsigned(0x5A), |_, _| true);
        assert_eq!(sent, Ok(()));
        assert_eq!(com.tx_ipdu(TxIpduId(0)), Some(&expected[..]), "bit {bit}");
        let mut carried = Vec::new();
        com.main_function_tx(|_, data| {
            carried.push(data.to_vec());
            true
        });
        assert_eq!(carried, [expected.to_vec()], "bit {bit}");
        assert_eq!(
            com.tx_ipdu(TxIpduId(0)),
            Some(&[0x5A, 0, 0, 0, 0, 0, 0, 0][..]),
            "bit {bit} cleared"
        );
    }
}

/// Every rule of `ComConfig::new` at its edge, on tables built at run time.
#[test]
fn configuration_limits_and_edges() {
    let tx = |len, mode| TxIpduConfig {
        name: "t",
        len,
        mode,
        mdt_ms: 0,
    };
    let rx = |len| RxIpduConfig {
        name: "r",
        len,
        deadline_ms: 0,
    };
    let none = TxMode::None;
    let sig = |direction, init, invalid, update_bit| SignalConfig {
        name: "s",
        direction,
        layout: layout(0, 8),
        init,
        invalid,
        update_bit,
    };
    let tx0 = SignalDirection::Tx(TxIpduId(0), TransferProperty::Pending);
    let no_sig = sig(tx0, 0, None, None);

    // 254 I-PDUs or signals of each kind are allowed, 255 are not.
    assert!(ComConfig::<8, 254, 0, 0>::new(10, [tx(8, none); 254], [], []).is_ok());
    assert!(ComConfig::<8, 0, 254, 0>::new(10, [], [rx(8); 254], []).is_ok());
    assert!(ComConfig::<8, 1, 0, 254>::new(10, [tx(8, none)], [], [no_sig; 254]).is_ok());
    let limits = Some(ComConfigError::Limits);
    assert_eq!(
        ComConfig::<8, 255, 0, 0>::new(10, [tx(8, none); 255], [], []).err(),
        limits
    );
    assert_eq!(
        ComConfig::<8, 0, 255, 0>::new(10, [], [rx(8); 255], []).err(),
        limits
    );
    assert_eq!(
        ComConfig::<8, 1, 0, 255>::new(10, [tx(8, none)], [], [no_sig; 255]).err(),
        limits
    );

    // I-PDU lengths: 1..=N bytes, TX and RX (RX counted after the TX table).
    for len in [0, 9] {
        assert_eq!(
            ComConfig::<8, 1, 0, 0>::new(10, [tx(len, none)], [], []).err(),
            Some(ComConfigError::IpduLength { ipdu: 0 }),
            "TX {len}"
        );
        assert_eq!(
            ComConfig::<8, 1, 1, 0>::new(10, [tx(8, none)], [rx(len)], []).err(),
            Some(ComConfigError::IpduLength { ipdu: 1 }),
            "RX {len}"
        );
    }
    assert!(ComConfig::<8, 1, 1, 0>::new(10, [tx(1, none)], [rx(1)], []).is_ok());

    // A periodic mode needs a period; repetitions need a repetition period.
    let timing = Some(ComConfigError::Timing { ipdu: 0 });
    let mixed = |period_ms, repetitions, repetition_period_ms| TxMode::Mixed {
        period_ms,
        offset_ms: 0,
        repetitions,
        repetition_period_ms,
    };
    assert_eq!(
        ComConfig::<8, 1, 0, 0>::new(10, [tx(8, mixed(0, 0, 0))], [], []).err(),
        timing
    );
    assert_eq!(
        ComConfig::<8, 1, 0, 0>::new(10, [tx(8, mixed(100, 2, 0))], [], []).err(),
        timing
    );
    assert!(ComConfig::<8, 1, 0, 0>::new(10, [tx(8, mixed(100, 0, 0))], [], []).is_ok());
    assert!(ComConfig::<8, 1, 0, 0>::new(10, [tx(8, mixed(100, 2, 20))], [], []).is_ok());
    let direct = |repetitions, repetition_period_ms| TxMode::Direct {
        repetitions,
        repetition_period_ms,
    };
    assert_eq!(
        ComConfig::<8, 1, 0, 0>::new(10, [tx(8, direct(1, 0))], [], []).err(),
        timing
    );
    assert!(ComConfig::<8, 1, 0, 0>::new(10, [tx(8, direct(0, 0))], [], []).is_ok());
    assert_eq!(
        ComConfig::<8, 0, 1, 0>::new(
            10,
            [],
            [RxIpduConfig {
                deadline_ms: 15,
                ..rx(8)
            }],
            []
        )
        .err(),
        timing
    );

    // Signals: in an existing I-PDU, inside its length, values that fit, update bit inside.
    let bad = Some(ComConfigError::Signal { signal: 0 });
    let one = |s: SignalConfig<8>, len| {
        ComConfig::<8, 1, 1, 1>::new(10, [tx(len, none)], [rx(8)], [s]).err()
    };
    assert_eq!(one(sig(tx0, 0, None, None), 8), None);
    assert_eq!(
        one(sig(SignalDirection::Rx(RxIpduId(0)), 0, None, None), 8),
        None
    );
    assert_eq!(
        one(
            sig(
                SignalDirection::Tx(TxIpduId(1), TransferProperty::Pending),
                0,
                None,
                None
            ),
            8
        ),
        bad
    );
    assert_eq!(
        one(sig(SignalDirection::Rx(RxIpduId(1)), 0, None, None), 8),
        bad
    );
    assert_eq!(
        one(sig(tx0, 0x100, None, None), 8),
        bad,
        "init wider than 8 bits"
    );
    assert_eq!(one(sig(tx0, 0xFF, Some(0xFF), None), 8), None);
    assert_eq!(
        one(sig(tx0, 0, Some(0x100), None), 8),
        bad,
        "invalid wider than 8 bits"
    );
    let beyond = SignalConfig {
        layout: layout(56, 8),
        ..sig(tx0, 0, None, None)
    };
    assert_eq!(one(beyond, 8), None);
    assert_eq!(one(beyond, 2), bad, "signal in byte 7 of a 2-byte I-PDU");
    assert_eq!(one(sig(tx0, 0, None, Some(15)), 2), None);
    assert_eq!(
        one(sig(tx0, 0, None, Some(16)), 2),
        bad,
        "update bit beyond 2 bytes"
    );

    let errors = [
        (ComConfigError::Limits, "254"),
        (ComConfigError::IpduLength { ipdu: 0 }, "empty or longer"),
        (ComConfigError::Timing { ipdu: 0 }, "main-function periods"),
        (
            ComConfigError::Signal { signal: 0 },
            "does not fit its I-PDU",
        ),
    ];
    for (error, words) in errors {
        assert!(error.describe().contains(words), "{error:?}");
    }
}

/// A triggering write to an I-PDU without direct transmission (periodic mode) sends
/// nothing at once: the value goes out with the next period.
#[test]
fn a_trigger_on_a_periodic_ipdu_waits_for_its_period() {
    let mut com = Com::new(&CFG);
    let mut log = Vec::new();
    assert_eq!(send(&mut com, STATUS, 0x1234, &mut log), Ok(()));
    assert_eq!(log, [], "no direct transmission in periodic mode");
    run(&mut com, 2, &mut log);
    assert_eq!(log.last(), Some(&(2, 1, std::vec![0x34, 0x12])));
}

/// A transmit signal has no received value to read.
#[test]
fn receiving_a_transmit_signal_is_refused() {
    let com = Com::new(&CFG);
    assert_eq!(com.receive_signal(DISTANCE), Err(ComError::UnknownSignal));
    assert_eq!(
        com.receive_signal(SignalId(5)),
        Err(ComError::UnknownSignal)
    );
}

/// When the lower layer refuses a transmission, the I-PDU keeps its update bits (the data
/// has not gone out) and its minimum delay does not start: the next attempt carries them.
#[test]
fn a_refused_transmission_keeps_the_update_bits_and_starts_no_mdt() {
    let mut com = Com::new(&CFG);
    assert_eq!(
        com.send_signal(LEVEL, SignalValue::Unsigned(2), |_, _| true),
        Ok(())
    );
    let mut refused = 0;
    com.main_function_tx(|id, _| {
        refused += usize::from(id == TxIpduId(0));
        false
    });
    assert_eq!(
        refused, 1,
        "the periodic transmission of cycle 1 was attempted"
    );
    assert_eq!(
        com.tx_ipdu(TxIpduId(0)).and_then(|b| b.get(7)).copied(),
        Some(0x80),
        "update bit 63 still set"
    );
    // No MDT runs from the refused attempt: a triggering write goes out at once.
    let mut log = Vec::new();
    assert_eq!(send(&mut com, DISTANCE, 42, &mut log), Ok(()));
    assert_eq!(log.len(), 1);
    assert_eq!(log[0].2, [42, 0, 0, 0, 2, 0, 0, 0x80]);
    assert_eq!(
        com.tx_ipdu(TxIpduId(0)).and_then(|b| b.get(7)).copied(),
        Some(0)
    );
}

/// Triggered transfer properties without repetition send once and never repeat, even on
/// an I-PDU configured with repetitions; with repetition they repeat. The transmission
/// files nothing on the timer wheel (no repetition left to wake the I-PDU for).
#[test]
fn triggered_without_repetition_sends_once() {
    static ONCE: ComConfig<8, 1, 0, 2> = match ComConfig::new(
        10,
        [TxIpduConfig {
            name: "t",
            len: 1,
            mode: TxMode::Direct {
                repetitions: 3,
                repetition_period_ms: 10,
            },
            mdt_ms: 0,
        }],
        [],
        [
            SignalConfig {
                name: "once",
                direction: SignalDirection::Tx(
                    TxIpduId(0),
                    TransferProperty::TriggeredWithoutRepetition,
                ),
                layout: layout(0, 4),
                init: 0,
                invalid: None,
                update_bit: None,
            },
            SignalConfig {
                name: "on change once",
                direction: SignalDirection::Tx(
                    TxIpduId(0),
                    TransferProperty::TriggeredOnChangeWithoutRepetition,
                ),
                layout: layout(4, 4),
                init: 0,
                invalid: None,
                update_bit: None,
            },
        ],
    ) {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    };
    for (signal, value) in [(SignalId(0), 5), (SignalId(1), 6)] {
        let mut com = Com::new(&ONCE);
        let mut sent = 0;
        assert_eq!(
            com.send_signal(signal, SignalValue::Unsigned(value), |_, _| {
                sent += 1;
                true
            }),
            Ok(())
        );
        assert_eq!(
            com.tx_wheel.list[0], UNFILED,
            "signal {signal:?}: nothing filed"
        );
        for _ in 0..10 {
            com.main_function_tx(|_, _| {
                sent += 1;
                true
            });
        }
        assert_eq!(sent, 1, "signal {signal:?}: sent once, no repetition");
    }
}

/// An I-PDU whose every byte carries an update bit (here its only byte): the bit is
/// cleared after each transmission all the same.
#[test]
fn an_update_bit_in_every_byte_is_cleared_after_sending() {
    static ONE_BYTE: ComConfig<1, 1, 0, 1> = update_bit_config(1, 7, 7);
    let mut com = Com::new(&ONE_BYTE);
    assert_eq!(
        com.send_signal(SignalId(0), SignalValue::Unsigned(5), |_, _| true),
        Ok(())
    );
    assert_eq!(com.tx_ipdu(TxIpduId(0)), Some(&[0x85][..]));
    let mut sent = Vec::new();
    com.main_function_tx(|_, data| {
        sent.extend_from_slice(data);
        true
    });
    assert_eq!(sent, [0x85]);
    assert_eq!(com.tx_ipdu(TxIpduId(0)), Some(&[0x05][..]));
}

/// A received signal with its update bit in the middle of a byte (bit 13: byte 1, bit 5)
/// is taken over exactly when that bit is set in the frame.
#[test]
fn rx_update_bit_inside_a_byte() {
    static RX13: ComConfig<8, 0, 1, 1> = match ComConfig::new(
        10,
        [],
        [RxIpduConfig {
            name: "r",
            len: 2,
            deadline_ms: 0,
        }],
        [SignalConfig {
            name: "s",
            direction: SignalDirection::Rx(RxIpduId(0)),
            layout: layout(0, 8),
            init: 9,
            invalid: None,
            update_bit: Some(13),
        }],
    ) {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    };
    let mut com = Com::new(&RX13);
    com.rx_indication(RxIpduId(0), &[42, 0b1101_1111]);
    assert_eq!(
        com.receive_signal(SignalId(0)),
        Ok(SignalValue::Unsigned(9)),
        "bit 13 clear (the other bits of its byte set): not updated"
    );
    com.rx_indication(RxIpduId(0), &[42, 0b0010_0000]);
    assert_eq!(
        com.receive_signal(SignalId(0)),
        Ok(SignalValue::Unsigned(42))
    );
}

/// A one-byte I-PDU in `mode` with an MDT of `mdt_ms`, and one triggered signal in it.
const fn one_triggered_ipdu(mode: TxMode, mdt_ms: u32) -> ComConfig<8, 1, 0, 1> {
    match ComConfig::new(
        10,
        [TxIpduConfig {
            name: "t",
            len: 1,
            mode,
            mdt_ms,
        }],
        [],
        [SignalConfig {
            name: "s",
            direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::Triggered),
            layout: layout(0, 8),
            init: 0,
            invalid: None,
            update_bit: None,
        }],
    ) {
        Ok(cfg) => cfg,
        Err(_) => panic!("test configuration refused"),
    }
}

/// The main-function cycles 1..=`last` in which `cfg`'s I-PDU goes out, with its signal
/// written right after the main function of cycle `trigger`.
fn transmissions(cfg: &'static ComConfig<8, 1, 0, 1>, trigger: u32, last: u32) -> Vec<u32> {
    let mut com = Com::new(cfg);
    let mut cycles = Vec::new();
    for now in 1..=last {
        com.main_function_tx(|_, _| {
            cycles.push(now);
            true
        });
        if now == trigger {
            assert_eq!(
                com.send_signal(SignalId(0), SignalValue::Unsigned(1), |_, _| {
                    cycles.push(now);
                    true
                }),
                Ok(())
            );
        }
    }
    cycles
}

/// Triggered transmissions against the periodic timing, the repetitions and the MDT of a
/// one-byte I-PDU:
/// - mixed, without repetitions (and so without a repetition period): a trigger leaves
///   the period exactly as it was;
/// - mixed, with a periodic transmission between two repetitions: the repetitions keep
///   their own timing;
/// - direct, repetitions 10 ms apart under a 20 ms MDT: each waits for the MDT, and there
///   are exactly as many as configured. (They once never ended: a held repetition did not
///   count.)
#[test]
fn triggers_against_period_repetitions_and_mdt() {
    static CONFIGS: [ComConfig<8, 1, 0, 1>; 3] = [
        one_triggered_ipdu(
            TxMode::Mixed {
                period_ms: 50,
                offset_ms: 0,
                repetitions: 0,
                repetition_period_ms: 0,
            },
            0,
        ),
        one_triggered_ipdu(
            TxMode::Mixed {
                period_ms: 100,
                offset_ms: 0,
                repetitions: 2,
                repetition_period_ms: 30,
            },
            0,
        ),
        one_triggered_ipdu(
            TxMode::Direct {
                repetitions: 2,
                repetition_period_ms: 10,
            },
            20,
        ),
    ];
    let [no_reps, mixed, held] = &CONFIGS;
    // Periodic in 1, 6, 11, ...; triggered in 3.
    assert_eq!(transmissions(no_reps, 3, 21), [1, 3, 6, 11, 16, 21]);
    // Periodic in 1, 11, 21; triggered in 9, repeated in 12 and 15.
    assert_eq!(transmissions(mixed, 9, 21), [1, 9, 11, 12, 15, 21]);
    // Triggered in 1; the repetitions, due in 2 and 3, wait for the MDT: 3 and 5.
    assert_eq!(transmissions(held, 1, 30), [1, 3, 5]);
}

/// A direct I-PDU leaves the timer wheel once its last repetition is out, so the main
/// function's later cycles are idle: nothing is filed, rather than the I-PDU woken every
/// cycle to find nothing due. The same with repetitions under an MDT and without either.
#[test]
fn a_direct_ipdu_leaves_the_wheel_when_its_repetitions_are_done() {
    static CONFIGS: [ComConfig<8, 1, 0, 1>; 2] = [
        one_triggered_ipdu(
            TxMode::Direct {
                repetitions: 2,
                repetition_period_ms: 10,
            },
            20,
        ),
        one_triggered_ipdu(
            TxMode::Direct {
                repetitions: 0,
                repetition_period_ms: 0,
            },
            0,
        ),
    ];
    // Natively 300 cycles; under Miri, which interprets each one, the 60 after the write.
    let cycles = if cfg!(miri) { 60 } else { 300 };
    for (cfg, expected) in CONFIGS.iter().zip([&[1, 3, 5][..], &[1][..]]) {
        let mut com = Com::new(cfg);
        let mut sent = Vec::new();
        for now in 1..=cycles {
            com.main_function_tx(|_, _| {
                sent.push(now);
                true
            });
            if now == 1 {
                let write = com.send_signal(SignalId(0), SignalValue::Unsigned(1), |_, _| {
                    sent.push(now);
                    true
                });
                assert_eq!(write, Ok(()));
            }
            if sent.len() == expected.len() && sent.last() < Some(&now) {
                assert_eq!(com.tx_wheel.list[0], UNFILED, "cycle {now}");
                assert!(com.tx_wheel.head.iter().all(|h| *h == NIL), "cycle {now}");
            }
        }
        assert_eq!(sent, expected);
    }
}

/// An entry filed for the cycle the caller is at, or one before it, is taken in the next
/// cycle (the caller's own slot is taken already), not a wheel revolution later.
#[test]
fn an_entry_filed_for_a_past_cycle_is_taken_in_the_next() {
    for due in [0, 99, 100] {
        let mut wheel = Wheel::<1>::new();
        wheel.file(0, due, 100);
        assert!(wheel.busy(101), "due {due}");
        assert_eq!(wheel.take(101), 0, "due {due}");
    }
}
