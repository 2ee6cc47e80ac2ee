//! The FlexCAN driver: AUTOSAR's `Can` module for one FlexCAN controller in mailbox mode.
//!
//! # Message buffers
//!
//! The configuration ([`FlexcanConfig`]) becomes a fixed layout ([`Layout`]):
//!
//! - buffer 0 is reserved for erratum ERR005829 and never transmits;
//! - then one receive buffer per acceptance filter ([`RxFilter`], CanIf's hardware receive
//!   objects: an identifier and a mask, stored in the buffer's identifier word and in its
//!   individual mask `RXIMR`, with `MCR[IRMQ]` set), in the order given: the module's
//!   matching takes the first free buffer whose filter matches, so exact filters come
//!   before a catch-all;
//! - then the transmit buffers of each hardware transmit handle (HTH), in HTH order.
//!
//! The legacy receive FIFO is not used (`MCR[RFEN]` clear): mailbox mode keeps one frame
//! per buffer with its own flag and overrun code, and the errata published against the
//! FIFO (its DMA and its ID filter table) do not concern this driver.
//!
//! # Ownership of a transmit buffer
//!
//! A transmit buffer belongs to the driver while its slot is `Free`, and to the module
//! from `Can_Write`'s store of the `DATA` code until the driver has serviced the buffer's
//! flag (`IFLAG1`, write 1 to clear): only then is the slot free again. The code read then
//! says what happened (reference manual, "Transmit process" and "Transmission abort
//! mechanism", with `MCR[AEN]` set): `INACTIVE` the frame went out (a confirmation),
//! `ABORT` it was withdrawn before it started (none). A frame that had begun when the
//! abort was asked for completes with its confirmation.
//!
//! # Errata
//!
//! - **ERR005829** (FlexCAN may miss a transmission enabled at a particular moment of the
//!   arbitration): the first valid buffer (buffer 0) is reserved, and after each
//!   transmission is set up the driver writes the `INACTIVE` code to it twice
//!   ([`Flexcan::write`]), as NXP's workaround and the Linux and NXP SDK drivers do.
//!
//! # Bus-off
//!
//! `CTRL1[BOFFREC]` is set: the module does not recover by itself (ISO 11898-1 lets a
//! node rejoin only when its host allows; AUTOSAR gives that decision to CanSM). At
//! bus-off (`ESR1[BOFFINT]`) the driver stops: it freezes the module, withdraws the
//! pending frames without confirmation and reports [`FlexcanEvent::BusOff`]. The next
//! start negates `BOFFREC` and asserts it again, which lets the module complete the
//! recovery the bus demands (128 sequences of 11 recessive bits) once and only once.
//!
//! # Modes
//!
//! Stopped is freeze mode (`MCR[HALT]`, acknowledged by `MCR[FRZACK]`), started is normal
//! mode, sleep is the module disabled (`MCR[MDIS]`, acknowledged by `MCR[LPMACK]`), woken
//! by software only: the wake-up interrupt and self wake-up (`MCR[WAK_MSK]`,
//! `MCR[SLF_WAK]`) are left off. The module enters freeze mode only at the end of the
//! frame on the wire: a stop polls the acknowledge a few times ([`MODE_POLLS`]) and
//! otherwise answers [`ModeChange::Pending`]; [`Flexcan::take_event`] then reports the
//! mode once it is acknowledged (`Can_MainFunction_Mode`).

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use cw_core::can::bittiming::{self, BitTiming, Unreachable};
use cw_core::can::confinement::ErrorState;
use cw_core::can::{
    CanBusy, CanDriver, CanFrame, CanId, ControllerConfig, ControllerMode, ErrorCounters, Hrh, Hth,
    InitRefused, ModeChange, ModeRefused,
};

use super::regs::{
    data_bytes, data_words, id_of, id_word, Access, Registers, CODE_BUSY, CTRL1, ECR, ESR1,
    MAX_MAILBOXES, MB_CS, MCR,
};

/// Polls of an acknowledge bit before a mode change is reported [`ModeChange::Pending`].
pub const MODE_POLLS: u32 = 8;

/// Polls of an acknowledge bit during `Can_Init` before the module is declared not
/// answering, for a core of up to about 200 MHz: start-up may wait for the frame on the
/// wire (at 125 kbit/s a frame lasts up to about 1 ms) and one poll of `MCR` takes a few
/// bus clocks. A board passes its own in [`FlexcanConfig::init_polls`].
pub const INIT_POLLS: u32 = 100_000;

/// Reads of a receive buffer's control word while its code says `BUSY` (the module is
/// moving a frame in, which takes a few clocks).
pub const BUSY_POLLS: u32 = 16;

/// The clock of the module's protocol engine (`CTRL1[CLKSRC]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClockSource {
    /// The oscillator (S32K144: SOSCDIV2; MPC5748G: FXOSC).
    Oscillator,
    /// The peripheral (bus) clock.
    PeripheralClock,
}

/// One hardware receive object: frames whose identifier matches `id` in the bits of
/// `mask` go to `hrh`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RxFilter {
    /// CanIf's receive handle for this buffer.
    pub hrh: Hrh,
    /// The identifier (its kind, standard or extended, must match exactly).
    pub id: CanId,
    /// The identifier bits compared (1: must match), over the identifier's own width.
    pub mask: u32,
}

impl RxFilter {
    /// Exactly `id`.
    pub const fn exact(id: CanId, hrh: Hrh) -> Self {
        Self {
            hrh,
            id,
            mask: if id.is_extended() { 0x1FFF_FFFF } else { 0x7FF },
        }
    }

    /// Every identifier of one kind (a CanIf catch-all receive object).
    pub const fn any(hrh: Hrh, extended: bool) -> Self {
        Self {
            hrh,
            id: CanId::masked(0, extended),
            mask: 0,
        }
    }
}

/// A controller's configuration: clock, buffers, filters and transmit handles.
#[derive(Debug, Clone, Copy)]
pub struct FlexcanConfig<'a> {
    /// The protocol engine's clock source.
    pub clock_source: ClockSource,
    /// That clock's frequency, Hz.
    pub clock_hz: u32,
    /// The buffers the instance has (S32K144: 32 on FlexCAN0, 16 on FlexCAN1 and 2).
    pub mailboxes: u8,
    /// The receive filters, in matching order.
    pub rx: &'a [RxFilter],
    /// The transmit buffers of each HTH (`tx[h]` buffers for `Hth(h)`).
    pub tx: &'a [u8],
    /// Polls of an acknowledge bit during `Can_Init` ([`INIT_POLLS`] suits the chips
    /// here).
    pub init_polls: u32,
}

/// A configuration the buffers cannot hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutError {
    /// More buffers needed (the reserved one included) than the instance has, or than
    /// `IFLAG1` covers.
    TooManyMailboxes {
        /// Buffers the configuration needs.
        needed: usize,
        /// Buffers available.
        available: usize,
    },
    /// An HTH with no transmit buffer.
    EmptyHth(Hth),
}

impl core::fmt::Display for LayoutError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooManyMailboxes { needed, available } => write!(
                f,
                "the configuration needs {needed} message buffers, the controller has {available}"
            ),
            Self::EmptyHth(Hth(h)) => write!(f, "HTH {h} has no transmit buffer"),
        }
    }
}

/// What a buffer is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// Not used (outside `MAXMB`, or beyond the configuration).
    Unused,
    /// Buffer 0: ERR005829's reserved buffer.
    Reserved,
    /// A receive buffer of this filter.
    Rx(RxFilter),
    /// A transmit buffer of this HTH.
    Tx(Hth),
}

/// The buffers' roles, fixed by the configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    roles: [Role; MAX_MAILBOXES],
    /// The last buffer used (`MCR[MAXMB]`).
    last: usize,
    /// The buffers the module has (`FlexcanConfig::mailboxes`, at most [`MAX_MAILBOXES`]).
    mailboxes: usize,
}

impl Layout {
    /// The layout of `config`.
    ///
    /// # Errors
    /// [`LayoutError`] when the buffers cannot hold the configuration.
    pub fn new(config: &FlexcanConfig<'_>) -> Result<Self, LayoutError> {
        let available = usize::from(config.mailboxes).min(MAX_MAILBOXES);
        let tx_total: usize = config.tx.iter().map(|&n| usize::from(n)).sum();
        let needed = 1 + config.rx.len() + tx_total;
        if needed > available {
            return Err(LayoutError::TooManyMailboxes { needed, available });
        }
        let mut roles = [Role::Unused; MAX_MAILBOXES];
        let mut next = roles.iter_mut();
        if let Some(slot) = next.next() {
            *slot = Role::Reserved;
        }
        for (filter, slot) in config.rx.iter().zip(next.by_ref()) {
            *slot = Role::Rx(*filter);
        }
        for (h, &count) in config.tx.iter().enumerate() {
            let hth = Hth(u8::try_from(h).unwrap_or(u8::MAX));
            if count == 0 {
                return Err(LayoutError::EmptyHth(hth));
            }
            for slot in next.by_ref().take(usize::from(count)) {
                *slot = Role::Tx(hth);
            }
        }
        Ok(Self {
            roles,
            last: needed - 1,
            mailboxes: available,
        })
    }

    /// Buffer `mb`'s role.
    pub fn role(&self, mb: usize) -> Role {
        self.roles.get(mb).copied().unwrap_or(Role::Unused)
    }

    /// The last buffer used.
    pub const fn last(&self) -> usize {
        self.last
    }

    /// The buffers whose flags the driver services: every receive and transmit buffer.
    pub fn serviced_mask(&self) -> u32 {
        self.roles
            .iter()
            .enumerate()
            .filter(|(_, r)| matches!(r, Role::Rx(_) | Role::Tx(_)))
            .fold(0, |m, (i, _)| m | (1 << i))
    }
}

/// `CTRL1`'s timing fields for one bit timing (each field holds its value minus one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Ctrl1Timing {
    /// `PRESDIV`.
    pub presdiv: u32,
    /// `PROPSEG`.
    pub propseg: u32,
    /// `PSEG1`.
    pub pseg1: u32,
    /// `PSEG2`.
    pub pseg2: u32,
    /// `RJW`.
    pub rjw: u32,
}

impl Ctrl1Timing {
    /// The fields for `timing`: `tseg1` split into a propagation segment of half of it
    /// (rounded down) and a first phase segment of the rest, each 1..=8 quanta; the jump
    /// width no wider than either phase segment (ISO 11898-1). `None` when a field would
    /// leave its range.
    pub fn from_timing(timing: &BitTiming) -> Option<Self> {
        let tseg1 = u32::from(timing.tseg1);
        let tseg2 = u32::from(timing.tseg2);
        let propseg = (tseg1 / 2).clamp(tseg1.saturating_sub(8).max(1), 8);
        let pseg1 = tseg1.checked_sub(propseg)?;
        let sjw = u32::from(timing.sjw).min(pseg1).min(tseg2).min(4);
        let presdiv = u32::from(timing.prescaler);
        let fields_fit = (1..=8).contains(&propseg)
            && (1..=8).contains(&pseg1)
            && (2..=8).contains(&tseg2)
            && (1..=256).contains(&presdiv)
            && sjw >= 1;
        fields_fit.then(|| Self {
            presdiv: presdiv - 1,
            propseg: propseg - 1,
            pseg1: pseg1 - 1,
            pseg2: tseg2 - 1,
            rjw: sjw - 1,
        })
    }

    /// The bit timing these fields give.
    pub const fn timing(&self) -> BitTiming {
        BitTiming {
            prescaler: (self.presdiv + 1) as u16,
            tseg1: (self.propseg + 1 + self.pseg1 + 1) as u8,
            tseg2: (self.pseg2 + 1) as u8,
            sjw: (self.rjw + 1) as u8,
        }
    }
}

/// The `CTRL1` timing for `bitrate` with the sample point `sample_permille` from a
/// `clock_hz` protocol clock.
///
/// # Errors
/// [`Unreachable`] when no timing within FlexCAN's fields gives the bitrate exactly.
pub fn ctrl1_timing(
    clock_hz: u32,
    bitrate: u32,
    sample_permille: u16,
) -> Result<Ctrl1Timing, Unreachable> {
    let unreachable = Unreachable { clock_hz, bitrate };
    let timing = bittiming::find(clock_hz, bitrate, sample_permille, &bittiming::FLEXCAN)?;
    Ctrl1Timing::from_timing(&timing).ok_or(unreachable)
}

/// What the controller's interrupt sources report, for CanIf.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FlexcanEvent {
    /// The frame of this PDU was sent (`CanIf_TxConfirmation`).
    TxConfirmation(u16),
    /// A frame arrived through this receive handle (`CanIf_RxIndication`).
    Received(Hrh, CanFrame),
    /// The controller went bus-off and stopped (`CanIf_ControllerBusOff`).
    BusOff,
    /// A mode change that was pending is complete (`CanIf_ControllerModeIndication`).
    ModeIndication(ControllerMode),
}

/// Why `Can_Init` failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlexcanError {
    /// No bit timing gives the bitrate from the clock.
    Timing(Unreachable),
    /// The module did not acknowledge within [`FlexcanConfig::init_polls`] reads.
    NoAcknowledge(Acknowledge),
}

/// The acknowledge a bounded wait was for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Acknowledge {
    /// `MCR[LPMACK]` set (module disabled).
    Disabled,
    /// `MCR[LPMACK]` clear (module enabled).
    Enabled,
    /// `MCR[SOFTRST]` clear (soft reset done).
    SoftReset,
    /// `MCR[FRZACK]` set (freeze mode).
    Freeze,
}

/// What the driver counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FlexcanStats {
    /// Frames received and reported.
    pub rx_frames: u32,
    /// Receive buffers found overrun: at least one frame was lost in each.
    pub rx_overruns: u32,
    /// Remote frames received and dropped (this ECU uses none).
    pub rx_remote: u32,
    /// Frames confirmed sent.
    pub tx_confirmed: u32,
    /// Frames withdrawn by an abort before they started.
    pub tx_aborted: u32,
    /// Frames withdrawn by a stop or bus-off (whatever their end, no confirmation).
    pub tx_discarded: u32,
    /// Flags of buffers that held nothing to report.
    pub spurious_flags: u32,
    /// Reads of a receive buffer that found it `BUSY`.
    pub busy_reads: u32,
    /// Bus-off entries.
    pub bus_offs: u32,
}

/// A transmit buffer's owner and what its flag will mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TxSlot {
    /// The driver's: free for `Can_Write`.
    Free,
    /// The module's, sending the frame of this PDU.
    Sending(u16),
    /// The module's, asked to abort the frame of this PDU.
    Aborting(u16),
    /// The module's, withdrawn by a stop or bus-off: its end is not reported.
    Discarding,
}

/// A FlexCAN controller and its driver.
pub struct Flexcan<A> {
    regs: Registers<A>,
    clock_source: ClockSource,
    clock_hz: u32,
    init_polls: u32,
    layout: Layout,
    tx: [TxSlot; MAX_MAILBOXES],
    mode: ControllerMode,
    pending: Option<ControllerMode>,
    stats: FlexcanStats,
}

impl<A: Access> Flexcan<A> {
    /// The driver of the controller behind `access`, with `config`'s buffers. No register
    /// is touched before [`CanDriver::init`].
    ///
    /// # Errors
    /// [`LayoutError`] when the buffers cannot hold the configuration.
    pub fn new(access: A, config: &FlexcanConfig<'_>) -> Result<Self, LayoutError> {
        Ok(Self {
            regs: Registers::new(access),
            clock_source: config.clock_source,
            clock_hz: config.clock_hz,
            init_polls: config.init_polls,
            layout: Layout::new(config)?,
            tx: [TxSlot::Free; MAX_MAILBOXES],
            mode: ControllerMode::Stopped,
            pending: None,
            stats: FlexcanStats::default(),
        })
    }

    /// The registers (the model, for a test that inspects it).
    pub const fn registers(&self) -> &Registers<A> {
        &self.regs
    }

    /// The buffers' layout.
    pub const fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Buffer `mb`'s transmit slot.
    pub fn tx_slot(&self, mb: usize) -> TxSlot {
        self.tx.get(mb).copied().unwrap_or(TxSlot::Free)
    }

    /// The mode last reached.
    pub const fn mode(&self) -> ControllerMode {
        self.mode
    }

    /// The mode asked for and not yet reached.
    pub const fn pending_mode(&self) -> Option<ControllerMode> {
        self.pending
    }

    /// What the driver counted.
    pub const fn stats(&self) -> FlexcanStats {
        self.stats
    }

    /// `Can_Init` with the reason of a failure: the module enabled on its clock, soft
    /// reset, frozen, and configured for `config`'s bit timing and the layout's buffers;
    /// stopped (frozen) afterwards.
    ///
    /// # Errors
    /// [`FlexcanError`]: no bit timing, or the module did not acknowledge a step.
    pub fn init_checked(&mut self, config: &ControllerConfig) -> Result<(), FlexcanError> {
        let timing = ctrl1_timing(self.clock_hz, config.bitrate, config.sample_permille)
            .map_err(FlexcanError::Timing)?;
        let clksrc = match self.clock_source {
            ClockSource::Oscillator => CTRL1::CLKSRC::Oscillator,
            ClockSource::PeripheralClock => CTRL1::CLKSRC::PeripheralClock,
        };
        let mcr = self.regs.mcr();
        // The clock source may change only while the module is disabled.
        mcr.modify(MCR::MDIS::SET);
        self.wait(self.init_polls, Acknowledge::Disabled)?;
        self.regs.ctrl1().modify(clksrc);
        mcr.modify(MCR::MDIS::CLEAR);
        self.wait(self.init_polls, Acknowledge::Enabled)?;
        // A soft reset leaves the module frozen (MCR back to FRZ and HALT set) and the
        // flags, counters and masks cleared; the buffers and CTRL1 keep their contents.
        mcr.modify(MCR::SOFTRST::SET);
        self.wait(self.init_polls, Acknowledge::SoftReset)?;
        mcr.modify(MCR::FRZ::SET + MCR::HALT::SET);
        self.wait(self.init_polls, Acknowledge::Freeze)?;
        self.configure(&timing, clksrc);
        self.tx = [TxSlot::Free; MAX_MAILBOXES];
        self.mode = ControllerMode::Stopped;
        self.pending = None;
        Ok(())
    }

    /// The frozen module's configuration: MCR, CTRL1, the buffers and the interrupt
    /// masks.
    fn configure(
        &self,
        timing: &Ctrl1Timing,
        clksrc: tock_registers::fields::FieldValue<u32, CTRL1::Register>,
    ) {
        let last = self.layout.last;
        self.regs.mcr().modify(
            MCR::RFEN::CLEAR
                + MCR::WAK_MSK::CLEAR
                + MCR::SLF_WAK::CLEAR
                + MCR::WRNEN::CLEAR
                + MCR::SRXDIS::SET
                + MCR::IRMQ::SET
                + MCR::LPRIO_EN::CLEAR
                + MCR::AEN::SET
                + MCR::MAXMB.val(u32::try_from(last).unwrap_or(0)),
        );
        self.regs.ctrl1().write(
            CTRL1::PRESDIV.val(timing.presdiv)
                + CTRL1::RJW.val(timing.rjw)
                + CTRL1::PSEG1.val(timing.pseg1)
                + CTRL1::PSEG2.val(timing.pseg2)
                + CTRL1::PROPSEG.val(timing.propseg)
                + CTRL1::BOFFMSK::SET
                + CTRL1::BOFFREC::SET
                + clksrc,
        );
        for mb in 0..=last {
            let cs = self.regs.mb_cs(mb);
            cs.set(0);
            self.regs.mb_data(mb, 0).set(0);
            self.regs.mb_data(mb, 1).set(0);
            match self.layout.role(mb) {
                Role::Rx(filter) => {
                    let extended = filter.id.is_extended();
                    self.regs.mb_id(mb).set(id_word(filter.id.raw(), extended));
                    self.regs.rximr(mb).set(id_word(filter.mask, extended));
                    cs.write(
                        MB_CS::CODE::RxEmpty + MB_CS::IDE.val(u32::from(filter.id.is_extended())),
                    );
                }
                Role::Tx(_) | Role::Reserved => {
                    self.regs.mb_id(mb).set(0);
                    self.regs.rximr(mb).set(0);
                    cs.write(MB_CS::CODE::TxInactive);
                }
                Role::Unused => {}
            }
        }
        // The buffers past the last one used, and their masks, are written too: the
        // module's RAM has ECC, and the manual's initialisation writes all of it before
        // anything reads it (a word never written can read as an uncorrectable error).
        for mb in last + 1..self.layout.mailboxes {
            self.regs.mb_cs(mb).set(0);
            self.regs.mb_id(mb).set(0);
            self.regs.mb_data(mb, 0).set(0);
            self.regs.mb_data(mb, 1).set(0);
            self.regs.rximr(mb).set(0);
        }
        self.regs.iflag1().set(u32::MAX);
        self.regs.esr1().write(
            ESR1::BOFFINT::SET + ESR1::ERRINT::SET + ESR1::WAKINT::SET + ESR1::BOFFDONEINT::SET,
        );
        self.regs.imask1().set(self.layout.serviced_mask());
    }

    /// Polls `MCR` up to `polls` times for `ack`.
    fn wait(&self, polls: u32, ack: Acknowledge) -> Result<(), FlexcanError> {
        if self.poll(polls, ack) {
            Ok(())
        } else {
            Err(FlexcanError::NoAcknowledge(ack))
        }
    }

    fn poll(&self, polls: u32, ack: Acknowledge) -> bool {
        (0..polls).any(|_| self.acknowledged(ack))
    }

    fn acknowledged(&self, ack: Acknowledge) -> bool {
        let mcr = self.regs.mcr().extract();
        match ack {
            Acknowledge::Disabled => mcr.is_set(MCR::LPMACK),
            Acknowledge::Enabled => !mcr.is_set(MCR::LPMACK),
            Acknowledge::SoftReset => !mcr.is_set(MCR::SOFTRST),
            Acknowledge::Freeze => mcr.is_set(MCR::FRZACK),
        }
    }

    /// Whether the module is in `mode` (its acknowledge bits say so).
    fn in_mode(&self, mode: ControllerMode) -> bool {
        let mcr = self.regs.mcr().extract();
        match mode {
            ControllerMode::Started => !mcr.is_set(MCR::FRZACK) && !mcr.is_set(MCR::LPMACK),
            ControllerMode::Stopped => mcr.is_set(MCR::FRZACK) && !mcr.is_set(MCR::LPMACK),
            ControllerMode::Sleep => mcr.is_set(MCR::LPMACK),
        }
    }

    /// Withdraws every frame the module holds: no confirmation follows for any.
    fn discard_pending(&mut self) {
        for mb in 0..=self.layout.last {
            if let Some(slot) = self.tx.get_mut(mb) {
                match *slot {
                    TxSlot::Sending(_) => {
                        self.regs.mb_cs(mb).write(MB_CS::CODE::TxAbort);
                        *slot = TxSlot::Discarding;
                    }
                    TxSlot::Aborting(_) => *slot = TxSlot::Discarding,
                    TxSlot::Free | TxSlot::Discarding => {}
                }
            }
        }
    }

    /// Asks for `mode` and polls its acknowledge briefly.
    fn request(&mut self, mode: ControllerMode) -> ModeChange {
        match mode {
            ControllerMode::Stopped => {
                if self.mode == ControllerMode::Sleep {
                    self.regs.mcr().modify(MCR::MDIS::CLEAR);
                } else {
                    self.discard_pending();
                    self.regs.mcr().modify(MCR::FRZ::SET + MCR::HALT::SET);
                }
            }
            ControllerMode::Started => {
                if self.regs.esr1().read(ESR1::FLTCONF) >= 2 {
                    // Bus-off: negating BOFFREC lets this recovery run; asserting it again
                    // keeps the next bus-off for CanSM to decide.
                    let ctrl1 = self.regs.ctrl1();
                    ctrl1.modify(CTRL1::BOFFREC::CLEAR);
                    ctrl1.modify(CTRL1::BOFFREC::SET);
                }
                self.regs.mcr().modify(MCR::HALT::CLEAR);
            }
            ControllerMode::Sleep => self.regs.mcr().modify(MCR::MDIS::SET),
        }
        if (0..MODE_POLLS).any(|_| self.in_mode(mode)) {
            self.mode = mode;
            self.pending = None;
            ModeChange::Reached
        } else {
            self.pending = Some(mode);
            ModeChange::Pending
        }
    }

    /// The next thing the controller has to report, if any: a pending mode reached,
    /// bus-off, then the buffers' flags from buffer 0 up. The interrupt handler (and
    /// `Can_MainFunction_Mode`) call it until it returns `None`.
    pub fn take_event(&mut self) -> Option<FlexcanEvent> {
        if let Some(target) = self.pending {
            if self.in_mode(target) {
                self.mode = target;
                self.pending = None;
                return Some(FlexcanEvent::ModeIndication(target));
            }
        }
        let esr1 = self.regs.esr1().extract();
        if esr1.is_set(ESR1::BOFFDONEINT) {
            self.regs.esr1().write(ESR1::BOFFDONEINT::SET);
        }
        if esr1.is_set(ESR1::BOFFINT) {
            self.regs.esr1().write(ESR1::BOFFINT::SET);
            self.stats.bus_offs += 1;
            self.discard_pending();
            self.regs.mcr().modify(MCR::FRZ::SET + MCR::HALT::SET);
            self.mode = ControllerMode::Stopped;
            self.pending = None;
            return Some(FlexcanEvent::BusOff);
        }
        loop {
            let flags = self.regs.iflag1().get() & self.layout.serviced_mask();
            if flags == 0 {
                return None;
            }
            let mb = flags.trailing_zeros() as usize;
            let event = match self.layout.role(mb) {
                Role::Rx(filter) => self.service_rx(mb, filter.hrh),
                Role::Tx(_) => self.service_tx(mb),
                Role::Reserved | Role::Unused => {
                    self.regs.iflag1().set(1 << mb);
                    self.stats.spurious_flags += 1;
                    None
                }
            };
            if event.is_some() {
                return event;
            }
        }
    }

    /// Reads a full receive buffer: its control word (which locks it), identifier and
    /// data; clears its flag; reads the timer (which unlocks it).
    fn service_rx(&mut self, mb: usize, hrh: Hrh) -> Option<FlexcanEvent> {
        let cs_reg = self.regs.mb_cs(mb);
        let mut cs = cs_reg.extract();
        let mut polls = 0;
        while cs.read(MB_CS::CODE) & CODE_BUSY != 0 && polls < BUSY_POLLS {
            self.stats.busy_reads += 1;
            polls += 1;
            cs = cs_reg.extract();
        }
        let word = self.regs.mb_id(mb).get();
        let words = [
            self.regs.mb_data(mb, 0).get(),
            self.regs.mb_data(mb, 1).get(),
        ];
        self.regs.iflag1().set(1 << mb);
        let _unlock = self.regs.timer().get();
        let code = cs.read_as_enum(MB_CS::CODE);
        match code {
            Some(MB_CS::CODE::Value::RxFull) => {}
            Some(MB_CS::CODE::Value::RxOverrun) => self.stats.rx_overruns += 1,
            _ => {
                self.stats.spurious_flags += 1;
                return None;
            }
        }
        if cs.is_set(MB_CS::RTR) {
            self.stats.rx_remote += 1;
            return None;
        }
        let id = id_of(word, cs.is_set(MB_CS::IDE));
        let len = u8::try_from(cs.read(MB_CS::DLC).min(8)).unwrap_or(8);
        self.stats.rx_frames += 1;
        Some(FlexcanEvent::Received(
            hrh,
            CanFrame::masked(id, len, data_bytes(words)),
        ))
    }

    /// Services a transmit buffer's flag: the code says whether the frame went out.
    fn service_tx(&mut self, mb: usize) -> Option<FlexcanEvent> {
        let code = self.regs.mb_cs(mb).read_as_enum(MB_CS::CODE);
        let slot = self.tx.get_mut(mb)?;
        self.regs.iflag1().set(1 << mb);
        let (now, event) = match (*slot, code) {
            (
                TxSlot::Sending(pdu) | TxSlot::Aborting(pdu),
                Some(MB_CS::CODE::Value::TxInactive),
            ) => {
                self.stats.tx_confirmed += 1;
                (TxSlot::Free, Some(FlexcanEvent::TxConfirmation(pdu)))
            }
            (TxSlot::Sending(_) | TxSlot::Aborting(_), Some(MB_CS::CODE::Value::TxAbort)) => {
                self.stats.tx_aborted += 1;
                (TxSlot::Free, None)
            }
            (
                TxSlot::Discarding,
                Some(MB_CS::CODE::Value::TxInactive | MB_CS::CODE::Value::TxAbort),
            ) => {
                self.stats.tx_discarded += 1;
                (TxSlot::Free, None)
            }
            // A flag with the buffer still busy (or never given to the module): nothing
            // to report, and the buffer keeps its owner.
            (other, _) => {
                self.stats.spurious_flags += 1;
                (other, None)
            }
        };
        *slot = now;
        event
    }
}

impl<A: Access> CanDriver for Flexcan<A> {
    fn init(&mut self, config: &ControllerConfig) -> Result<(), InitRefused> {
        self.init_checked(config).map_err(|_| InitRefused {
            bitrate: config.bitrate,
        })
    }

    fn write(&mut self, hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        if self.mode != ControllerMode::Started || self.pending.is_some() {
            return Err(CanBusy);
        }
        let layout = &self.layout;
        let mb = (0..=layout.last)
            .find(|&mb| layout.role(mb) == Role::Tx(hth) && self.tx.get(mb) == Some(&TxSlot::Free))
            .ok_or(CanBusy)?;
        let id = frame.can_id();
        let extended = id.is_extended();
        let cs = self.regs.mb_cs(mb);
        cs.write(MB_CS::CODE::TxInactive);
        self.regs.mb_id(mb).set(id_word(id.raw(), extended));
        let [w0, w1] = data_words(frame.bytes());
        self.regs.mb_data(mb, 0).set(w0);
        self.regs.mb_data(mb, 1).set(w1);
        cs.write(
            MB_CS::CODE::TxData
                + MB_CS::DLC.val(u32::from(frame.len()))
                + MB_CS::IDE.val(u32::from(extended))
                + MB_CS::SRR.val(u32::from(extended)),
        );
        // ERR005829: INACTIVE written twice to the reserved first buffer after each
        // transmission is set up.
        let reserved = self.regs.mb_cs(0);
        reserved.write(MB_CS::CODE::TxInactive);
        reserved.write(MB_CS::CODE::TxInactive);
        if let Some(slot) = self.tx.get_mut(mb) {
            *slot = TxSlot::Sending(pdu);
        }
        Ok(())
    }

    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        if let Some(pending) = self.pending {
            return if pending == mode {
                Ok(ModeChange::Pending)
            } else {
                Err(ModeRefused)
            };
        }
        match (self.mode, mode) {
            (now, asked) if now == asked => Ok(ModeChange::Reached),
            (ControllerMode::Sleep, ControllerMode::Started)
            | (ControllerMode::Started, ControllerMode::Sleep) => Err(ModeRefused),
            (_, asked) => Ok(self.request(asked)),
        }
    }

    /// The counters of `ECR` and the state of `ESR1[FLTCONF]`. While bus-off the
    /// transmit counter no longer holds a count: 256 stands for it.
    fn error_counters(&self) -> ErrorCounters {
        let ecr = self.regs.ecr().extract();
        let state = match self.regs.esr1().read(ESR1::FLTCONF) {
            0 => ErrorState::Active,
            1 => ErrorState::Passive,
            _ => ErrorState::BusOff,
        };
        let tec = u16::try_from(ecr.read(ECR::TXERRCNT)).unwrap_or(u16::MAX);
        ErrorCounters {
            state,
            tec: if state == ErrorState::BusOff {
                256
            } else {
                tec
            },
            rec: u8::try_from(ecr.read(ECR::RXERRCNT)).unwrap_or(u8::MAX),
        }
    }

    fn abort(&mut self, hth: Hth) {
        for mb in 0..=self.layout.last {
            if self.layout.role(mb) != Role::Tx(hth) {
                continue;
            }
            if let Some(slot) = self.tx.get_mut(mb) {
                if let TxSlot::Sending(pdu) = *slot {
                    self.regs.mb_cs(mb).write(MB_CS::CODE::TxAbort);
                    *slot = TxSlot::Aborting(pdu);
                }
            }
        }
    }
}
