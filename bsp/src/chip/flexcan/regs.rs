//! FlexCAN's registers: the bitfields, the register map and their typed view.
//!
//! Offsets and fields as NXP's reference manuals give them for the FlexCAN module of the
//! S32K1xx (S32K1XXRM, chapter "FlexCAN", section "Memory map and register definition")
//! and of the MPC5748G (MPC5748GRM, chapter "FlexCAN"). Only what the driver uses is
//! named; both chips lay these registers out alike.
//!
//! **The seam.** A driver reaches the module through [`Registers`], a typed view over
//! one [`Access`] ([`crate::chip::access`]): on silicon [`Mmio`] (volatile loads and
//! stores at the module's base), on the host the register-level model
//! ([`super::model::FlexcanModel`]), which reacts to each access as the module does (a
//! read of a mailbox's control word locks it, a write of one to a flag clears it). Each
//! register is a [`Reg`]: the driver reads and writes fields by name
//! (`mcr.is_set(MCR::FRZACK)`, `ctrl1.modify(CTRL1::BOFFREC::SET)`), never masks and
//! shifts, and the offsets live here alone.
//!
//! **Endianness.** Every access is one aligned 32-bit word, and FlexCAN keeps a frame's
//! data bytes big-endian within each of its two data words (byte 0 in bits 31..24) on
//! both chips, whatever the core's byte order (the S32K144's Cortex-M4 is little-endian,
//! the MPC5748G's e200 cores big-endian): [`data_words`] and [`data_bytes`] are the one
//! place that converts, on values, not on memory, so the same code is right on both
//! (its tests also run under Miri on s390x, a big-endian target).

use cw_core::can::CanId;
use tock_registers::RegisterLongName;

pub use crate::chip::access::{Access, Mmio, Reg};

pub use bits::{CTRL1, CTRL2, ECR, ESR1, MB_CS, MB_ID, MCR};
/// The traits that read and write a [`Reg`] (`tock-registers`' interfaces).
pub use tock_registers::interfaces;

/// The registers' bitfields (the macro's items carry the docs written here, not every
/// helper it generates).
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `MCR`, the module configuration register.
    pub MCR [
        /// Module disable (low-power mode).
        MDIS OFFSET(31) NUMBITS(1) [],
        /// Freeze enable: lets `HALT` (or debug) put the module in freeze mode.
        FRZ OFFSET(30) NUMBITS(1) [],
        /// The legacy receive FIFO (not used: mailbox mode).
        RFEN OFFSET(29) NUMBITS(1) [],
        /// Halt: requests freeze mode.
        HALT OFFSET(28) NUMBITS(1) [],
        /// Not ready: the module is disabled, frozen or stopped, not on the bus.
        NOTRDY OFFSET(27) NUMBITS(1) [],
        /// Wake-up interrupt mask.
        WAK_MSK OFFSET(26) NUMBITS(1) [],
        /// Soft reset: set by software, cleared by the module when the reset is done.
        SOFTRST OFFSET(25) NUMBITS(1) [],
        /// Freeze mode acknowledge.
        FRZACK OFFSET(24) NUMBITS(1) [],
        /// Supervisor mode: registers only in supervisor mode.
        SUPV OFFSET(23) NUMBITS(1) [],
        /// Self wake-up from low-power mode by bus activity.
        SLF_WAK OFFSET(22) NUMBITS(1) [],
        /// Warning interrupts (TWRNINT, RWRNINT) enable.
        WRNEN OFFSET(21) NUMBITS(1) [],
        /// Low-power mode acknowledge.
        LPMACK OFFSET(20) NUMBITS(1) [],
        /// Self reception disable: the module does not receive its own frames.
        SRXDIS OFFSET(17) NUMBITS(1) [],
        /// Individual receive masking (`RXIMR`) and queueing.
        IRMQ OFFSET(16) NUMBITS(1) [],
        /// Local priority enable.
        LPRIO_EN OFFSET(13) NUMBITS(1) [],
        /// Abort enable: a pending transmission is withdrawn by writing `ABORT`.
        AEN OFFSET(12) NUMBITS(1) [],
        /// The number of the last message buffer taking part in matching and arbitration.
        MAXMB OFFSET(0) NUMBITS(7) []
    ],
    /// `CTRL1`, control register 1: bit timing and error handling.
    pub CTRL1 [
        /// Prescaler division factor minus one.
        PRESDIV OFFSET(24) NUMBITS(8) [],
        /// Resynchronisation jump width minus one.
        RJW OFFSET(22) NUMBITS(2) [],
        /// Phase segment 1 minus one.
        PSEG1 OFFSET(19) NUMBITS(3) [],
        /// Phase segment 2 minus one.
        PSEG2 OFFSET(16) NUMBITS(3) [],
        /// Bus-off interrupt enable.
        BOFFMSK OFFSET(15) NUMBITS(1) [],
        /// Error interrupt enable.
        ERRMSK OFFSET(14) NUMBITS(1) [],
        /// Protocol engine clock: 0 the oscillator, 1 the peripheral clock.
        CLKSRC OFFSET(13) NUMBITS(1) [
            Oscillator = 0,
            PeripheralClock = 1
        ],
        /// Loop back.
        LPB OFFSET(12) NUMBITS(1) [],
        /// Transmit warning interrupt enable.
        TWRNMSK OFFSET(11) NUMBITS(1) [],
        /// Receive warning interrupt enable.
        RWRNMSK OFFSET(10) NUMBITS(1) [],
        /// Three samples per bit instead of one.
        SMP OFFSET(7) NUMBITS(1) [],
        /// Bus-off recovery disabled: the module stays bus-off until software negates it.
        BOFFREC OFFSET(6) NUMBITS(1) [],
        /// Timer synchronisation with mailbox 0.
        TSYN OFFSET(5) NUMBITS(1) [],
        /// Lowest buffer first (instead of lowest identifier first) for transmission.
        LBUF OFFSET(4) NUMBITS(1) [],
        /// Listen only.
        LOM OFFSET(3) NUMBITS(1) [],
        /// Propagation segment minus one.
        PROPSEG OFFSET(0) NUMBITS(3) []
    ],
    /// `CTRL2`, control register 2.
    pub CTRL2 [
        /// Error counters writable (in freeze mode).
        ECRWRE OFFSET(29) NUMBITS(1) [],
        /// Matching starts from the mailboxes (with the FIFO on).
        MRP OFFSET(18) NUMBITS(1) [],
        /// Remote request storing.
        RRS OFFSET(17) NUMBITS(1) [],
        /// Entire frame arbitration field comparison: IDE and RTR compared too.
        EACEN OFFSET(16) NUMBITS(1) []
    ],
    /// `ECR`, the error counters.
    pub ECR [
        /// Receive error counter.
        RXERRCNT OFFSET(8) NUMBITS(8) [],
        /// Transmit error counter.
        TXERRCNT OFFSET(0) NUMBITS(8) []
    ],
    /// `ESR1`, error and status register 1 (interrupt flags write-1-to-clear, error bits
    /// cleared by reading).
    pub ESR1 [
        /// Bus-off recovery done (write 1 to clear).
        BOFFDONEINT OFFSET(19) NUMBITS(1) [],
        /// The module is synchronised to the bus.
        SYNCH OFFSET(18) NUMBITS(1) [],
        /// Transmit warning interrupt (write 1 to clear).
        TWRNINT OFFSET(17) NUMBITS(1) [],
        /// Receive warning interrupt (write 1 to clear).
        RWRNINT OFFSET(16) NUMBITS(1) [],
        /// A recessive bit was sent and a dominant one seen.
        BIT1ERR OFFSET(15) NUMBITS(1) [],
        /// A dominant bit was sent and a recessive one seen.
        BIT0ERR OFFSET(14) NUMBITS(1) [],
        /// No acknowledge.
        ACKERR OFFSET(13) NUMBITS(1) [],
        /// CRC error.
        CRCERR OFFSET(12) NUMBITS(1) [],
        /// Form error.
        FRMERR OFFSET(11) NUMBITS(1) [],
        /// Stuffing error.
        STFERR OFFSET(10) NUMBITS(1) [],
        /// Transmit error counter at 96 or more.
        TXWRN OFFSET(9) NUMBITS(1) [],
        /// Receive error counter at 96 or more.
        RXWRN OFFSET(8) NUMBITS(1) [],
        /// The bus is idle.
        IDLE OFFSET(7) NUMBITS(1) [],
        /// Transmitting.
        TX OFFSET(6) NUMBITS(1) [],
        /// Fault confinement state.
        FLTCONF OFFSET(4) NUMBITS(2) [
            Active = 0,
            Passive = 1,
            BusOff = 2,
            BusOffToo = 3
        ],
        /// Receiving.
        RX OFFSET(3) NUMBITS(1) [],
        /// Bus-off entered (write 1 to clear).
        BOFFINT OFFSET(2) NUMBITS(1) [],
        /// An error bit was set (write 1 to clear).
        ERRINT OFFSET(1) NUMBITS(1) [],
        /// Wake-up (write 1 to clear).
        WAKINT OFFSET(0) NUMBITS(1) []
    ],
    /// A message buffer's control and status word.
    pub MB_CS [
        /// The buffer's state (receive or transmit codes).
        CODE OFFSET(24) NUMBITS(4) [
            RxInactive = 0b0000,
            RxFull = 0b0010,
            RxEmpty = 0b0100,
            RxOverrun = 0b0110,
            TxInactive = 0b1000,
            TxAbort = 0b1001,
            TxData = 0b1100
        ],
        /// Substitute remote request (recessive, 1, in extended frames).
        SRR OFFSET(22) NUMBITS(1) [],
        /// Identifier extension: a 29-bit identifier.
        IDE OFFSET(21) NUMBITS(1) [],
        /// Remote transmission request.
        RTR OFFSET(20) NUMBITS(1) [],
        /// Data length code.
        DLC OFFSET(16) NUMBITS(4) [],
        /// The free-running timer when the frame was received or sent.
        TIME_STAMP OFFSET(0) NUMBITS(16) []
    ],
    /// A message buffer's identifier word.
    pub MB_ID [
        /// Local priority.
        PRIO OFFSET(29) NUMBITS(3) [],
        /// The 11-bit standard identifier.
        STD OFFSET(18) NUMBITS(11) [],
        /// The 29-bit extended identifier.
        EXT OFFSET(0) NUMBITS(29) []
    ]
    ];
}

/// The `BUSY` bit of a receive buffer's code: the module is moving a frame in.
pub const CODE_BUSY: u32 = 0b0001;

/// Register offsets from the module's base.
pub mod offset {
    /// `MCR`.
    pub const MCR: usize = 0x000;
    /// `CTRL1`.
    pub const CTRL1: usize = 0x004;
    /// `TIMER`, the free-running timer (a read unlocks a locked buffer).
    pub const TIMER: usize = 0x008;
    /// `RXMGMASK`, the legacy global receive mask.
    pub const RXMGMASK: usize = 0x010;
    /// `ECR`.
    pub const ECR: usize = 0x01C;
    /// `ESR1`.
    pub const ESR1: usize = 0x020;
    /// `IMASK1`, interrupt masks of buffers 0..=31.
    pub const IMASK1: usize = 0x028;
    /// `IFLAG1`, interrupt flags of buffers 0..=31 (write 1 to clear).
    pub const IFLAG1: usize = 0x030;
    /// `CTRL2`.
    pub const CTRL2: usize = 0x034;
    /// Message buffer 0; each buffer is four words (classic CAN, 8 data bytes).
    pub const MB0: usize = 0x080;
    /// Bytes per message buffer.
    pub const MB_STRIDE: usize = 0x10;
    /// `RXIMR0`, the individual receive mask of buffer 0 (with `MCR[IRMQ]`).
    pub const RXIMR0: usize = 0x880;
}

/// The buffers this driver and model address: those of `IFLAG1` (0..=31). Every FlexCAN
/// instance of both chips has at least 16 (S32K144: 32, 16, 16; MPC5748G: 96 each).
pub const MAX_MAILBOXES: usize = 32;

/// The module's registers over an access path.
pub struct Registers<A> {
    access: A,
}

impl<A: Access> Registers<A> {
    /// The registers reached through `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (the model, for a test that inspects it).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn reg<R: RegisterLongName>(&self, offset: usize) -> Reg<'_, A, R> {
        Reg::new(&self.access, offset)
    }

    /// `MCR`.
    pub fn mcr(&self) -> Reg<'_, A, MCR::Register> {
        self.reg(offset::MCR)
    }
    /// `CTRL1`.
    pub fn ctrl1(&self) -> Reg<'_, A, CTRL1::Register> {
        self.reg(offset::CTRL1)
    }
    /// `CTRL2`.
    pub fn ctrl2(&self) -> Reg<'_, A, CTRL2::Register> {
        self.reg(offset::CTRL2)
    }
    /// `TIMER`.
    pub fn timer(&self) -> Reg<'_, A, ()> {
        self.reg(offset::TIMER)
    }
    /// `RXMGMASK`.
    pub fn rxmgmask(&self) -> Reg<'_, A, ()> {
        self.reg(offset::RXMGMASK)
    }
    /// `ECR`.
    pub fn ecr(&self) -> Reg<'_, A, ECR::Register> {
        self.reg(offset::ECR)
    }
    /// `ESR1`.
    pub fn esr1(&self) -> Reg<'_, A, ESR1::Register> {
        self.reg(offset::ESR1)
    }
    /// `IMASK1`.
    pub fn imask1(&self) -> Reg<'_, A, ()> {
        self.reg(offset::IMASK1)
    }
    /// `IFLAG1`.
    pub fn iflag1(&self) -> Reg<'_, A, ()> {
        self.reg(offset::IFLAG1)
    }
    /// Message buffer `mb`'s control and status word.
    pub fn mb_cs(&self, mb: usize) -> Reg<'_, A, MB_CS::Register> {
        self.reg(mb_offset(mb))
    }
    /// Message buffer `mb`'s identifier word.
    pub fn mb_id(&self, mb: usize) -> Reg<'_, A, MB_ID::Register> {
        self.reg(mb_offset(mb) + 4)
    }
    /// Message buffer `mb`'s data word `word` (0: bytes 0..=3, 1: bytes 4..=7).
    pub fn mb_data(&self, mb: usize, word: usize) -> Reg<'_, A, ()> {
        self.reg(mb_offset(mb) + 8 + 4 * (word & 1))
    }
    /// `RXIMR<mb>`.
    pub fn rximr(&self, mb: usize) -> Reg<'_, A, ()> {
        self.reg(offset::RXIMR0 + 4 * (mb % MAX_MAILBOXES))
    }
}

/// The offset of buffer `mb` (taken modulo [`MAX_MAILBOXES`]: always inside the buffers).
const fn mb_offset(mb: usize) -> usize {
    offset::MB0 + offset::MB_STRIDE * (mb % MAX_MAILBOXES)
}

/// Where a register offset falls, for the model: `(buffer, word)` inside the buffers.
pub const fn mb_of(offset: usize) -> Option<(usize, usize)> {
    if offset < offset::MB0 || offset >= offset::MB0 + offset::MB_STRIDE * MAX_MAILBOXES {
        return None;
    }
    let rel = offset - offset::MB0;
    Some((rel / offset::MB_STRIDE, (rel % offset::MB_STRIDE) / 4))
}

/// An identifier's bits in a buffer's identifier word (or an individual mask): a standard
/// identifier in bits 28..18, an extended one in 28..0.
pub const fn id_word(raw: u32, extended: bool) -> u32 {
    if extended {
        raw & 0x1FFF_FFFF
    } else {
        (raw & 0x7FF) << 18
    }
}

/// The identifier an identifier word holds, of the kind `CS[IDE]` says.
pub const fn id_of(word: u32, extended: bool) -> CanId {
    if extended {
        CanId::masked(word & 0x1FFF_FFFF, true)
    } else {
        CanId::masked((word >> 18) & 0x7FF, false)
    }
}

/// A frame's data bytes as FlexCAN's two data words: byte 0 in bits 31..24 of word 0.
pub fn data_words(bytes: &[u8]) -> [u32; 2] {
    let mut padded = [0u8; 8];
    for (slot, &b) in padded.iter_mut().zip(bytes) {
        *slot = b;
    }
    let [a, b, c, d, e, f, g, h] = padded;
    [
        u32::from_be_bytes([a, b, c, d]),
        u32::from_be_bytes([e, f, g, h]),
    ]
}

/// The eight data bytes held in FlexCAN's two data words.
pub fn data_bytes(words: [u32; 2]) -> [u8; 8] {
    let [a, b, c, d] = words[0].to_be_bytes();
    let [e, f, g, h] = words[1].to_be_bytes();
    [a, b, c, d, e, f, g, h]
}
