//! Instruction-count probes of the communication stack, per layer (the paper's Figure 10),
//! with the ECU's own configuration (`cw_firmware::config`). Run by `cargo xtask callgrind`.
//!
//! Usage: `stack_probe <op> <iterations>`; each op calls `probe_<op>` that many times.
//! Transmit: SWC write -> RTE -> CanTranslate -> Com_SendSignal (pack) -> PduR -> CanIf
//! -> Can_Write (frame in the mailbox). Receive: mailbox -> CanIf (lookup, HRH and DLC
//! checks) -> PduR -> Com (copy into the I-PDU) -> Com_ReceiveSignal (unpack). Each layer
//! is also probed alone, so its share is the difference between neighbours.

use cw_core::can::{
    CanBusy, CanDriver, CanFrame, ControllerMode, Hrh, Hth, ModeChange, ModeRefused,
};
use cw_core::canif::{CanIf, PduMode, RxPduId, TxPduId};
use cw_core::com::ipdu::Com;
use cw_core::com::signal::SignalValue;
use cw_core::rte::LastIsBest;
use cw_core::warning::Measurement;
use cw_firmware::config;
use cw_firmware::rte::SonarDataInterface;
use std::hint::black_box;

/// A controller with one transmit mailbox, as registers would hold it.
#[derive(Default)]
struct Mailbox {
    frame: Option<CanFrame>,
}

impl CanDriver for Mailbox {
    fn init(
        &mut self,
        _: &cw_core::can::ControllerConfig,
    ) -> Result<(), cw_core::can::InitRefused> {
        self.frame = None;
        Ok(())
    }

    // A register model without a bus: no transmission fails.
    fn error_counters(&self) -> cw_core::can::ErrorCounters {
        cw_core::can::ErrorCounters::ACTIVE
    }

    fn abort(&mut self, _hth: Hth) {
        self.frame = None;
    }

    #[inline]
    fn write(&mut self, _hth: Hth, _pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        if self.frame.is_some() {
            return Err(CanBusy);
        }
        self.frame = Some(*frame);
        Ok(())
    }

    fn set_controller_mode(&mut self, _mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        Ok(ModeChange::Reached)
    }
}

struct Stack {
    rte: LastIsBest<SonarDataInterface>,
    com: config::EcuCom,
    canif: config::EcuCanIf,
    can: Mailbox,
}

/// `Com_SendSignal` of the distance down through PduR and CanIf to the mailbox.
#[inline(always)]
fn send_distance_down(s: &mut Stack, distance_mm: u32) {
    let (canif, can) = (&mut s.canif, &mut s.can);
    let _ = s.com.send_signal(
        config::SIG_DISTANCE,
        SignalValue::Unsigned(u64::from(distance_mm)),
        |ipdu, sdu| config::PDUR.com_transmit(canif, can, ipdu, sdu).is_ok(),
    );
}

#[inline(never)]
fn probe_tx_path(s: &mut Stack, distance_mm: u32) {
    // UltraSonic writes; CanTranslate takes it and sends the signal down to the mailbox.
    let _ = s.rte.write(Measurement::Distance { distance_mm });
    if let Ok(Measurement::Distance { distance_mm }) = s.rte.take() {
        send_distance_down(s, distance_mm);
    }
}

#[inline(never)]
fn probe_tx_com_down(s: &mut Stack, distance_mm: u32) {
    send_distance_down(s, distance_mm);
}

#[inline(never)]
fn probe_tx_com_only(s: &mut Stack, distance_mm: u32) {
    let _ = s.com.send_signal(
        config::SIG_DISTANCE,
        SignalValue::Unsigned(u64::from(distance_mm)),
        |_, sdu| {
            black_box(sdu);
            true
        },
    );
}

#[inline(never)]
fn probe_tx_pdur_down(s: &mut Stack, sdu: &[u8; 8]) {
    let _ = config::PDUR.com_transmit(&mut s.canif, &mut s.can, config::DISTANCE_IPDU, sdu);
}

#[inline(never)]
fn probe_tx_canif_down(s: &mut Stack, sdu: &[u8; 8]) {
    let _ = s.canif.transmit(&mut s.can, TxPduId(0), sdu);
}

#[inline(never)]
fn probe_tx_can(s: &mut Stack, frame: &CanFrame) {
    let _ = s.can.write(Hth(0), 0, frame);
}

#[inline(never)]
fn probe_rx_path(s: &mut Stack, frame: &CanFrame) -> u64 {
    if let Ok(pdu) = s.canif.rx_indication(Hrh(0), frame) {
        config::PDUR.canif_rx_indication(&mut s.com, pdu, frame.bytes());
    }
    match s.com.receive_signal(config::SIG_RED_BELOW) {
        Ok(SignalValue::Unsigned(v)) => v,
        _ => 0,
    }
}

#[inline(never)]
fn probe_rx_canif(s: &mut Stack, frame: &CanFrame) -> bool {
    s.canif.rx_indication(Hrh(0), frame).is_ok()
}

#[inline(never)]
fn probe_rx_pdur_com(s: &mut Stack, bytes: &[u8]) {
    config::PDUR.canif_rx_indication(&mut s.com, RxPduId(0), bytes);
}

#[inline(never)]
fn probe_rx_com_read(s: &mut Stack) -> u64 {
    match s.com.receive_signal(config::SIG_RED_BELOW) {
        Ok(SignalValue::Unsigned(v)) => v,
        _ => 0,
    }
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: stack_probe <op> <iterations>";
    let op = args.next().ok_or(usage)?;
    let n: u32 = args.next().and_then(|s| s.parse().ok()).ok_or(usage)?;
    let mut s = Stack {
        rte: LastIsBest::new(Measurement::Invalid, true),
        com: Com::new(config::ComTables),
        canif: CanIf::new(config::CanIfTables),
        can: Mailbox::default(),
    };
    s.canif
        .set_controller_mode(&mut s.can, ControllerMode::Started)
        .map_err(|_| "controller refused to start")?;
    s.canif.set_pdu_mode(PduMode::Online);
    let rx = CanFrame::from_parts(config::THRESHOLD_FRAME_ID, &[0xF4, 0x01, 0xE8, 0x03])
        .ok_or("rx frame")?;
    let tx = CanFrame::from_parts(config::DISTANCE_FRAME_ID, &[0xDC, 0x05, 0, 0, 2, 0, 0, 0])
        .ok_or("tx frame")?;
    let sdu = [0xDCu8, 0x05, 0, 0, 2, 0, 0, 0];
    let mut sink = 0u64;
    for i in 0..n {
        // Empty the mailbox (the frame left), outside the probes.
        s.can.frame = None;
        match op.as_str() {
            "tx_path" => probe_tx_path(&mut s, black_box(1000 + i % 500)),
            "tx_com_down" => probe_tx_com_down(&mut s, black_box(1000 + i % 500)),
            "tx_com_only" => probe_tx_com_only(&mut s, black_box(1000 + i % 500)),
            "tx_pdur_down" => probe_tx_pdur_down(&mut s, black_box(&sdu)),
            "tx_canif_down" => probe_tx_canif_down(&mut s, black_box(&sdu)),
            "tx_can" => probe_tx_can(&mut s, black_box(&tx)),
            "rx_path" => sink ^= probe_rx_path(&mut s, black_box(&rx)),
            "rx_canif" => sink ^= u64::from(probe_rx_canif(&mut s, black_box(&rx))),
            "rx_pdur_com" => probe_rx_pdur_com(&mut s, black_box(rx.bytes())),
            "rx_com_read" => sink ^= probe_rx_com_read(&mut s),
            other => return Err(format!("unknown op {other}")),
        }
    }
    println!(
        "{op} x{n}: sink {sink} mailbox {:?}",
        s.can.frame.map(|f| f.len())
    );
    Ok(())
}
