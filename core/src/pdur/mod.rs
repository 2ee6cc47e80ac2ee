//! PDU Router (AUTOSAR SWS PduR), the static routes between Com and CanIf.
//!
//! Transmit: each Com TX I-PDU routes to exactly one CanIf TX L-PDU (`PduR_ComTransmit`);
//! the transmit confirmation takes the reverse route (`PduR_CanIfTxConfirmation`), derived
//! from the same table. Receive: each CanIf RX L-PDU routes to one Com RX I-PDU (the fast
//! path), to several (fan-out, out of line), or nowhere (`PduR_CanIfRxIndication`).
//!
//! Routes are `const` tables resolved at build time; a route to a PDU that does not exist
//! is a build error.

use crate::can::CanDriver;
use crate::canif::{CanIf, CanIfConfig, RxPduId, TransmitError, TxPduId};
use crate::com::ipdu::{self, Com, ComConfig};
use crate::tables::Tables;

/// Where a received L-PDU goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RxRoute {
    /// Not routed: dropped by PduR.
    Drop,
    /// To one Com I-PDU.
    One(ipdu::RxIpduId),
    /// To several Com I-PDUs, in this order.
    FanOut(&'static [ipdu::RxIpduId]),
}

/// A broken routing rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PduRConfigError {
    /// A Com TX I-PDU routes to a CanIf PDU beyond `CANIF_TX`.
    TxRoute {
        /// The Com TX I-PDU.
        ipdu: u16,
    },
    /// Two Com TX I-PDUs route to the same CanIf PDU (the confirmation would be ambiguous).
    SharedTxPdu {
        /// The second Com TX I-PDU.
        ipdu: u16,
    },
    /// A CanIf RX L-PDU routes to a Com I-PDU beyond `COM_RX`.
    RxRoute {
        /// The CanIf RX L-PDU.
        pdu: u16,
    },
}

impl PduRConfigError {
    /// A sentence describing the broken rule.
    pub const fn describe(&self) -> &'static str {
        match self {
            Self::TxRoute { .. } => "a PduR transmit route names a CanIf PDU that does not exist",
            Self::SharedTxPdu { .. } => "two Com I-PDUs route to one CanIf PDU",
            Self::RxRoute { .. } => "a PduR receive route names a Com I-PDU that does not exist",
        }
    }
}

const NONE: u16 = u16::MAX;

/// Validated routes: `COM_TX` Com TX I-PDUs onto `CANIF_TX` CanIf TX PDUs, and `CANIF_RX`
/// CanIf RX PDUs onto `COM_RX` Com RX I-PDUs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PduRConfig<
    const COM_TX: usize,
    const CANIF_TX: usize,
    const CANIF_RX: usize,
    const COM_RX: usize,
> {
    tx: [TxPduId; COM_TX],
    rx: [RxRoute; CANIF_RX],
    /// Derived: CanIf TX PDU -> Com TX I-PDU (`NONE` if unrouted).
    confirm: [u16; CANIF_TX],
}

impl<const COM_TX: usize, const CANIF_TX: usize, const CANIF_RX: usize, const COM_RX: usize>
    PduRConfig<COM_TX, CANIF_TX, CANIF_RX, COM_RX>
{
    /// Validates the routes and derives the confirmation routes.
    ///
    /// # Errors
    /// The first [`PduRConfigError`].
    pub const fn new(
        tx: [TxPduId; COM_TX],
        rx: [RxRoute; CANIF_RX],
    ) -> Result<Self, PduRConfigError> {
        let mut confirm = [NONE; CANIF_TX];
        let mut i = 0;
        while i < COM_TX {
            let target = tx[i].0 as usize;
            if target >= CANIF_TX {
                return Err(PduRConfigError::TxRoute { ipdu: i as u16 });
            }
            if confirm[target] != NONE {
                return Err(PduRConfigError::SharedTxPdu { ipdu: i as u16 });
            }
            confirm[target] = i as u16;
            i += 1;
        }
        let mut p = 0;
        while p < CANIF_RX {
            let ok = match rx[p] {
                RxRoute::Drop => true,
                RxRoute::One(id) => (id.0 as usize) < COM_RX,
                RxRoute::FanOut(list) => {
                    let mut k = 0;
                    let mut all = true;
                    while k < list.len() {
                        all &= (list[k].0 as usize) < COM_RX;
                        k += 1;
                    }
                    all
                }
            };
            if !ok {
                return Err(PduRConfigError::RxRoute { pdu: p as u16 });
            }
            p += 1;
        }
        Ok(Self { tx, rx, confirm })
    }

    /// `PduR_ComTransmit`: hands a Com TX I-PDU to CanIf. Returns whether CanIf accepted it
    /// (sent or buffered).
    #[inline(always)]
    pub fn com_transmit<D: CanDriver, const TX: usize, const RX: usize, K>(
        &self,
        canif: &mut CanIf<TX, RX, K>,
        driver: &mut D,
        ipdu: ipdu::TxIpduId,
        sdu: &[u8],
    ) -> Result<(), TransmitError>
    where
        K: Tables<CanIfConfig<TX, RX>>,
    {
        let pdu = *self
            .tx
            .get(usize::from(ipdu.0))
            .ok_or(TransmitError::UnknownPdu)?;
        canif.transmit(driver, pdu, sdu)
    }

    /// `PduR_CanIfTxConfirmation`: the Com TX I-PDU a confirmed CanIf PDU belongs to.
    #[inline]
    pub fn canif_tx_confirmation(&self, pdu: TxPduId) -> Option<ipdu::TxIpduId> {
        let ipdu = *self.confirm.get(usize::from(pdu.0))?;
        (ipdu != NONE).then_some(ipdu::TxIpduId(ipdu))
    }

    /// `PduR_CanIfRxIndication`: hands a received L-PDU to the Com I-PDU(s) it routes to.
    /// Returns how many Com I-PDUs received it.
    #[inline(always)]
    pub fn canif_rx_indication<
        const N: usize,
        const CTX: usize,
        const CRX: usize,
        const S: usize,
        K: Tables<ComConfig<N, CTX, CRX, S>>,
    >(
        &self,
        com: &mut Com<N, CTX, CRX, S, K>,
        pdu: RxPduId,
        sdu: &[u8],
    ) -> usize {
        match self.rx.get(usize::from(pdu.0)) {
            Some(RxRoute::One(ipdu)) => {
                com.rx_indication(*ipdu, sdu);
                1
            }
            Some(RxRoute::FanOut(list)) => Self::fan_out(com, list, sdu),
            Some(RxRoute::Drop) | None => 0,
        }
    }

    #[inline(never)]
    fn fan_out<const N: usize, const CTX: usize, const CRX: usize, const S: usize, K>(
        com: &mut Com<N, CTX, CRX, S, K>,
        list: &[ipdu::RxIpduId],
        sdu: &[u8],
    ) -> usize
    where
        K: Tables<ComConfig<N, CTX, CRX, S>>,
    {
        for ipdu in list {
            com.rx_indication(*ipdu, sdu);
        }
        list.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::{CanBusy, CanFrame, CanId, ControllerMode, Hrh, Hth, ModeChange, ModeRefused};
    use crate::canif::{PduMode, RxPduConfig, TxPduConfig};
    use crate::com::ipdu::{
        ComConfig, RxIpduConfig, RxIpduId, SignalConfig, SignalDirection, SignalId,
        TransferProperty, TxIpduConfig, TxIpduId, TxMode,
    };
    use crate::com::signal::{ByteOrder, SignalLayout, SignalValue, Signedness};
    extern crate std;
    use std::vec::Vec;

    const fn id(raw: u16) -> CanId {
        match CanId::standard(raw) {
            Some(id) => id,
            None => panic!("bad id"),
        }
    }

    const U32: SignalLayout<8> =
        crate::signal_layout!(8; 0, 32, ByteOrder::Intel, Signedness::Unsigned);

    static CANIF: crate::canif::CanIfConfig<1, 2> = match crate::canif::CanIfConfig::new(
        [TxPduConfig {
            name: "Distance",
            id: id(0x100),
            dlc: 8,
            hth: Hth(0),
        }],
        [
            RxPduConfig {
                name: "Echo",
                id: id(0x200),
                dlc: 8,
                hrh: Hrh(0),
            },
            RxPduConfig {
                name: "Unrouted",
                id: id(0x300),
                dlc: 1,
                hrh: Hrh(0),
            },
        ],
    ) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };

    static COM: ComConfig<8, 1, 2, 3> = match ComConfig::new(
        10,
        [TxIpduConfig {
            name: "Distance",
            len: 8,
            mode: TxMode::Direct {
                repetitions: 0,
                repetition_period_ms: 0,
            },
            mdt_ms: 0,
        }],
        [
            RxIpduConfig {
                name: "EchoA",
                len: 8,
                deadline_ms: 0,
            },
            RxIpduConfig {
                name: "EchoB",
                len: 8,
                deadline_ms: 0,
            },
        ],
        [
            SignalConfig {
                name: "Distance",
                direction: SignalDirection::Tx(TxIpduId(0), TransferProperty::Triggered),
                layout: U32,
                init: 0,
                invalid: None,
                update_bit: None,
            },
            SignalConfig {
                name: "A",
                direction: SignalDirection::Rx(RxIpduId(0)),
                layout: U32,
                init: 0,
                invalid: None,
                update_bit: None,
            },
            SignalConfig {
                name: "B",
                direction: SignalDirection::Rx(RxIpduId(1)),
                layout: U32,
                init: 0,
                invalid: None,
                update_bit: None,
            },
        ],
    ) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };

    static BOTH: [RxIpduId; 2] = [RxIpduId(0), RxIpduId(1)];
    static ROUTES: PduRConfig<1, 1, 2, 2> =
        match PduRConfig::new([TxPduId(0)], [RxRoute::FanOut(&BOTH), RxRoute::Drop]) {
            Ok(c) => c,
            Err(e) => panic!("{}", e.describe()),
        };

    #[derive(Default)]
    struct Bus(Vec<CanFrame>);
    impl CanDriver for Bus {
        fn init(
            &mut self,
            _: &crate::can::ControllerConfig,
        ) -> Result<(), crate::can::InitRefused> {
            Ok(())
        }
        // Frames leave at once: nothing waits to be aborted, no error is counted.
        fn error_counters(&self) -> crate::can::ErrorCounters {
            crate::can::ErrorCounters::ACTIVE
        }
        fn abort(&mut self, _: Hth) {}
        fn write(&mut self, _: Hth, _: u16, frame: &CanFrame) -> Result<(), CanBusy> {
            self.0.push(*frame);
            Ok(())
        }
        fn set_controller_mode(&mut self, _: ControllerMode) -> Result<ModeChange, ModeRefused> {
            Ok(ModeChange::Reached)
        }
    }

    #[test]
    fn a_signal_travels_com_pdur_canif_to_the_driver_and_back() {
        let mut com = Com::new(&COM);
        let mut canif = CanIf::new(&CANIF);
        let mut bus = Bus::default();
        assert_eq!(
            canif.set_controller_mode(&mut bus, ControllerMode::Started),
            Ok(ModeChange::Reached)
        );
        canif.set_pdu_mode(PduMode::Online);
        let r = com.send_signal(SignalId(0), SignalValue::Unsigned(1500), |ipdu, sdu| {
            ROUTES.com_transmit(&mut canif, &mut bus, ipdu, sdu).is_ok()
        });
        assert_eq!(r, Ok(()));
        assert_eq!(bus.0.len(), 1);
        assert_eq!(bus.0[0].bytes(), &[0xDC, 0x05, 0, 0, 0, 0, 0, 0]);
        assert_eq!(ROUTES.canif_tx_confirmation(TxPduId(0)), Some(TxIpduId(0)));
        // The frame comes back as 0x200 and fans out to both Com I-PDUs.
        let Some(echo) = CanFrame::from_parts(id(0x200), bus.0[0].bytes()) else {
            panic!()
        };
        let Ok(pdu) = canif.rx_indication(Hrh(0), &echo) else {
            panic!("dropped")
        };
        assert_eq!(ROUTES.canif_rx_indication(&mut com, pdu, echo.bytes()), 2);
        assert_eq!(
            com.receive_signal(SignalId(1)),
            Ok(SignalValue::Unsigned(1500))
        );
        assert_eq!(
            com.receive_signal(SignalId(2)),
            Ok(SignalValue::Unsigned(1500))
        );
        // An unrouted L-PDU reaches no Com I-PDU.
        assert_eq!(ROUTES.canif_rx_indication(&mut com, RxPduId(1), &[1]), 0);
    }

    #[test]
    fn broken_routes_are_refused() {
        assert_eq!(
            PduRConfig::<1, 1, 0, 0>::new([TxPduId(1)], []).err(),
            Some(PduRConfigError::TxRoute { ipdu: 0 })
        );
        assert_eq!(
            PduRConfig::<2, 1, 0, 0>::new([TxPduId(0), TxPduId(0)], []).err(),
            Some(PduRConfigError::SharedTxPdu { ipdu: 1 })
        );
        assert_eq!(
            PduRConfig::<0, 0, 1, 1>::new([], [RxRoute::One(RxIpduId(1))]).err(),
            Some(PduRConfigError::RxRoute { pdu: 0 })
        );
    }
}
