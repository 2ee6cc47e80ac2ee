//! The CAN driver interface as the communication stack sees it (AUTOSAR SWS Can:
//! `Can_Write`, `Can_SetControllerMode`, and the callbacks into CanIf). Boards implement
//! [`CanDriver`]; the stack never touches a controller otherwise.
//!
//! Frames are classic CAN (up to 8 data bytes) and implement [`embedded_can::Frame`], so
//! board crates and host tools share one vocabulary. [`CanId`] is a `const`-constructible
//! identifier for static configuration tables; it converts to and from
//! [`embedded_can::Id`].

pub mod bittiming;
pub mod confinement;
pub mod slcan;
pub mod text;
pub mod timing;

use embedded_can::{ExtendedId, Id, StandardId};

/// A CAN identifier usable in `const` tables: 11-bit standard or 29-bit extended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CanId {
    /// `raw | EXTENDED_FLAG` for extended ids: one number that orders and looks up both.
    key: u32,
}

const EXTENDED_FLAG: u32 = 1 << 31;

impl CanId {
    /// An 11-bit standard identifier, `None` above `0x7FF`.
    pub const fn standard(raw: u16) -> Option<Self> {
        if raw > 0x7FF {
            None
        } else {
            Some(Self { key: raw as u32 })
        }
    }

    /// A 29-bit extended identifier, `None` above `0x1FFF_FFFF`.
    pub const fn extended(raw: u32) -> Option<Self> {
        if raw > 0x1FFF_FFFF {
            None
        } else {
            Some(Self {
                key: raw | EXTENDED_FLAG,
            })
        }
    }

    /// Whether this is a 29-bit identifier.
    pub const fn is_extended(self) -> bool {
        self.key & EXTENDED_FLAG != 0
    }

    /// The identifier's numeric value (without the standard/extended distinction).
    pub const fn raw(self) -> u32 {
        self.key & !EXTENDED_FLAG
    }

    /// A single number that distinguishes standard from extended ids, for lookups.
    pub const fn key(self) -> u32 {
        self.key
    }

    /// The identifier's place in bitwise arbitration (ISO 11898-1): the lower key wins the
    /// bus. The 11-bit base identifier first, then a standard frame before an extended
    /// one with the same base (its dominant RTR meets the extended frame's recessive
    /// SRR), then the 18-bit extension.
    pub const fn arbitration_key(self) -> u32 {
        if self.is_extended() {
            let raw = self.raw();
            ((raw >> 18) << 19) | (1 << 18) | (raw & 0x3_FFFF)
        } else {
            self.raw() << 19
        }
    }

    /// The identifier `raw` names once masked to its width (11 or 29 bits): total, so
    /// that harnesses and generators can draw any identifier from plain integers.
    pub const fn masked(raw: u32, extended: bool) -> Self {
        if extended {
            Self {
                key: (raw & 0x1FFF_FFFF) | EXTENDED_FLAG,
            }
        } else {
            Self { key: raw & 0x7FF }
        }
    }
}

impl From<CanId> for Id {
    fn from(id: CanId) -> Self {
        if id.is_extended() {
            ExtendedId::new(id.raw()).map_or(Id::Extended(ExtendedId::MAX), Id::Extended)
        } else {
            StandardId::new(id.raw() as u16).map_or(Id::Standard(StandardId::MAX), Id::Standard)
        }
    }
}

impl From<Id> for CanId {
    fn from(id: Id) -> Self {
        match id {
            Id::Standard(s) => Self {
                key: u32::from(s.as_raw()),
            },
            Id::Extended(e) => Self {
                key: e.as_raw() | EXTENDED_FLAG,
            },
        }
    }
}

/// A classic CAN data frame: identifier, DLC 0..=8 and the data bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: CanId,
    dlc: u8,
    data: [u8; 8],
}

impl CanFrame {
    /// A data frame; `None` if `data` is longer than 8 bytes.
    pub fn from_parts(id: CanId, data: &[u8]) -> Option<Self> {
        if data.len() > 8 {
            return None;
        }
        let mut bytes = [0u8; 8];
        for (slot, &byte) in bytes.iter_mut().zip(data) {
            *slot = byte;
        }
        Some(Self {
            id,
            dlc: data.len() as u8,
            data: bytes,
        })
    }

    /// The frame with `id` and the first `len % 9` bytes of `data` (the rest zero, as
    /// `from_parts` leaves them): total, so that harnesses and generators can draw any
    /// frame from plain integers.
    pub const fn masked(id: CanId, len: u8, data: [u8; 8]) -> Self {
        let dlc = len % 9;
        let mut bytes = [0u8; 8];
        let mut i = 0;
        while i < dlc as usize {
            bytes[i] = data[i];
            i += 1;
        }
        Self {
            id,
            dlc,
            data: bytes,
        }
    }

    /// The identifier.
    pub const fn can_id(&self) -> CanId {
        self.id
    }

    /// The data length code (0..=8).
    pub const fn len(&self) -> u8 {
        self.dlc
    }

    /// Whether the frame carries no data.
    pub const fn is_empty(&self) -> bool {
        self.dlc == 0
    }

    /// The data bytes (`len()` of them).
    pub fn bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.dlc.min(8))]
    }
}

impl embedded_can::Frame for CanFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        Self::from_parts(CanId::from(id.into()), data)
    }

    /// Remote frames are not used by this ECU: always `None`.
    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }

    fn is_extended(&self) -> bool {
        self.id.is_extended()
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> Id {
        self.id.into()
    }

    fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    fn data(&self) -> &[u8] {
        self.bytes()
    }
}

/// A hardware transmit handle: one transmit mailbox (or group) of the controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Hth(pub u8);

/// A hardware receive handle: one receive mailbox (or filter group) of the controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Hrh(pub u8);

/// `Can_Write` found the mailbox occupied (`CAN_BUSY`): nothing was sent or lost, the
/// caller keeps the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanBusy;

/// Controller states (AUTOSAR `Can_ControllerStateType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ControllerMode {
    /// Not participating in the bus; mailboxes idle.
    Stopped,
    /// Participating in the bus.
    Started,
    /// Low power.
    Sleep,
}

/// A controller refused a mode change (e.g. sleep to started directly).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeRefused;

/// How a controller took a mode request it accepted (`Can_SetControllerMode` returned
/// `E_OK`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModeChange {
    /// The controller is in the mode now. No indication follows: the caller indicates it
    /// (`CanIf_ControllerModeIndication` from within `Can_SetControllerMode`).
    Reached,
    /// The controller gets there later and then reports the mode it reached as an event
    /// (`CanIf_ControllerModeIndication` from its interrupt or `Can_MainFunction_Mode`): a
    /// FlexCAN asked to stop enters freeze mode only once the frame on the wire has ended.
    Pending,
}

/// A controller's configuration (AUTOSAR `CanControllerBaudrateConfig`): the bitrate and
/// the sample point the driver turns into its bit timing ([`bittiming::find`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ControllerConfig {
    /// Bits per second.
    pub bitrate: u32,
    /// The sample point, per mille of the bit.
    pub sample_permille: u16,
}

/// The controller refused its configuration (`Can_Init` / `Can_SetBaudrate`: `E_NOT_OK`):
/// no bit timing gives the bitrate from its clock, or its bus runs at another bitrate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InitRefused {
    /// The bitrate refused.
    pub bitrate: u32,
}

/// A controller's error state and counters (`Can_GetControllerErrorState`,
/// `Can_GetControllerTxErrorCounter`, `Can_GetControllerRxErrorCounter`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ErrorCounters {
    /// Error active, error passive or bus-off.
    pub state: confinement::ErrorState,
    /// The transmit error counter (above 255 only while bus-off).
    pub tec: u16,
    /// The receive error counter.
    pub rec: u8,
}

impl ErrorCounters {
    /// Error active, no error counted: a controller fresh from reset.
    pub const ACTIVE: Self = Self {
        state: confinement::ErrorState::Active,
        tec: 0,
        rec: 0,
    };
}

/// What the stack needs from a CAN controller driver.
pub trait CanDriver {
    /// `Can_Init` for this controller: its bitrate and sample point. The controller is
    /// stopped afterwards; [`CanDriver::set_controller_mode`] starts it.
    ///
    /// # Errors
    /// [`InitRefused`] when the driver cannot run at `config` (the controller keeps its
    /// previous configuration).
    fn init(&mut self, config: &ControllerConfig) -> Result<(), InitRefused>;

    /// `Can_Write`: puts `frame` into a free mailbox of `hth`. `pdu` is the stack's handle,
    /// handed back with the transmit confirmation.
    ///
    /// # Errors
    /// [`CanBusy`] when no mailbox of `hth` is free.
    fn write(&mut self, hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy>;

    /// `Can_SetControllerMode`: asks for `mode`. The controller may get there at once
    /// ([`ModeChange::Reached`]) or later ([`ModeChange::Pending`]: it reports the mode as
    /// an event when it gets there, and only then).
    ///
    /// # Errors
    /// [`ModeRefused`] for a transition the controller does not allow.
    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused>;

    /// The error state and counters now.
    fn error_counters(&self) -> ErrorCounters;

    /// Withdraws the frames waiting in the mailboxes of `hth`: they are neither sent nor
    /// confirmed. A frame whose transmission has begun may still finish, with its
    /// confirmation, as a controller's hardware finishes it (the SLCAN controller finishes
    /// a line on the wire; the host model, which settles a frame at its end, withdraws
    /// it).
    fn abort(&mut self, hth: Hth);
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::Frame;

    #[test]
    fn ids_convert_both_ways_and_keep_their_kind() {
        for raw in [0u16, 0x100, 0x7FF] {
            let Some(id) = CanId::standard(raw) else {
                panic!("valid id refused")
            };
            assert!(!id.is_extended());
            assert_eq!(CanId::from(Id::from(id)), id);
            assert_eq!(id.raw(), u32::from(raw));
        }
        let Some(ext) = CanId::extended(0x100) else {
            panic!("valid id refused")
        };
        assert_ne!(
            CanId::standard(0x100),
            Some(ext),
            "0x100 standard is not 0x100 extended"
        );
        assert_eq!(CanId::from(Id::from(ext)), ext);
        assert_eq!(CanId::standard(0x800), None);
        assert_eq!(CanId::extended(0x2000_0000), None);
    }

    #[test]
    fn arbitration_orders_base_ids_then_standard_before_extended() {
        let key = |raw, extended| CanId::masked(raw, extended).arbitration_key();
        assert!(key(0x100, false) < key(0x101, false));
        // Same base id 0x100: the standard frame wins.
        assert!(key(0x100, false) < key(0x100 << 18, true));
        assert!(key(0x100 << 18, true) < key((0x100 << 18) | 1, true));
        // A lower base id wins whatever the kind.
        assert!(key((0x0FF << 18) | 0x3_FFFF, true) < key(0x100, false));
        assert_eq!(key(0x7FF, false), 0x7FF << 19);
    }

    #[test]
    fn frames_hold_at_most_eight_bytes() {
        let Some(id) = CanId::standard(0x123) else {
            panic!("valid id refused")
        };
        let Some(frame) = CanFrame::from_parts(id, &[1, 2, 3]) else {
            panic!("3 bytes refused")
        };
        assert_eq!(frame.dlc(), 3);
        assert_eq!(frame.data(), &[1, 2, 3]);
        assert!(frame.is_standard() && frame.is_data_frame());
        assert_eq!(CanFrame::from_parts(id, &[0; 9]), None);
        assert!(CanFrame::new_remote(StandardId::ZERO, 1).is_none());
    }

    #[test]
    fn masked_ids_and_frames_are_the_checked_ones() {
        assert_eq!(Some(CanId::masked(0x8123, false)), CanId::standard(0x123));
        assert_eq!(
            Some(CanId::masked(0xE000_0100, true)),
            CanId::extended(0x100)
        );
        let id = CanId::masked(0x123, false);
        let data = [1, 2, 3, 4, 5, 6, 7, 8];
        for len in 0..=20u8 {
            let want = CanFrame::from_parts(id, &data[..usize::from(len % 9)]);
            assert_eq!(Some(CanFrame::masked(id, len, data)), want, "len {len}");
        }
    }
}
