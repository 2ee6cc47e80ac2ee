extern crate std;

use std::string::ToString;
use std::vec;
use std::vec::Vec;

use core::cell::Cell;

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use cw_core::can::bittiming::{self, FLEXCAN};
use cw_core::can::confinement::Failure;
use cw_core::can::{
    CanBusy, CanDriver, CanFrame, CanId, ControllerConfig, ControllerMode, Hrh, Hth, ModeChange,
    ModeRefused,
};

use super::model::{ACK_READS, MCR_RESET, RECOVERY_SEQUENCES};
use super::regs::{
    data_bytes, data_words, offset, Access, Mmio, Registers, CTRL1, ESR1, MB_CS, MCR,
};
use super::spec::{self, Op, BITRATE, CONFIG};
use super::*;

fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::from_parts(CanId::masked(u32::from(id), false), data).unwrap()
}

fn started() -> Flexcan<FlexcanModel> {
    let mut can = Flexcan::new(FlexcanModel::new(), &CONFIG).unwrap();
    can.init(&BITRATE).unwrap();
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    can
}

fn model(can: &Flexcan<FlexcanModel>) -> &FlexcanModel {
    can.registers().access()
}

fn events(can: &mut Flexcan<FlexcanModel>) -> Vec<FlexcanEvent> {
    core::iter::from_fn(|| can.take_event()).collect()
}

/// The module's next frame goes out (or fails) at once.
fn transmit(can: &Flexcan<FlexcanModel>, failure: Option<Failure>) -> Option<CanFrame> {
    let m = model(can);
    let (mb, frame) = m.offer()?;
    m.begin_tx(mb);
    m.end_tx(failure);
    Some(frame)
}

// ---- the model against the manual's sequences ----

#[test]
fn out_of_reset_the_module_is_disabled_and_asked_to_freeze() {
    let regs = Registers::new(FlexcanModel::new());
    assert_eq!(regs.mcr().get(), MCR_RESET);
    assert_eq!(regs.iflag1().get(), 0);
    assert_eq!(regs.esr1().read(ESR1::FLTCONF), 0);
}

#[test]
fn enabling_enters_freeze_mode_after_a_few_clocks() {
    let regs = Registers::new(FlexcanModel::new());
    regs.mcr().modify(MCR::MDIS::CLEAR);
    let reads = (1..=10).find(|_| regs.mcr().is_set(MCR::FRZACK)).unwrap();
    assert!(reads > 1, "not acknowledged on the first read");
    assert!(reads <= usize::from(ACK_READS) + 2);
    assert!(!regs.mcr().is_set(MCR::LPMACK));
    assert!(regs.mcr().is_set(MCR::NOTRDY));
}

fn frozen() -> Registers<FlexcanModel> {
    let regs = Registers::new(FlexcanModel::new());
    regs.mcr().modify(MCR::MDIS::CLEAR);
    assert!((0..10).any(|_| regs.mcr().is_set(MCR::FRZACK)));
    regs
}

#[test]
fn freeze_is_entered_only_at_the_end_of_the_frame_on_the_wire() {
    let regs = frozen();
    regs.mcr().modify(MCR::HALT::CLEAR);
    assert!((0..10).any(|_| !regs.mcr().is_set(MCR::FRZACK)));
    let m = regs.access();
    m.begin_rx();
    regs.mcr().modify(MCR::HALT::SET);
    assert!((0..100).all(|_| !regs.mcr().is_set(MCR::FRZACK)));
    m.end_rx(&std_frame(0x10, &[1]));
    assert!(regs.mcr().is_set(MCR::FRZACK));
}

#[test]
fn soft_reset_clears_flags_and_counters_but_keeps_timing_and_buffers() {
    let regs = frozen();
    regs.ctrl1()
        .write(CTRL1::PRESDIV.val(3) + CTRL1::BOFFREC::SET);
    regs.mb_data(5, 0).set(0xDEAD_BEEF);
    regs.imask1().set(0xFF);
    regs.access().write(offset::IFLAG1, 0); // w1c: nothing cleared, nothing set
    regs.mcr().modify(MCR::AEN::SET + MCR::SOFTRST::SET);
    assert!(regs.mcr().is_set(MCR::SOFTRST), "still resetting");
    assert!(!regs.mcr().is_set(MCR::SOFTRST), "done");
    assert!(!regs.mcr().is_set(MCR::AEN), "MCR back to reset");
    assert_eq!(regs.imask1().get(), 0);
    assert_eq!(regs.ctrl1().read(CTRL1::PRESDIV), 3);
    assert_eq!(regs.mb_data(5, 0).get(), 0xDEAD_BEEF);
}

#[test]
fn a_soft_reset_of_a_disabled_module_never_completes() {
    let regs = Registers::new(FlexcanModel::new());
    regs.mcr().modify(MCR::SOFTRST::SET);
    assert!((0..100).all(|_| regs.mcr().is_set(MCR::SOFTRST)));
}

#[test]
fn configuration_outside_freeze_mode_is_ignored_and_counted() {
    let regs = frozen();
    regs.ctrl1().write(CTRL1::PRESDIV.val(1));
    regs.mcr().modify(MCR::HALT::CLEAR);
    assert!((0..10).any(|_| !regs.mcr().is_set(MCR::FRZACK)));
    regs.ctrl1().write(CTRL1::PRESDIV.val(7));
    regs.mcr().modify(MCR::MAXMB.val(3));
    regs.rximr(2).set(0);
    assert_eq!(regs.ctrl1().read(CTRL1::PRESDIV), 1);
    assert_eq!(regs.mcr().read(MCR::MAXMB), 15);
    assert_eq!(regs.rximr(2).get(), u32::MAX);
    // CLKSRC changes only while disabled, even in freeze mode.
    regs.ctrl1().modify(CTRL1::BOFFREC::SET);
    assert!(
        regs.ctrl1().is_set(CTRL1::BOFFREC),
        "BOFFREC may change any time"
    );
    assert_eq!(regs.access().stats().ignored_writes, 3);
}

#[test]
fn flags_clear_by_writing_one() {
    let can = started();
    let m = model(&can);
    m.receive(&std_frame(0x123, &[1]));
    m.receive(&std_frame(0x124, &[2]));
    let regs = can.registers();
    assert_eq!(regs.iflag1().get(), 0b1010);
    regs.iflag1().set(0b0010);
    assert_eq!(regs.iflag1().get(), 0b1000);
    regs.esr1().write(ESR1::BOFFINT::SET);
    assert_eq!(regs.iflag1().get(), 0b1000);
}

#[test]
fn a_frame_for_a_locked_buffer_waits_for_the_unlock() {
    let can = started();
    let m = model(&can);
    let regs = can.registers();
    m.receive(&std_frame(0x123, &[1]));
    let _ = regs.mb_cs(1).get(); // locks buffer 1, which is now serviced (free again)
    assert_eq!(m.locked(), Some(1));
    assert_eq!(m.receive(&std_frame(0x123, &[2])), RxOutcome::Held(1));
    assert_eq!(
        regs.mb_data(1, 0).get() >> 24,
        1,
        "the old frame stays while locked"
    );
    let _ = regs.timer().get();
    assert_eq!(m.locked(), None);
    assert_eq!(regs.mb_data(1, 0).get() >> 24, 2);
    assert_eq!(regs.mb_cs(1).read(MB_CS::CODE), 0b0010, "FULL");
    // Two frames while locked: the first is lost, the buffer overruns.
    let _ = regs.mb_cs(1).get();
    m.receive(&std_frame(0x123, &[3]));
    m.receive(&std_frame(0x123, &[4]));
    let _ = regs.mb_cs(2).get(); // reading another buffer also unlocks
    assert_eq!(regs.mb_cs(1).read(MB_CS::CODE), 0b0110, "OVERRUN");
    assert_eq!(regs.mb_data(1, 0).get() >> 24, 4);
    assert_eq!(m.stats().rx_lost, 1);
}

#[test]
fn matching_takes_the_first_free_buffer_then_overwrites_the_last() {
    let can = started();
    let m = model(&can);
    // Buffer 1: exactly 0x123; buffer 3: any standard id.
    assert_eq!(m.receive(&std_frame(0x123, &[1])), RxOutcome::Stored(1));
    assert_eq!(m.receive(&std_frame(0x123, &[2])), RxOutcome::Stored(3));
    assert_eq!(m.receive(&std_frame(0x123, &[3])), RxOutcome::Overrun(3));
    assert_eq!(m.receive(&std_frame(0x7FF, &[4])), RxOutcome::Overrun(3));
    let ext = CanFrame::from_parts(CanId::masked(0x55, true), &[]).unwrap();
    assert_eq!(m.receive(&ext), RxOutcome::Unmatched, "IDE is compared");
    let stats = m.stats();
    assert_eq!((stats.rx_lost, stats.overrun_episodes), (2, 1));
}

#[test]
fn transmission_takes_the_lowest_identifier_then_the_lowest_buffer() {
    let mut can = started();
    can.write(Hth(0), 1, &std_frame(0x300, &[1])).unwrap();
    can.write(Hth(0), 2, &std_frame(0x200, &[2])).unwrap();
    can.write(Hth(1), 3, &std_frame(0x200, &[3])).unwrap();
    let order: Vec<_> = core::iter::from_fn(|| transmit(&can, None))
        .map(|f| f.bytes()[0])
        .collect();
    assert_eq!(order, [2, 3, 1]);
}

#[test]
fn an_abort_withdraws_a_waiting_frame_and_lets_the_one_on_the_wire_finish() {
    let mut can = started();
    can.write(Hth(0), 7, &std_frame(0x100, &[1])).unwrap();
    can.abort(Hth(0));
    assert_eq!(model(&can).offer(), None);
    assert_eq!(events(&mut can), []);
    assert_eq!(can.stats().tx_aborted, 1);
    assert_eq!(can.tx_slot(4), TxSlot::Free);
    // On the wire: a success is confirmed, a failure is withdrawn.
    for (failure, want) in [
        (None, vec![FlexcanEvent::TxConfirmation(8)]),
        (Some(Failure::Error), vec![]),
    ] {
        can.write(Hth(0), 8, &std_frame(0x100, &[2])).unwrap();
        let m = model(&can);
        let (mb, _) = m.offer().unwrap();
        m.begin_tx(mb);
        can.abort(Hth(0));
        model(&can).end_tx(failure);
        assert_eq!(events(&mut can), want);
        assert_eq!(model(&can).offer(), None);
    }
}

#[test]
fn a_bus_off_module_does_not_recover_by_itself() {
    let mut can = started();
    can.write(Hth(0), 1, &std_frame(0x100, &[1])).unwrap();
    for _ in 0..32 {
        transmit(&can, Some(Failure::Error)).unwrap();
    }
    assert_eq!(events(&mut can), [FlexcanEvent::BusOff]);
    // Out of freeze mode behind the driver's back: BOFFREC still holds the module.
    let regs = can.registers();
    regs.mcr().modify(MCR::HALT::CLEAR);
    assert!((0..10).any(|_| !regs.mcr().is_set(MCR::FRZACK)));
    model(&can).idle(RECOVERY_SEQUENCES * 2);
    assert!(model(&can).is_bus_off());
    // Negated after the 128 sequences: back at the next recessive sequence.
    regs.ctrl1().modify(CTRL1::BOFFREC::CLEAR);
    model(&can).idle(1);
    assert!(!model(&can).is_bus_off());
    assert_eq!(model(&can).stats().recoveries, 1);
}

#[test]
fn bus_off_waits_for_cansm_then_recovers_after_128_sequences() {
    let mut can = started();
    can.write(Hth(0), 1, &std_frame(0x100, &[1])).unwrap();
    for _ in 0..32 {
        transmit(&can, Some(Failure::Error)).unwrap();
    }
    assert!(model(&can).is_bus_off());
    assert_eq!(events(&mut can), [FlexcanEvent::BusOff]);
    assert_eq!(can.mode(), ControllerMode::Stopped);
    assert_eq!(can.error_counters().tec, 256);
    assert_eq!(can.write(Hth(0), 2, &std_frame(0x100, &[2])), Err(CanBusy));
    // CanSM's start allows one recovery.
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert!(
        can.registers().ctrl1().is_set(CTRL1::BOFFREC),
        "asserted again"
    );
    model(&can).idle(RECOVERY_SEQUENCES - 1);
    assert!(model(&can).is_bus_off());
    model(&can).idle(1);
    assert!(!model(&can).is_bus_off());
    assert_eq!(events(&mut can), [], "the withdrawn frame is not confirmed");
    assert_eq!(can.stats().tx_discarded, 1);
    assert_eq!(transmit(&can, None), None, "nor sent after the recovery");
    can.write(Hth(0), 3, &std_frame(0x100, &[3])).unwrap();
    assert!(transmit(&can, None).is_some());
    assert_eq!(events(&mut can), [FlexcanEvent::TxConfirmation(3)]);
    assert_eq!(model(&can).stats().ignored_writes, 0);
}

// ---- the driver ----

#[test]
fn the_papers_bit_timing_is_16_quanta_at_87_5_percent() {
    let t = ctrl1_timing(8_000_000, 500_000, 875).unwrap();
    assert_eq!(
        t,
        Ctrl1Timing {
            presdiv: 0,
            propseg: 5,
            pseg1: 6,
            pseg2: 1,
            rjw: 1
        }
    );
    let timing = t.timing();
    assert_eq!(timing.quanta(), 16);
    assert_eq!(timing.sample_permille(), 875);
}

#[test]
fn bit_timing_is_exact_at_every_usual_rate_from_every_board_clock() {
    // S32K144: SOSC 8 MHz, SYS_CLK 80 MHz, 48 MHz; MPC5748G: FXOSC 40 MHz, 16 MHz IRC.
    for clock in [8_000_000, 16_000_000, 40_000_000, 48_000_000, 80_000_000] {
        for rate in [125_000, 250_000, 500_000, 1_000_000] {
            let sample = bittiming::cia_sample_permille(rate);
            let t = ctrl1_timing(clock, rate, sample).unwrap();
            let timing = t.timing();
            assert!(timing.fits(&FLEXCAN), "{clock} {rate}: {timing:?}");
            assert_eq!(timing.bitrate(clock), Some(rate));
            assert_eq!(
                timing.sample_permille(),
                u32::from(sample),
                "{clock} {rate}"
            );
            assert!(t.rjw <= t.pseg1.min(t.pseg2));
        }
    }
    assert_eq!(
        ctrl1_timing(8_000_000, 33_333, 875),
        Err(bittiming::Unreachable {
            clock_hz: 8_000_000,
            bitrate: 33_333
        })
    );
}

#[test]
fn init_configures_the_frozen_module_without_an_ignored_write() {
    let mut can = Flexcan::new(FlexcanModel::new(), &CONFIG).unwrap();
    can.init(&BITRATE).unwrap();
    let regs = can.registers();
    let mcr = regs.mcr().extract();
    assert!(mcr.is_set(MCR::FRZACK));
    assert!(mcr.is_set(MCR::AEN) && mcr.is_set(MCR::IRMQ) && mcr.is_set(MCR::SRXDIS));
    assert!(!mcr.is_set(MCR::RFEN) && !mcr.is_set(MCR::WAK_MSK) && !mcr.is_set(MCR::SLF_WAK));
    assert_eq!(mcr.read(MCR::MAXMB), 6, "reserved + 3 receive + 3 transmit");
    assert!(regs.ctrl1().is_set(CTRL1::BOFFREC));
    assert!(regs.ctrl1().is_set(CTRL1::BOFFMSK));
    let codes: Vec<_> = (0..7).map(|mb| regs.mb_cs(mb).read(MB_CS::CODE)).collect();
    assert_eq!(
        codes,
        [0b1000, 0b0100, 0b0100, 0b0100, 0b1000, 0b1000, 0b1000]
    );
    assert_eq!(regs.imask1().get(), 0b111_1110);
    assert_eq!(model(&can).stats().ignored_writes, 0);
    assert_eq!(can.mode(), ControllerMode::Stopped);
    assert_eq!(
        can.write(Hth(0), 0, &std_frame(1, &[])),
        Err(CanBusy),
        "stopped"
    );
}

/// The model with every written offset noted.
struct Noted {
    model: FlexcanModel,
    written: core::cell::RefCell<std::collections::BTreeSet<usize>>,
}

impl Access for Noted {
    fn read(&self, off: usize) -> u32 {
        self.model.read(off)
    }
    fn write(&self, off: usize, value: u32) {
        self.written.borrow_mut().insert(off);
        self.model.write(off, value);
    }
}

/// `Can_Init` writes every word of every buffer the module has, and every buffer's
/// individual mask, the unused ones too (the RAM has ECC: a word never written can read
/// as an uncorrectable error), all in freeze mode (no write ignored).
#[test]
fn init_writes_all_of_the_buffers_ram() {
    let noted = Noted {
        model: FlexcanModel::new(),
        written: Default::default(),
    };
    let mut can = Flexcan::new(noted, &CONFIG).unwrap();
    can.init(&BITRATE).unwrap();
    let written = can.registers().access().written.borrow().clone();
    let mailboxes = usize::from(CONFIG.mailboxes);
    for mb in 0..mailboxes {
        for word in 0..4 {
            let off = super::regs::offset::MB0 + super::regs::offset::MB_STRIDE * mb + 4 * word;
            assert!(written.contains(&off), "buffer {mb}, word {word}");
        }
        assert!(
            written.contains(&(super::regs::offset::RXIMR0 + 4 * mb)),
            "buffer {mb}'s mask"
        );
    }
    assert_eq!(can.registers().access().model.stats().ignored_writes, 0);
}

/// Registers that are plain memory: nothing ever acknowledges.
struct Dead([Cell<u32>; 1024]);

impl Access for Dead {
    fn read(&self, off: usize) -> u32 {
        self.0.get(off / 4).map_or(0, Cell::get)
    }
    fn write(&self, off: usize, value: u32) {
        if let Some(c) = self.0.get(off / 4) {
            c.set(value);
        }
    }
}

#[test]
fn init_gives_up_on_a_module_that_does_not_acknowledge() {
    let dead = Dead(core::array::from_fn(|_| Cell::new(0)));
    let few = FlexcanConfig {
        init_polls: 100,
        ..CONFIG
    };
    let mut can = Flexcan::new(dead, &few).unwrap();
    assert_eq!(
        can.init_checked(&BITRATE),
        Err(FlexcanError::NoAcknowledge(driver::Acknowledge::Disabled))
    );
    let mut can = Flexcan::new(FlexcanModel::new(), &CONFIG).unwrap();
    let refused = ControllerConfig {
        bitrate: 33_333,
        sample_permille: 875,
    };
    assert!(matches!(
        can.init_checked(&refused),
        Err(FlexcanError::Timing(_))
    ));
    assert_eq!(model(&can).phase(), Phase::Disabled, "nothing touched");
}

#[test]
fn a_written_frame_goes_out_byte_for_byte_with_err005829_applied() {
    let mut can = started();
    let frame = std_frame(0x321, &[1, 2, 3, 4, 5, 6, 7]);
    let before = model(&can).stats().reserved_inactive_writes;
    can.write(Hth(0), 42, &frame).unwrap();
    assert_eq!(model(&can).stats().reserved_inactive_writes, before + 2);
    assert_eq!(transmit(&can, None), Some(frame));
    assert_eq!(events(&mut can), [FlexcanEvent::TxConfirmation(42)]);
    let ext = CanFrame::from_parts(CanId::masked(0x1234_5678, true), &[9]).unwrap();
    can.write(Hth(1), 43, &ext).unwrap();
    assert_eq!(transmit(&can, None), Some(ext));
    assert_eq!(model(&can).stats().reserved_inactive_writes, before + 4);
}

#[test]
fn an_hth_takes_as_many_frames_as_it_has_buffers() {
    let mut can = started();
    for pdu in 0..2 {
        can.write(Hth(0), pdu, &std_frame(0x100, &[])).unwrap();
    }
    assert_eq!(can.write(Hth(0), 2, &std_frame(0x100, &[])), Err(CanBusy));
    assert_eq!(
        can.write(Hth(2), 2, &std_frame(0x100, &[])),
        Err(CanBusy),
        "no such HTH"
    );
    transmit(&can, None).unwrap();
    assert_eq!(
        can.write(Hth(0), 2, &std_frame(0x100, &[])),
        Err(CanBusy),
        "flag not serviced"
    );
    assert_eq!(events(&mut can).len(), 1);
    can.write(Hth(0), 2, &std_frame(0x100, &[])).unwrap();
}

#[test]
fn received_frames_go_to_their_filters_receive_handle() {
    let mut can = started();
    let m = model(&can);
    let exact = std_frame(0x123, &[0xA, 0xB, 0xC, 0xD, 0xE]);
    let ext =
        CanFrame::from_parts(CanId::masked(0x001A_BCDE, true), &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
    let other = std_frame(0x124, &[]);
    m.receive(&exact);
    m.receive(&ext);
    m.receive(&other);
    assert_eq!(
        events(&mut can),
        [
            FlexcanEvent::Received(Hrh(0), exact),
            FlexcanEvent::Received(Hrh(1), ext),
            FlexcanEvent::Received(Hrh(2), other),
        ]
    );
    assert_eq!(model(&can).locked(), None, "every buffer unlocked");
}

#[test]
fn an_overrun_is_counted_and_the_newest_frame_reported() {
    let mut can = started();
    let m = model(&can);
    for b in 1..=4 {
        m.receive(&std_frame(0x123, &[b]));
    }
    let got: Vec<_> = events(&mut can)
        .into_iter()
        .map(|e| match e {
            FlexcanEvent::Received(hrh, f) => (hrh, f.bytes()[0]),
            other => panic!("{other:?}"),
        })
        .collect();
    // 1 in its exact buffer, 2 queued into the catch-all, 3 overwritten there by 4.
    assert_eq!(got, [(Hrh(0), 1), (Hrh(2), 4)]);
    assert_eq!(can.stats().rx_overruns, 1);
    assert_eq!(model(&can).stats().rx_lost, 2);
}

#[test]
fn a_stop_during_a_frame_is_pending_until_its_end() {
    let mut can = started();
    model(&can).begin_rx();
    assert_eq!(
        can.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    assert_eq!(can.take_event(), None);
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Err(ModeRefused)
    );
    let frame = std_frame(0x123, &[1]);
    model(&can).end_rx(&frame);
    assert_eq!(
        events(&mut can),
        [
            FlexcanEvent::ModeIndication(ControllerMode::Stopped),
            FlexcanEvent::Received(Hrh(0), frame)
        ]
    );
    assert_eq!(can.mode(), ControllerMode::Stopped);
}

#[test]
fn a_stop_withdraws_waiting_frames_without_confirmation() {
    let mut can = started();
    can.write(Hth(0), 1, &std_frame(0x100, &[1])).unwrap();
    can.write(Hth(1), 2, &std_frame(0x101, &[2])).unwrap();
    let m = model(&can);
    let (mb, _) = m.offer().unwrap();
    m.begin_tx(mb);
    assert_eq!(
        can.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    model(&can).end_tx(None);
    assert_eq!(
        events(&mut can),
        [FlexcanEvent::ModeIndication(ControllerMode::Stopped)]
    );
    assert_eq!(can.stats().tx_discarded, 2);
    assert_eq!(can.stats().tx_confirmed, 0);
}

#[test]
fn sleep_is_the_disabled_module_woken_by_software() {
    let mut can = started();
    assert_eq!(
        can.set_controller_mode(ControllerMode::Sleep),
        Err(ModeRefused)
    );
    can.set_controller_mode(ControllerMode::Stopped).unwrap();
    assert_eq!(
        can.set_controller_mode(ControllerMode::Sleep),
        Ok(ModeChange::Reached)
    );
    assert_eq!(model(&can).phase(), Phase::Disabled);
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Err(ModeRefused)
    );
    assert_eq!(
        can.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(model(&can).stats().ignored_writes, 0);
}

#[test]
fn layouts_that_do_not_fit_are_refused_by_name() {
    let filters = [RxFilter::any(Hrh(0), false); 20];
    let too_many = FlexcanConfig {
        rx: &filters,
        ..CONFIG
    };
    assert_eq!(
        Layout::new(&too_many).err(),
        Some(LayoutError::TooManyMailboxes {
            needed: 24,
            available: 16
        })
    );
    let empty = FlexcanConfig {
        tx: &[1, 0],
        ..CONFIG
    };
    assert_eq!(
        Layout::new(&empty).err(),
        Some(LayoutError::EmptyHth(Hth(1)))
    );
    assert_eq!(
        LayoutError::EmptyHth(Hth(1)).to_string(),
        "HTH 1 has no transmit buffer"
    );
}

#[test]
fn data_bytes_are_big_endian_in_each_word_on_any_core() {
    let words = data_words(&[1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(words, [0x0102_0304, 0x0506_0708]);
    assert_eq!(data_bytes(words), [1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(data_words(&[0xAB]), [0xAB00_0000, 0]);
}

#[test]
fn identifiers_sit_in_bits_28_to_18_or_28_to_0_of_their_word_and_read_back() {
    use super::regs::{id_of, id_word};
    assert_eq!(id_word(0x7FF, false), 0x7FF << 18);
    assert_eq!(id_word(0x1FFF_FFFF, true), 0x1FFF_FFFF);
    assert_eq!(
        id_word(0xFFFF_FFFF, false),
        0x7FF << 18,
        "masked to 11 bits"
    );
    for (raw, extended) in [
        (0x123, false),
        (0x7FF, false),
        (0x001A_BCDE, true),
        (0, true),
    ] {
        let id = CanId::masked(raw, extended);
        assert_eq!(id_of(id_word(raw, extended), extended), id);
    }
}

#[test]
fn mmio_reaches_the_words_at_their_offsets() {
    let mut block = [0u32; 0x900 / 4];
    // SAFETY: `block` is a FlexCAN-sized block of words this test alone uses.
    let mmio = unsafe { Mmio::new(block.as_mut_ptr().cast()) };
    let regs = Registers::new(mmio);
    regs.mcr().set(0x1234);
    regs.mb_data(2, 1).set(0xCAFE);
    regs.rximr(3).set(7);
    assert_eq!(block[0], 0x1234);
    assert_eq!(
        block[(offset::MB0 + 2 * offset::MB_STRIDE + 12) / 4],
        0xCAFE
    );
    assert_eq!(block[(offset::RXIMR0 + 12) / 4], 7);
}

// ---- the contract ----

#[test]
fn directed_sequences_keep_the_promises() {
    let w = |hth, id| Op::Write {
        hth,
        id,
        extended: false,
        len: 2,
    };
    let rx = Op::Receive {
        id: 0x123,
        extended: false,
        len: 1,
    };
    let cases: [&[Op]; 5] = [
        &[
            w(0, 1),
            w(0, 2),
            w(1, 3),
            Op::Transmit(Some(true)),
            Op::Drain,
            Op::Transmit(Some(true)),
        ],
        &[
            w(0, 1),
            Op::Transmit(None),
            Op::Abort(0),
            Op::EndTx(true),
            Op::Drain,
        ],
        &[rx, rx, rx, rx, Op::TakeOne, rx, Op::Drain],
        &[
            w(0, 5),
            Op::Transmit(None),
            Op::Mode(ControllerMode::Stopped),
            Op::EndTx(false),
            Op::Drain,
            Op::Mode(ControllerMode::Started),
            w(0, 6),
            Op::Transmit(Some(true)),
            Op::Drain,
        ],
        &[w(0, 9); 3],
    ];
    for ops in cases {
        assert!(spec::mailboxes_keep_their_promises(ops), "{ops:?}");
    }
    let mut bus_off = vec![w(0, 7)];
    bus_off.extend([Op::Transmit(Some(false)); 32]);
    bus_off.extend([
        Op::Drain,
        Op::Mode(ControllerMode::Started),
        Op::Idle(200),
        w(0, 8),
        Op::Transmit(Some(true)),
        Op::Drain,
    ]);
    assert!(spec::mailboxes_keep_their_promises(&bus_off));
}

/// Kani: every sequence of six steps keeps the message-buffer promises (the bolero test
/// below covers longer ones; the `flexcan_mailboxes` fuzz target runs the same contract
/// under libFuzzer).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(70))]
fn every_short_sequence_keeps_the_promises() {
    bolero::check!().with_type::<[u8; 18]>().for_each(|bytes| {
        let mut ops = [Op::Drain; 6];
        for (slot, op) in ops.iter_mut().zip(spec::decode(bytes)) {
            *slot = op;
        }
        assert!(spec::mailboxes_keep_their_promises(&ops));
    });
}

#[test]
fn any_sequence_keeps_the_promises() {
    bolero::check!().with_type::<Vec<u8>>().for_each(|bytes| {
        let ops: Vec<Op> = spec::decode(bytes).collect();
        assert!(spec::mailboxes_keep_their_promises(&ops), "{ops:?}");
    });
}
