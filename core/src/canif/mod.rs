//! CAN Interface (AUTOSAR SWS CanIf): the layer between PduR and the CAN driver.
//!
//! - Transmit: `CanIf_Transmit` maps a TX L-PDU to its CAN id and hardware transmit handle
//!   (HTH) and calls `Can_Write`. When the mailbox is busy the PDU is kept in a one-deep
//!   buffer per L-PDU (the newest data wins) and sent from the transmit confirmation, highest
//!   priority (lowest id) first.
//! - Receive: `CanIf_RxIndication` finds the RX L-PDU of a frame by binary search over the
//!   ids (sorted at configuration time), checks the receive handle (HRH) and the DLC, and
//!   hands the PDU up. A frame with an unknown id, on the wrong HRH or too short is dropped
//!   and counted, and nothing else changes.
//! - Modes: the controller mode (`CanIf_SetControllerMode`, learned from the driver's
//!   `CanIf_ControllerModeIndication`, at once or later) and the PDU channel mode
//!   (`CanIf_SetPduMode`): offline, receive-only (TX offline) or online. Bus-off stops the
//!   controller and clears the transmit buffers.
//!
//! Configuration is a `const` [`CanIfConfig`], validated when it is built.

use crate::can::{
    CanBusy, CanDriver, CanFrame, CanId, ControllerMode, Hrh, Hth, ModeChange, ModeRefused,
};
use crate::tables::Tables;

/// A transmit L-PDU of CanIf.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TxPduId(pub u16);

/// A receive L-PDU of CanIf.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RxPduId(pub u16);

/// One transmit L-PDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TxPduConfig {
    /// Name, for messages and traces.
    pub name: &'static str,
    /// CAN identifier.
    pub id: CanId,
    /// Largest data length, bytes (0..=8).
    pub dlc: u8,
    /// The mailbox it is sent from.
    pub hth: Hth,
}

/// One receive L-PDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RxPduConfig {
    /// Name, for messages and traces.
    pub name: &'static str,
    /// CAN identifier.
    pub id: CanId,
    /// Configured data length: shorter frames fail the DLC check (bytes, 0..=8).
    pub dlc: u8,
    /// The mailbox it arrives in.
    pub hrh: Hrh,
}

/// A broken configuration rule, naming the table entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CanIfConfigError {
    /// More than 255 PDUs in a table.
    TooManyPdus,
    /// A transmit PDU's DLC is above 8.
    TxDlc {
        /// Index in the TX table.
        pdu: u16,
    },
    /// A receive PDU's DLC is above 8.
    RxDlc {
        /// Index in the RX table.
        pdu: u16,
    },
    /// Two receive PDUs share a CAN id.
    DuplicateRxId {
        /// Index of the second one in the RX table.
        pdu: u16,
    },
}

impl CanIfConfigError {
    /// A sentence describing the broken rule.
    pub const fn describe(&self) -> &'static str {
        match self {
            Self::TooManyPdus => "more than 255 CanIf PDUs in a table",
            Self::TxDlc { .. } => "a CanIf transmit PDU has a DLC above 8",
            Self::RxDlc { .. } => "a CanIf receive PDU has a DLC above 8",
            Self::DuplicateRxId { .. } => "two CanIf receive PDUs share a CAN id",
        }
    }
}

/// Validated CanIf configuration: `TX` transmit and `RX` receive L-PDUs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanIfConfig<const TX: usize, const RX: usize> {
    tx: [TxPduConfig; TX],
    rx: [RxPduConfig; RX],
    /// Derived: receive PDU ids, sorted.
    rx_keys: [u32; RX],
    /// Derived: the receive PDU index for each entry of `rx_keys`.
    rx_index: [u8; RX],
}

impl<const TX: usize, const RX: usize> CanIfConfig<TX, RX> {
    /// Validates the tables and sorts the receive ids for lookup.
    ///
    /// # Errors
    /// The first [`CanIfConfigError`] found.
    pub const fn new(
        tx: [TxPduConfig; TX],
        rx: [RxPduConfig; RX],
    ) -> Result<Self, CanIfConfigError> {
        Self::checked(tx, rx)
    }

    /// [`Self::new`]'s checks and lookup table. (A function of its own because
    /// cargo-mutants leaves functions named `new` alone: see `docs/src/mutants.md`.)
    const fn checked(
        tx: [TxPduConfig; TX],
        rx: [RxPduConfig; RX],
    ) -> Result<Self, CanIfConfigError> {
        if TX > 255 || RX > 255 {
            return Err(CanIfConfigError::TooManyPdus);
        }
        let mut i = 0;
        while i < TX {
            if tx[i].dlc > 8 {
                return Err(CanIfConfigError::TxDlc { pdu: i as u16 });
            }
            i += 1;
        }
        let mut rx_keys = [0u32; RX];
        let mut rx_index = [0u8; RX];
        let mut n = 0;
        while n < RX {
            if rx[n].dlc > 8 {
                return Err(CanIfConfigError::RxDlc { pdu: n as u16 });
            }
            // Insertion sort by id; equal ids are a configuration error.
            let key = rx[n].id.key();
            let mut at = n;
            while at > 0 && rx_keys[at - 1] > key {
                rx_keys[at] = rx_keys[at - 1];
                rx_index[at] = rx_index[at - 1];
                at -= 1;
            }
            if at > 0 && rx_keys[at - 1] == key {
                return Err(CanIfConfigError::DuplicateRxId { pdu: n as u16 });
            }
            rx_keys[at] = key;
            rx_index[at] = n as u8;
            n += 1;
        }
        Ok(Self {
            tx,
            rx,
            rx_keys,
            rx_index,
        })
    }

    /// The transmit table.
    pub const fn tx(&self) -> &[TxPduConfig; TX] {
        &self.tx
    }

    /// The receive table.
    pub const fn rx(&self) -> &[RxPduConfig; RX] {
        &self.rx
    }

    /// The receive PDU configured for `id`, by binary search.
    #[inline]
    pub fn rx_pdu_for(&self, id: CanId) -> Option<RxPduId> {
        let i = self.rx_keys.binary_search(&id.key()).ok()?;
        self.rx_index.get(i).map(|&p| RxPduId(u16::from(p)))
    }
}

/// The PDU channel mode (AUTOSAR `CanIf_PduModeType`, without the wake-up variants).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PduMode {
    /// Nothing is sent or received.
    Offline,
    /// Frames are received; transmit requests are refused.
    TxOffline,
    /// Frames are sent and received.
    Online,
}

/// Why `transmit` refused a PDU. Nothing was sent or buffered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TransmitError {
    /// No such transmit PDU.
    UnknownPdu,
    /// The controller is not started or the channel is not online.
    Offline,
    /// The data is longer than the PDU's configured DLC.
    TooLong,
}

/// Why a received frame was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RxDropped {
    /// The controller is not started or the channel is offline.
    Offline,
    /// No receive PDU has this CAN id.
    UnknownId,
    /// The frame arrived in a mailbox not configured for its PDU.
    WrongHrh,
    /// The frame is shorter than the PDU's configured DLC.
    WrongDlc,
}

/// Counters of everything CanIf dropped or deferred, for diagnostics and tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CanIfStats {
    /// Frames dropped: unknown id.
    pub rx_unknown_id: u32,
    /// Frames dropped: wrong receive handle.
    pub rx_wrong_hrh: u32,
    /// Frames dropped: DLC below the configured length.
    pub rx_wrong_dlc: u32,
    /// Frames dropped: received while offline.
    pub rx_offline: u32,
    /// Transmit requests buffered because the mailbox was busy.
    pub tx_buffered: u32,
    /// Buffered data replaced by newer data before it could be sent.
    pub tx_overwritten: u32,
    /// Buffered PDUs discarded by bus-off or a controller stop.
    pub tx_discarded: u32,
}

const EMPTY: u8 = u8::MAX;

/// The CanIf state for one controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanIf<const TX: usize, const RX: usize, C = &'static CanIfConfig<TX, RX>> {
    cfg: C,
    controller: ControllerMode,
    pdu_mode: PduMode,
    /// Per TX PDU: buffered data length, or `EMPTY`.
    buffered_len: [u8; TX],
    buffered_data: [[u8; 8]; TX],
    stats: CanIfStats,
}

impl<const TX: usize, const RX: usize, C: Tables<CanIfConfig<TX, RX>>> CanIf<TX, RX, C> {
    /// CanIf after `CanIf_Init`: controller stopped, channel offline, buffers empty.
    pub const fn new(cfg: C) -> Self {
        Self {
            cfg,
            controller: ControllerMode::Stopped,
            pdu_mode: PduMode::Offline,
            buffered_len: [EMPTY; TX],
            buffered_data: [[0; 8]; TX],
            stats: CanIfStats {
                rx_unknown_id: 0,
                rx_wrong_hrh: 0,
                rx_wrong_dlc: 0,
                rx_offline: 0,
                tx_buffered: 0,
                tx_overwritten: 0,
                tx_discarded: 0,
            },
        }
    }

    /// The configuration.
    #[inline(always)]
    pub fn config(&self) -> &'static CanIfConfig<TX, RX> {
        self.cfg.tables()
    }

    /// The controller mode as CanIf last set or learned it.
    pub const fn controller_mode(&self) -> ControllerMode {
        self.controller
    }

    /// The PDU channel mode.
    pub const fn pdu_mode(&self) -> PduMode {
        self.pdu_mode
    }

    /// Drop and deferral counters.
    pub const fn stats(&self) -> &CanIfStats {
        &self.stats
    }

    /// Whether a transmit PDU waits in its buffer.
    pub fn is_buffered(&self, pdu: TxPduId) -> bool {
        self.buffered_len
            .get(usize::from(pdu.0))
            .is_some_and(|&l| l != EMPTY)
    }

    /// `CanIf_SetControllerMode`: asks the driver for `mode`. A mode the controller
    /// reaches at once is indicated here ([`Self::controller_mode_indication`]); a pending
    /// one when the driver reports it. Until then CanIf keeps the mode it had.
    ///
    /// # Errors
    /// [`ModeRefused`] from the driver; the mode is unchanged then.
    pub fn set_controller_mode<D: CanDriver>(
        &mut self,
        driver: &mut D,
        mode: ControllerMode,
    ) -> Result<ModeChange, ModeRefused> {
        let change = driver.set_controller_mode(mode)?;
        if change == ModeChange::Reached {
            self.controller_mode_indication(mode);
        }
        Ok(change)
    }

    /// `CanIf_ControllerModeIndication`: the controller reached `mode`. Any mode but
    /// started discards the transmit buffers.
    pub fn controller_mode_indication(&mut self, mode: ControllerMode) {
        self.controller = mode;
        if mode != ControllerMode::Started {
            self.discard_buffers();
        }
    }

    /// `CanIf_SetPduMode`.
    pub fn set_pdu_mode(&mut self, mode: PduMode) {
        self.pdu_mode = mode;
        if mode != PduMode::Online {
            self.discard_buffers();
        }
    }

    /// `CanIf_ControllerBusOff`: the controller left the bus. CanIf marks it stopped and
    /// discards the transmit buffers; the caller tells CanSM, which decides on recovery.
    pub fn controller_bus_off(&mut self) {
        self.controller_mode_indication(ControllerMode::Stopped);
    }

    fn discard_buffers(&mut self) {
        for len in self.buffered_len.iter_mut() {
            if *len != EMPTY {
                *len = EMPTY;
                self.stats.tx_discarded = self.stats.tx_discarded.saturating_add(1);
            }
        }
    }

    /// `CanIf_Transmit`: sends `sdu` as transmit PDU `pdu`, or buffers it if the mailbox is
    /// busy (the newest data replaces older buffered data of the same PDU).
    ///
    /// # Errors
    /// [`TransmitError`]; nothing was sent or buffered then.
    #[inline]
    pub fn transmit<D: CanDriver>(
        &mut self,
        driver: &mut D,
        pdu: TxPduId,
        sdu: &[u8],
    ) -> Result<(), TransmitError> {
        let p = usize::from(pdu.0);
        let cfg = self.config().tx.get(p).ok_or(TransmitError::UnknownPdu)?;
        if self.controller != ControllerMode::Started || self.pdu_mode != PduMode::Online {
            return Err(TransmitError::Offline);
        }
        if sdu.len() > usize::from(cfg.dlc) {
            return Err(TransmitError::TooLong);
        }
        let frame = CanFrame::from_parts(cfg.id, sdu).ok_or(TransmitError::TooLong)?;
        match driver.write(cfg.hth, pdu.0, &frame) {
            Ok(()) => Ok(()),
            Err(CanBusy) => {
                self.buffer(p, sdu);
                Ok(())
            }
        }
    }

    fn buffer(&mut self, p: usize, sdu: &[u8]) {
        if self.buffered_len[p] != EMPTY {
            self.stats.tx_overwritten = self.stats.tx_overwritten.saturating_add(1);
        }
        self.stats.tx_buffered = self.stats.tx_buffered.saturating_add(1);
        let n = sdu.len().min(8);
        self.buffered_data[p][..n].copy_from_slice(&sdu[..n]);
        self.buffered_len[p] = n as u8;
    }

    /// `CanIf_TxConfirmation`: the driver sent the frame of `pdu`. A mailbox of its HTH is
    /// free again, so the highest-priority buffered PDU of that HTH goes out now. Returns
    /// the confirmed PDU for the upper layer (`None` for an unknown handle).
    ///
    /// No mode check is needed here: only `transmit` fills a buffer, and only with the
    /// controller started and the channel online, and every way out of that state
    /// (stopping, sleeping, bus-off, a PDU mode other than online) discards the buffers, so
    /// outside it there is nothing to send.
    pub fn tx_confirmation<D: CanDriver>(&mut self, driver: &mut D, pdu: u16) -> Option<TxPduId> {
        let hth = self.config().tx.get(usize::from(pdu))?.hth;
        self.flush(driver, hth);
        Some(TxPduId(pdu))
    }

    /// Sends the buffered PDU of `hth` with the lowest CAN id, if any (of two with the same
    /// id, the one configured first).
    fn flush<D: CanDriver>(&mut self, driver: &mut D, hth: Hth) {
        // The buffered PDU of `hth` with the lowest CAN id: (index, its id).
        let mut best: Option<(usize, CanId)> = None;
        for (p, cfg) in self.config().tx.iter().enumerate() {
            let buffered = self.buffered_len.get(p).is_some_and(|&n| n != EMPTY);
            if cfg.hth == hth && buffered && best.is_none_or(|(_, id)| cfg.id.key() < id.key()) {
                best = Some((p, cfg.id));
            }
        }
        let Some((p, id)) = best else { return };
        let len = self.buffered_len.get(p).map_or(0, |&n| usize::from(n));
        let Some(frame) = self
            .buffered_data
            .get(p)
            .and_then(|data| data.get(..len))
            .and_then(|data| CanFrame::from_parts(id, data))
        else {
            return;
        };
        if driver.write(hth, p as u16, &frame).is_ok() {
            self.buffered_len[p] = EMPTY;
        }
    }

    /// `CanIf_RxIndication`: a frame arrived in mailbox `hrh`. Returns the receive PDU it
    /// belongs to (its data is `frame.bytes()`), or why it was dropped (and counted).
    ///
    /// # Errors
    /// [`RxDropped`].
    #[inline]
    pub fn rx_indication(&mut self, hrh: Hrh, frame: &CanFrame) -> Result<RxPduId, RxDropped> {
        let verdict = self.check_rx(hrh, frame);
        if let Err(reason) = verdict {
            let counter = match reason {
                RxDropped::Offline => &mut self.stats.rx_offline,
                RxDropped::UnknownId => &mut self.stats.rx_unknown_id,
                RxDropped::WrongHrh => &mut self.stats.rx_wrong_hrh,
                RxDropped::WrongDlc => &mut self.stats.rx_wrong_dlc,
            };
            *counter = counter.saturating_add(1);
        }
        verdict
    }

    #[inline]
    fn check_rx(&self, hrh: Hrh, frame: &CanFrame) -> Result<RxPduId, RxDropped> {
        if self.controller != ControllerMode::Started || self.pdu_mode == PduMode::Offline {
            return Err(RxDropped::Offline);
        }
        let pdu = self
            .config()
            .rx_pdu_for(frame.can_id())
            .ok_or(RxDropped::UnknownId)?;
        let cfg = &self.config().rx[usize::from(pdu.0)];
        if cfg.hrh != hrh {
            return Err(RxDropped::WrongHrh);
        }
        if frame.len() < cfg.dlc {
            return Err(RxDropped::WrongDlc);
        }
        Ok(pdu)
    }
}

#[cfg(test)]
mod tests;
