//! Fuzz targets. Each is a bolero test: `cargo test -p cw-fuzz` runs it on random inputs
//! and its committed corpus, `cargo bolero test -p cw-fuzz <target>` runs it under
//! libFuzzer (coverage-guided, AddressSanitizer), and the check command runs each for a
//! short smoke time. The properties checked are the core's own contracts
//! (`cw_core::com::signal::spec::codec_contract`, `cw_core::os::spec::call_and_check`).
//!
//! The book: [verification](../../book/verification.html) (what each target covers).
//!
//! Corpora live under `src/__fuzz__/<target>/corpus` and are committed.

use cw_core::os::spec::Service;
use cw_core::os::{AlarmId, CounterId, IsrId, ResourceId, ServiceCall, TaskId, RES_SCHEDULER};

/// Decodes four fuzzer bytes into one step of the code running on the processor: any
/// service, an ISR's entry or return, a whole ISR making one call, or a task body that
/// returns. Ids range a little beyond every configuration used here so that `E_OS_ID`
/// paths are exercised.
pub fn decode_service(op: u8, a: u8, b: u8, c: u8) -> Service {
    let task = TaskId(a % 8);
    let res = if b % 4 == 3 {
        RES_SCHEDULER
    } else {
        ResourceId(b % 4)
    };
    let mask = u32::from(b % 4);
    let isr = IsrId(c % 4);
    let call = match op % 26 {
        // The port's activation (the kernel's fast path, the service where it declines)
        // or the service itself.
        0 if c % 2 == 1 => return Service::FastActivate(task),
        0 => ServiceCall::ActivateTask(task),
        1 => ServiceCall::TerminateTask,
        2 => ServiceCall::ChainTask(task),
        3 => ServiceCall::Schedule,
        4 => ServiceCall::SetEvent(task, mask),
        5 => ServiceCall::ClearEvent(mask),
        6 => ServiceCall::WaitEvent(mask),
        // The port's lock (the kernel's fast path, the service where it declines) or the
        // service itself.
        7 if c % 2 == 1 => return Service::FastGet(res),
        8 if c % 2 == 1 => return Service::FastRelease(res),
        7 => ServiceCall::GetResource(res),
        8 => ServiceCall::ReleaseResource(res),
        9 => ServiceCall::SetRelAlarm {
            alarm: AlarmId(a % 6),
            increment: u32::from(b),
            cycle: u32::from(c % 50),
        },
        10 => ServiceCall::SetAbsAlarm {
            alarm: AlarmId(a % 6),
            start: u32::from(b),
            cycle: u32::from(c % 50),
        },
        11 => ServiceCall::CancelAlarm(AlarmId(a % 6)),
        12 => ServiceCall::IncrementCounter(CounterId(a % 2)),
        13 => return Service::EnterIsr(isr),
        14 => return Service::ExitIsr,
        15 => return Service::Isr(isr, ServiceCall::IncrementCounter(CounterId(a % 2))),
        16 => return Service::Isr(isr, ServiceCall::ActivateTask(task)),
        17 => return Service::Isr(isr, ServiceCall::SetEvent(task, mask)),
        18 => return Service::TaskReturn,
        19 => match b % 6 {
            0 => ServiceCall::DisableAllInterrupts,
            1 => ServiceCall::EnableAllInterrupts,
            2 => ServiceCall::SuspendAllInterrupts,
            3 => ServiceCall::ResumeAllInterrupts,
            4 => ServiceCall::SuspendOsInterrupts,
            _ => ServiceCall::ResumeOsInterrupts,
        },
        20 => ServiceCall::GetTaskId,
        21 => ServiceCall::GetTaskState(task),
        22 => ServiceCall::GetEvent(task),
        23 => ServiceCall::GetAlarm(AlarmId(a % 6)),
        24 => ServiceCall::GetIsrId,
        _ => ServiceCall::ShutdownOs(c),
    };
    Service::Call(call)
}

#[cfg(test)]
mod targets {
    use super::decode_service;
    use cw_can::asc::AscReader;
    use cw_can::blf::BlfReader;
    use cw_can::codec;
    use cw_can::dbc::{Database, Strictness};
    use cw_can::log::{At, CandumpReader};
    use cw_can::report::{self, Format};
    use cw_can::view::feed::{Control, Feed, CHART_POINTS};
    use cw_can::view::state::{Replay, ViewFrames};
    use cw_core::can::{slcan, CanFrame, CanId};
    use cw_core::com::signal::{spec, ByteOrder, SignalLayout, Signedness};
    use cw_core::os::spec::call_and_check;
    use cw_core::os::OSDEFAULTAPPMODE;
    use cw_core::scenario;
    use cw_core::sonar::uart;
    use cw_proofs::{configs, Kernel};

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
        const I: usize,
        const Q: usize,
    >(
        cfg: &'static cw_core::os::OsConfig<T, R, C, A, I>,
        calls: &[(u8, u8, u8, u8)],
    ) {
        let Ok(mut os) = Kernel::<T, R, C, A, I, Q>::new(cfg) else {
            panic!("configuration refused");
        };
        assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
        for &(op, a, b, c) in calls.iter().take(256) {
            let service = decode_service(op, a, b, c);
            if let Err(rule) = call_and_check(&mut os, service) {
                panic!("{service:?}: {rule}");
            }
            if let Some(rule) = os.hooks().broken() {
                panic!("{service:?}: {rule}");
            }
        }
    }

    /// Any sequence of steps (services, ISR entries and returns, interrupt locks, missing
    /// ends, shutdown) on the paper's task set, the event-heavy set and the interrupt set:
    /// every transition rule, kernel invariant and hook rule holds after every step.
    #[test]
    fn scheduler_api() {
        bolero::check!()
            .with_type::<(u8, Vec<(u8, u8, u8, u8)>)>()
            .for_each(|(set, calls)| match set % 3 {
                0 => run_services::<6, 2, 1, 4, 2, 6>(&configs::PAPER, calls),
                1 => run_services::<3, 1, 1, 2, 1, 4>(&configs::EVENTS, calls),
                _ => run_services::<3, 1, 0, 0, 3, 3>(&configs::INTERRUPTS, calls),
            });
    }

    /// Any bytes arriving on an SLCAN link, then a good frame's line: the decoder accepts
    /// only canonical frame lines, gives at most one verdict per line end, never panics,
    /// and the good frame after the garbage comes out intact
    /// (`cw_core::can::slcan::spec::stream_contract`).
    #[test]
    fn slcan_stream() {
        bolero::check!()
            .with_type::<(Vec<u8>, u32, bool, u8, [u8; 8])>()
            .for_each(|(garbage, raw, extended, len, data)| {
                let frame = CanFrame::masked(CanId::masked(*raw, *extended), *len, *data);
                assert!(slcan::spec::stream_contract(garbage, &frame));
            });
    }

    /// Any schedule of job starts, stack use, ends, waits and wake-ups: the preemptive
    /// port's switch keeps every job's context apart on the shared stack and on the own
    /// stacks (`cw_bsp::port::preempt::spec::stacks_stay_apart`).
    #[test]
    fn port_switch() {
        bolero::check!()
            .with_type::<Vec<(u8, u8)>>()
            .for_each(|steps| assert!(cw_bsp::port::preempt::spec::stacks_stay_apart(steps)));
    }

    /// Any copy, move (overlapping or not) and fill, at any alignment and length in 64
    /// bytes: the Cortex-M images' memory functions leave the bytes the standard
    /// library's copies and fills leave (`cw_bsp::mem::spec`).
    #[test]
    fn mem_functions() {
        use cw_bsp::mem::spec::{all_agree, Buf};
        bolero::check!()
            .with_type::<([u8; 64], [u8; 4])>()
            .for_each(|(bytes, ops)| {
                let mut b = Buf(*bytes);
                b.0.reverse();
                assert!(all_agree(&Buf(*bytes), &b, *ops));
            });
    }

    /// Any writes, received bytes, transmitter room and interrupt work on the SLCAN
    /// controller over a model UART: each accepted frame confirmed once, in order, its
    /// line out whole (`cw_bsp::slcan::spec`).
    #[test]
    fn slcan_controller() {
        bolero::check!()
            .with_type::<Vec<(u8, u8, u8)>>()
            .for_each(|ops| {
                assert!(cw_bsp::slcan::spec::operations_confirm_each_frame_once(ops));
            });
    }

    /// Any sequence of `Can_Write`, aborts, mode changes, frames sent, failed and
    /// received, idle bus and interrupt work on the FlexCAN driver over the register-level
    /// model: no frame confirmed that was not sent, one owner per message buffer, no
    /// received frame lost uncounted (`cw_bsp::chip::flexcan::spec`).
    #[test]
    fn flexcan_mailboxes() {
        bolero::check!().with_type::<Vec<u8>>().for_each(|bytes| {
            let ops: Vec<_> = cw_bsp::chip::flexcan::spec::decode(bytes).collect();
            assert!(cw_bsp::chip::flexcan::spec::mailboxes_keep_their_promises(
                &ops
            ));
        });
    }

    /// Any clock, bitrate and sample point: the bit timing found is within FlexCAN's
    /// limits, exact, and has the nearest sample point, or none exists
    /// (`cw_core::can::bittiming::spec`, on limits small enough to search exhaustively).
    #[test]
    fn bit_timing() {
        bolero::check!()
            .with_type::<(u32, u32, u16)>()
            .cloned()
            .for_each(|(clock, divisor, sample)| {
                let limits = cw_core::can::bittiming::BitTimingLimits {
                    prescaler: (1, 16),
                    ..cw_core::can::bittiming::FLEXCAN
                };
                let clock = clock % 100_000_000 + 1;
                let bitrate = clock / (divisor % 400 + 1);
                assert!(cw_core::can::bittiming::spec::find_is_exact_and_nearest(
                    clock,
                    bitrate,
                    sample % 1000,
                    &limits
                ));
            });
    }

    /// Any releases of four tasks or ISRs of any priorities and limits, at any times and
    /// costs: the OS's timing model (`cw_core::os::timeline`, which times the evaluation's
    /// host setting) keeps its promises (`spec::replay_keeps_its_promises`).
    #[test]
    fn os_timeline() {
        bolero::check!()
            .with_type::<([(u16, u8); 4], Vec<(u32, u8, u32)>)>()
            .for_each(|(items, releases)| {
                let items =
                    items.map(|(priority, limit)| cw_core::os::timeline::Item { priority, limit });
                assert!(cw_core::os::timeline::spec::replay_keeps_its_promises(
                    &items, releases
                ));
            });
    }

    /// The ECU's ARXML descriptions with any of their texts replaced by any text: the basic
    /// software's values (`ecu.arxml`) or the software components' short names, references,
    /// periods, init values, queue lengths and Rust types (`swc.arxml`). They generate, or
    /// are refused with every error naming the file or an ARXML path, never a panic
    /// (`cw_gen::spec::a_changed_value_generates_or_names_paths`,
    /// `cw_gen::spec::a_changed_component_generates_or_names_paths`).
    #[test]
    fn arxml_description() {
        bolero::check!()
            .with_type::<(bool, u8, u8, String)>()
            .for_each(|(components, tag, which, value)| {
                if *components {
                    assert!(cw_gen::spec::a_changed_component_generates_or_names_paths(
                        usize::from(*tag),
                        usize::from(*which),
                        value
                    ));
                } else {
                    assert!(cw_gen::spec::a_changed_value_generates_or_names_paths(
                        usize::from(*which),
                        value
                    ));
                }
            });
    }

    /// Any bus (frames and signals of any id, layout, scaling, range, named values, sender,
    /// receivers and comments) written as a system description (ARXML) and as a DBC reads
    /// back the same; any text read as either is a bus or refused, never a panic; frames
    /// between other nodes leave the ECU's communication as it was, and one the ECU sends
    /// without a CanIf PDU is refused (`cw_gen::spec::a_bus_reads_back_as_written`,
    /// `cw_gen::spec::a_text_is_a_bus_or_is_refused`,
    /// `cw_gen::spec::frames_of_other_nodes_leave_the_ecu_alone`).
    #[test]
    fn bus_description() {
        bolero::check!()
            .with_type::<(Vec<cw_gen::spec::FrameSeed>, String)>()
            .for_each(|(frames, text)| {
                assert!(cw_gen::spec::a_bus_reads_back_as_written(frames));
                assert!(cw_gen::spec::a_text_is_a_bus_or_is_refused(text));
                assert!(cw_gen::spec::frames_of_other_nodes_leave_the_ecu_alone(
                    frames
                ));
            });
    }

    /// Any frame, standard or extended, of any length and payload: its stuff bits counted
    /// eight bits at a time through the tables are those its bits one by one get
    /// (`cw_core::can::timing::spec::stuffing_agrees`, the CRC-15 included).
    #[test]
    fn frame_stuffing() {
        bolero::check!()
            .with_type::<(bool, u32, u8, [u8; 8])>()
            .cloned()
            .for_each(|(extended, raw, len, data)| {
                let frame = cw_core::can::CanFrame::masked(
                    cw_core::can::CanId::masked(raw, extended),
                    len,
                    data,
                );
                assert!(cw_core::can::timing::spec::stuffing_agrees(&frame));
            });
    }

    /// Any run of WdgM's main functions with any alive indications: the supervision keeps
    /// its rule (`cw_core::wdgm::spec::alive_rule`) on the ECU's own configuration.
    #[test]
    fn wdgm_alive() {
        bolero::check!()
            .with_type::<(Vec<[u8; 3]>, u8)>()
            .for_each(|(rounds, tolerance)| {
                let rounds: Vec<[u32; 3]> =
                    rounds.iter().map(|r| r.map(|n| u32::from(n % 4))).collect();
                assert!(cw_core::wdgm::spec::alive_rule(
                    &ALIVE,
                    u16::from(tolerance % 3),
                    &rounds
                ));
            });
    }

    /// Any run of ComM requests, bus-offs, controller mode indications (on time, late,
    /// never), refusals and main-function periods keeps CanSM's promises
    /// (`cw_core::cansm::spec::events_keep_the_promises`) on the ECU's timing (10 ms BSW
    /// period: fast recovery 10 ms twice, slow 1 s, ensured after 100 ms; a mode request
    /// asked again after 10 ms, three times).
    #[test]
    fn cansm_modes() {
        let cfg = cw_core::cansm::CanSmConfig::from_ms(
            10,
            cw_core::cansm::CanSmTimesMs {
                fast_retries: 2,
                fast: 10,
                slow: 1000,
                tx_ensured: 100,
                mode_request: 10,
                mode_request_repeats: 3,
            },
        )
        .expect("the ECU's CanSM timing");
        bolero::check!()
            .with_type::<Vec<u8>>()
            .for_each(|events: &Vec<u8>| {
                assert!(cw_core::cansm::spec::events_keep_the_promises(cfg, events))
            });
    }

    /// The ECU's alive supervision (`cw-firmware`'s `config::ALIVE`, written out: the fuzz
    /// targets do not link the firmware).
    static ALIVE: [cw_core::wdgm::AliveSupervision; 3] = [
        cw_core::wdgm::AliveSupervision::new("OsLEDTask", 1, 1),
        cw_core::wdgm::AliveSupervision::new("OsObstacleDetectionTask", 2, 1),
        cw_core::wdgm::AliveSupervision::new("OsSonarTask", 4, 1),
    ];

    /// Any text as a scenario file (the host simulation's and the image's parser): read
    /// or refused with a line number within the text, never a panic; every line read
    /// writes back to a line that reads as the same command.
    #[test]
    fn scenario_text() {
        bolero::check!()
            .with_type::<String>()
            .for_each(|text: &String| {
                match scenario::Scenario::<8>::parse(text) {
                    Ok(s) => assert!(!s.segments.is_empty()),
                    Err(e) => assert!(e.line <= text.lines().count()),
                }
                for line in text.lines() {
                    if let Ok(Some(command)) = scenario::parse_line(line) {
                        let again = command.to_string();
                        assert_eq!(scenario::parse_line(&again), Ok(Some(command)), "{again}");
                    }
                }
            });
    }

    /// Any bytes on the distance sensor's UART (the A02YYUW protocol): the streaming
    /// decoder gives exactly the verdicts, stray and pending counts of the batch rule
    /// (`cw_core::sonar::uart::spec::matches_reference`), never a panic.
    #[test]
    fn sensor_uart_stream() {
        bolero::check!()
            .with_type::<Vec<u8>>()
            .for_each(|bytes: &Vec<u8>| assert!(uart::spec::matches_reference(bytes)));
    }

    /// Any DBC and any log, as `cw-can decode` reads them (the input's bytes up to the
    /// first 0 byte are the DBC, in UTF-8 or Windows-1252; the rest is read as a candump
    /// log and as an ASC log): the
    /// DBC loads (strict, or else lenient) or is refused with a reason, every log line is an entry or an error that
    /// names its line, and every entry decodes or is refused, then renders in every output
    /// form, never a panic. Each decoded frame's signals encode back into the same bits.
    #[test]
    fn dbc_and_log() {
        bolero::check!().for_each(|bytes: &[u8]| {
            let (dbc, log) = match bytes.iter().position(|b| *b == 0) {
                Some(at) => (&bytes[..at], &bytes[at + 1..]),
                None => (bytes, &[][..]),
            };
            // Strict, or else lenient (what strict refuses for a layout is a warning);
            // where strict loads, lenient loads the same with no warning.
            let text = cw_can::dbc::text_of(dbc);
            let lenient = Database::from_text_with(&text, Strictness::Lenient);
            let db = match Database::from_text(&text) {
                Ok(strict) => {
                    let Ok(lenient) = lenient else {
                        panic!("a DBC strict loading takes, lenient loading refuses")
                    };
                    assert!(lenient.warnings().is_empty());
                    assert_eq!(lenient.messages(), strict.messages());
                    strict
                }
                Err(_) => match lenient {
                    Ok(db) => db,
                    Err(_) => return,
                },
            };
            let lines = log.split(|b| *b == b'\n').count();
            let candump = CandumpReader::new(log);
            let asc = AscReader::new(log);
            for item in candump.chain(asc) {
                let entry = match item {
                    Ok(entry) => entry,
                    Err(e) => {
                        assert!(
                            e.line_number().is_some_and(|n| (1..=lines).contains(&n)),
                            "{e}"
                        );
                        continue;
                    }
                };
                let Ok(decoded) = report::decode(&db, &entry) else {
                    continue;
                };
                for format in [Format::Text, Format::Json, Format::Csv] {
                    assert!(!decoded.render(format).is_empty());
                }
                if let Some((name, signals)) = &decoded.message {
                    check_reencodes(&db, name, &entry.frame.data, signals);
                }
            }
        });
    }

    /// The decoded raw values, encoded again without scaling, give back the frame's bits
    /// of every present signal.
    fn check_reencodes(db: &Database, name: &str, data: &[u8], signals: &[codec::Decoded<'_>]) {
        let Some(message) = db.by_name(name) else {
            panic!("{name} decoded but not in the database")
        };
        let Ok(bits) = codec::encode_raw(message, signals) else {
            panic!("{name}: the decoded values do not encode again")
        };
        for d in signals {
            let mut theirs = [0u8; 64];
            let mut ours = [0u8; 64];
            for (to, from) in theirs.iter_mut().zip(data) {
                *to = *from;
            }
            for (to, from) in ours.iter_mut().zip(&bits) {
                *to = *from;
            }
            assert_eq!(
                d.signal.layout.unpack_raw(&theirs),
                d.signal.layout.unpack_raw(&ours),
                "{name}.{}",
                d.signal.name
            );
        }
    }

    /// Any bytes as a BLF file (`cw-can`'s reader of Vector's binary logs, zlib
    /// containers included): refused at the header, or entries and errors that name a
    /// byte offset, never a panic, and an end.
    #[test]
    fn blf_bytes() {
        bolero::check!().for_each(|bytes: &[u8]| {
            let Ok(reader) = BlfReader::new(bytes.to_vec()) else {
                return;
            };
            let mut errors = 0;
            for item in reader {
                if let Err(e) = item {
                    assert!(matches!(e.at, At::Byte(_)), "{e}");
                    errors += 1;
                    assert!(errors <= bytes.len(), "an error per object at most");
                }
            }
        });
    }

    /// Any bytes as a candump log replayed in the view (the first 16 bytes drive the
    /// replay's controls, the rest is the log, decoded with the ECU's DBC): bad lines and
    /// frames are named, the clock stays within the log under any play, speed and seek,
    /// and every snapshot has at most the chart's points and is JSON, never a panic.
    #[test]
    fn view_replay() {
        let db = Database::from_bytes(include_bytes!("../../firmware/ecu.dbc"));
        let Ok(db) = db else { panic!("ecu.dbc loads") };
        let Ok(frame) = ViewFrames::find(&db) else {
            panic!("ecu.dbc has a DistanceFrame")
        };
        bolero::check!().for_each(|bytes: &[u8]| {
            let (ops, log) = bytes.split_at(bytes.len().min(16));
            let lines = log.split(|b| *b == b'\n').count();
            let mut reader = CandumpReader::new(log);
            let entries: Vec<_> = std::iter::from_fn(|| {
                let item = reader.next()?;
                Some(item.map(|e| (At::Line(reader.line()), e)))
            })
            .collect();
            let errors = entries.iter().filter(|e| e.is_err()).count();
            let replay = Replay::new(&frame, entries, "fuzz.log");
            assert!(replay.bad().len() >= errors);
            assert!(replay.bad().len() <= lines);
            let mut feed = Feed::Replay(replay, "fuzz.log".into());
            for op in ops.chunks(2) {
                let (kind, value) = (op.first().copied().unwrap_or(0), op.get(1).copied());
                let value = f64::from(value.unwrap_or(0));
                let control = match kind % 4 {
                    0 => Control {
                        play: Some(kind & 4 == 0),
                        ..Control::default()
                    },
                    1 => Control {
                        speed: Some(value / 8.0),
                        ..Control::default()
                    },
                    2 => Control {
                        seek: Some(value / 16.0 - 1.0),
                        ..Control::default()
                    },
                    _ => {
                        feed.tick(value / 32.0);
                        Control::default()
                    }
                };
                let _ = feed.control(control);
                let snap = feed.snapshot();
                let Some(clock) = snap.clock else {
                    panic!("a replay has a clock")
                };
                assert!((0.0..=clock.duration).contains(&clock.position));
                assert!(snap.chart.len() <= CHART_POINTS);
                assert!(serde_json::to_string(&snap).is_ok());
            }
        });
    }
}
