//! Instruction-count probes of the communication stack, per layer (the paper's Figure 10),
//! with the ECU's own configuration ([`config`]): measured by callgrind on x86-64
//! (`cargo xtask callgrind`, through `firmware/examples/stack_probe.rs`) and by the
//! measuring image's trace on the Cortex-M4 (`cargo xtask qemu`, `cargo xtask eval`), the
//! same code on both.
//!
//! Transmit: SWC write -> RTE -> CanTranslate -> Com_SendSignal (pack) -> PduR -> CanIf
//! -> Can_Write (frame in the mailbox). Receive: mailbox -> CanIf (lookup, HRH and DLC
//! checks) -> PduR -> Com (copy into the I-PDU) -> Com_ReceiveSignal (unpack). Each layer
//! is also probed alone, so its share is the difference between neighbours. Each probe is
//! one function, `probe_<name>`, never inlined, that a measurement brackets: callgrind
//! collects inside it (`--toggle-collect`), the image's trace marks a span around its call.
//! The probes take no lock: they are the layers' own code (the ECU's paths with their
//! locks are measured in the ECU itself).

use cw_core::can::{
    CanBusy, CanDriver, CanFrame, ControllerMode, Hrh, Hth, ModeChange, ModeRefused,
};
use cw_core::canif::{CanIf, PduMode, RxPduId};
use cw_core::com::ipdu::Com;
use cw_core::com::signal::SignalValue;
use cw_core::rte::LastIsBest;
use cw_core::warning::Measurement;

use crate::config;
use crate::rte::SonarDataInterface;

/// The probes, by name (`probe_<name>`), with what one call does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Probe {
    /// SWC write -> RTE -> CanTranslate -> Com -> PduR -> CanIf -> mailbox.
    TxPath,
    /// `Com_SendSignal` -> PduR -> CanIf -> mailbox.
    TxComDown,
    /// `Com_SendSignal` alone (pack, transfer property, MDT).
    TxComOnly,
    /// `PduR_ComTransmit` -> CanIf -> mailbox. (PduR's static route adds no code to
    /// `CanIf_Transmit`'s: a probe from CanIf down would be the same function, which the
    /// linker folds into this one.)
    TxPdurDown,
    /// `Can_Write` alone (the frame into the mailbox).
    TxCan,
    /// Mailbox -> CanIf -> PduR -> Com -> `Com_ReceiveSignal`.
    RxPath,
    /// `CanIf_RxIndication` alone (lookup, HRH, DLC).
    RxCanif,
    /// `PduR_CanIfRxIndication` -> `Com_RxIndication`.
    RxPdurCom,
    /// `Com_ReceiveSignal` alone (unpack).
    RxComRead,
}

impl Probe {
    /// Every probe.
    pub const ALL: [Self; 9] = [
        Self::TxPath,
        Self::TxComDown,
        Self::TxComOnly,
        Self::TxPdurDown,
        Self::TxCan,
        Self::RxPath,
        Self::RxCanif,
        Self::RxPdurCom,
        Self::RxComRead,
    ];

    /// Its name: its function is `probe_<name>`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::TxPath => "tx_path",
            Self::TxComDown => "tx_com_down",
            Self::TxComOnly => "tx_com_only",
            Self::TxPdurDown => "tx_pdur_down",
            Self::TxCan => "tx_can",
            Self::RxPath => "rx_path",
            Self::RxCanif => "rx_canif",
            Self::RxPdurCom => "rx_pdur_com",
            Self::RxComRead => "rx_com_read",
        }
    }

    /// The probe named `name`.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// A controller with one transmit mailbox, as registers would hold it.
#[derive(Default)]
pub struct Mailbox {
    /// The frame written and not yet sent.
    pub frame: Option<CanFrame>,
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

/// The layers as the ECU links them, with the ECU's configuration, over [`Mailbox`].
pub struct Stack {
    rte: LastIsBest<SonarDataInterface>,
    com: config::EcuCom,
    canif: config::EcuCanIf,
    /// The controller.
    pub can: Mailbox,
}

/// `Com_SendSignal` of the distance down through PduR and CanIf to the mailbox.
#[inline(always)]
fn send_distance_down(s: &mut Stack, distance_mm: u32) {
    let (canif, can) = (&mut s.canif, &mut s.can);
    let _ = s.com.send_signal(
        config::com::DISTANCE,
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
        config::com::DISTANCE,
        SignalValue::Unsigned(u64::from(distance_mm)),
        |_, sdu| {
            core::hint::black_box(sdu);
            true
        },
    );
}

#[inline(never)]
fn probe_tx_pdur_down(s: &mut Stack, sdu: &[u8; 8]) {
    let _ = config::PDUR.com_transmit(&mut s.canif, &mut s.can, config::com::DISTANCE_FRAME, sdu);
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
    match s.com.receive_signal(config::com::RED_BELOW) {
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
    match s.com.receive_signal(config::com::RED_BELOW) {
        Ok(SignalValue::Unsigned(v)) => v,
        _ => 0,
    }
}

impl Stack {
    /// The stack started (controller started, PDUs online), its mailbox empty. About 0.9
    /// KiB, most of it Com's state: a Cortex-M image keeps it in a static (its task stack
    /// has no room for it).
    pub fn started() -> Result<Self, &'static str> {
        let mut s = Self {
            rte: LastIsBest::new(Measurement::Invalid, true),
            com: Com::new(config::ComTables),
            canif: CanIf::new(config::CanIfTables),
            can: Mailbox::default(),
        };
        s.canif
            .set_controller_mode(&mut s.can, ControllerMode::Started)
            .map_err(|_| "the probes' controller refused to start")?;
        s.canif.set_pdu_mode(PduMode::Online);
        Ok(s)
    }

    /// Call `i` of `probe`: its inputs made opaque to the compiler (as the ECU's own would
    /// be), then `around(true)`, the probe's function, `around(false)`. Returns what the probe
    /// read (receive probes), for the caller to keep.
    #[inline(always)]
    pub fn call(&mut self, probe: Probe, i: u32, mut around: impl FnMut(bool)) -> u64 {
        use core::hint::black_box;
        const RX: [u8; 4] = [0xF4, 0x01, 0xE8, 0x03];
        const SDU: [u8; 8] = [0xDC, 0x05, 0, 0, 2, 0, 0, 0];
        // Empty the mailbox (the frame left), outside the probe.
        self.can.frame = None;
        let distance = black_box(1000 + i % 500);
        let (Some(rx), Some(tx)) = (
            CanFrame::from_parts(config::canif::THRESHOLD_CONFIG_ID, &RX),
            CanFrame::from_parts(config::canif::DISTANCE_FRAME_ID, &SDU),
        ) else {
            return 0;
        };
        let (rx, tx, sdu) = (black_box(rx), black_box(tx), black_box(SDU));
        // The span brackets the probe's call alone (the choice of the probe before it),
        // as callgrind collects inside the probe's function alone.
        match probe {
            Probe::TxPath => {
                around(true);
                probe_tx_path(self, distance);
                around(false);
                0
            }
            Probe::TxComDown => {
                around(true);
                probe_tx_com_down(self, distance);
                around(false);
                0
            }
            Probe::TxComOnly => {
                around(true);
                probe_tx_com_only(self, distance);
                around(false);
                0
            }
            Probe::TxPdurDown => {
                around(true);
                probe_tx_pdur_down(self, &sdu);
                around(false);
                0
            }
            Probe::TxCan => {
                around(true);
                probe_tx_can(self, &tx);
                around(false);
                0
            }
            Probe::RxPath => {
                around(true);
                let read = probe_rx_path(self, &rx);
                around(false);
                read
            }
            Probe::RxCanif => {
                around(true);
                let read = probe_rx_canif(self, &rx);
                around(false);
                u64::from(read)
            }
            Probe::RxPdurCom => {
                around(true);
                probe_rx_pdur_com(self, rx.bytes());
                around(false);
                0
            }
            Probe::RxComRead => {
                around(true);
                let read = probe_rx_com_read(self);
                around(false);
                read
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_probe_is_named_once_and_found_by_its_name() {
        for p in Probe::ALL {
            assert_eq!(Probe::named(p.name()), Some(p));
        }
        assert_eq!(Probe::named("tx"), None);
    }

    #[test]
    fn the_transmit_probes_reach_the_mailbox_and_the_receive_path_reads_the_frame() {
        let mut s = Stack::started().unwrap();
        for p in [
            Probe::TxPath,
            Probe::TxComDown,
            Probe::TxPdurDown,
            Probe::TxCan,
        ] {
            let mut marks = 0;
            s.call(p, 0, |_| marks += 1);
            assert_eq!(marks, 2, "{p:?}");
            assert!(s.can.frame.is_some(), "{p:?} left no frame in the mailbox");
        }
        // RedBelow, the threshold frame's first signal: 0x01F4 = 500 mm.
        assert_eq!(s.call(Probe::RxPath, 0, |_| ()), 500);
        assert_eq!(s.call(Probe::RxComRead, 0, |_| ()), 500);
        assert_eq!(s.call(Probe::RxCanif, 0, |_| ()), 1);
    }
}
