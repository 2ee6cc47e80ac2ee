//! Criterion: the ECU's communication stack per layer (the paper's Figure 10) in
//! nanoseconds, with the ECU's own configuration. Instruction counts of the same paths:
//! `cargo xtask callgrind` (firmware/examples/stack_probe.rs).

use criterion::{criterion_group, criterion_main, Criterion};
use cw_core::can::{
    CanBusy, CanDriver, CanFrame, ControllerMode, Hrh, Hth, ModeChange, ModeRefused,
};
use cw_core::canif::{CanIf, PduMode, RxPduId, TxPduId};
use cw_core::com::ipdu::Com;
use cw_core::com::signal::SignalValue;
use cw_firmware::config;
use std::hint::black_box;

/// A controller with one transmit mailbox that empties itself (the frame left).
struct Mailbox;
impl CanDriver for Mailbox {
    fn init(
        &mut self,
        _: &cw_core::can::ControllerConfig,
    ) -> Result<(), cw_core::can::InitRefused> {
        Ok(())
    }
    // The frame leaves at once: nothing waits, no error is counted.
    fn error_counters(&self) -> cw_core::can::ErrorCounters {
        cw_core::can::ErrorCounters::ACTIVE
    }
    fn abort(&mut self, _: Hth) {}
    fn write(&mut self, _: Hth, _: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        black_box(frame);
        Ok(())
    }
    fn set_controller_mode(&mut self, _: ControllerMode) -> Result<ModeChange, ModeRefused> {
        Ok(ModeChange::Reached)
    }
}

fn stack(c: &mut Criterion) {
    let mut com = Com::new(config::ComTables);
    let mut canif = CanIf::new(config::CanIfTables);
    let mut can = Mailbox;
    let _ = canif.set_controller_mode(&mut can, ControllerMode::Started);
    canif.set_pdu_mode(PduMode::Online);
    let rx = CanFrame::from_parts(
        config::canif::THRESHOLD_CONFIG_ID,
        &[0xF4, 0x01, 0xE8, 0x03],
    );
    let Some(rx) = rx else { return };
    let sdu = [0xDCu8, 0x05, 0, 0, 2, 0, 0, 0];

    let mut g = c.benchmark_group("stack");
    g.bench_function("TX Com_SendSignal -> PduR -> CanIf -> Can_Write", |b| {
        b.iter(|| {
            com.send_signal(
                config::com::DISTANCE,
                SignalValue::Unsigned(black_box(1500)),
                |ipdu, sdu| {
                    config::PDUR
                        .com_transmit(&mut canif, &mut can, ipdu, sdu)
                        .is_ok()
                },
            )
        })
    });
    g.bench_function("TX PduR -> CanIf -> Can_Write", |b| {
        b.iter(|| {
            config::PDUR.com_transmit(
                &mut canif,
                &mut can,
                config::com::DISTANCE_FRAME,
                black_box(&sdu),
            )
        })
    });
    g.bench_function("TX CanIf_Transmit -> Can_Write", |b| {
        b.iter(|| canif.transmit(&mut can, TxPduId(0), black_box(&sdu)))
    });
    g.bench_function("RX CanIf -> PduR -> Com -> Com_ReceiveSignal", |b| {
        b.iter(|| {
            if let Ok(pdu) = canif.rx_indication(Hrh(0), black_box(&rx)) {
                config::PDUR.canif_rx_indication(&mut com, pdu, rx.bytes());
            }
            com.receive_signal(config::com::RED_BELOW)
        })
    });
    g.bench_function("RX CanIf_RxIndication", |b| {
        b.iter(|| canif.rx_indication(Hrh(0), black_box(&rx)))
    });
    g.bench_function("RX PduR -> Com_RxIndication", |b| {
        b.iter(|| config::PDUR.canif_rx_indication(&mut com, RxPduId(0), black_box(rx.bytes())))
    });
    g.bench_function("RX Com_ReceiveSignal", |b| {
        b.iter(|| com.receive_signal(black_box(config::com::RED_BELOW)))
    });
    g.finish();
}

criterion_group!(benches, stack);
criterion_main!(benches);
