//! Bit timings against their rule (`spec::find_is_exact_and_nearest`), and the usual
//! bitrates of an S32K144's FlexCAN by name.

extern crate std;

use std::string::ToString;

use super::*;

#[test]
fn the_usual_bitrates_from_an_80_mhz_flexcan_clock() {
    // 500 kbit/s from 80 MHz, sample point 87.5 %: 20 quanta of 8 clocks, 1 + 16 + 3...
    let t = find(80_000_000, 500_000, 875, &FLEXCAN).expect("500 kbit/s");
    assert_eq!(t.bitrate(80_000_000), Some(500_000));
    assert!(t.fits(&FLEXCAN));
    assert_eq!(t.sample_permille(), 875);
    for bitrate in [125_000, 250_000, 500_000, 1_000_000] {
        let t = find(80_000_000, bitrate, 875, &FLEXCAN).expect("a usual bitrate");
        assert_eq!(t.bitrate(80_000_000), Some(bitrate));
        assert!((850..=900).contains(&t.sample_permille()), "{t:?}");
    }
    // From the 8 MHz oscillator, 500 kbit/s has 16 quanta at most: 1 + 13 + 2.
    let t = find(8_000_000, 500_000, 875, &FLEXCAN).expect("500 kbit/s from 8 MHz");
    assert_eq!((t.prescaler, t.quanta(), t.sample_permille()), (1, 16, 875));
}

#[test]
fn a_bitrate_no_timing_reaches_exactly_is_refused_naming_it() {
    let e = find(80_000_000, 333_333, 875, &FLEXCAN).expect_err("not exact");
    assert_eq!(
        e.to_string(),
        "no bit timing gives 333333 bit/s exactly from a 80000000 Hz clock"
    );
    assert!(find(80_000_000, 0, 875, &FLEXCAN).is_err());
    // Above the quanta the clock allows: 5 MHz cannot make 1 Mbit/s with 8 quanta.
    assert!(find(5_000_000, 1_000_000, 875, &FLEXCAN).is_err());
}

#[test]
fn the_resynchronisation_jump_is_as_wide_as_allowed() {
    let t = find(80_000_000, 500_000, 875, &FLEXCAN).expect("500 kbit/s");
    assert_eq!(t.sjw, FLEXCAN.sjw_max.min(t.tseg2));
}

#[test]
fn a_timing_outside_any_one_limit_does_not_fit_and_a_zero_prescaler_has_no_bitrate() {
    let good = BitTiming {
        prescaler: 4,
        tseg1: 13,
        tseg2: 6,
        sjw: 4,
    };
    assert!(good.fits(&FLEXCAN));
    let outside = [
        BitTiming {
            prescaler: 0,
            ..good
        },
        BitTiming {
            prescaler: 257,
            ..good
        },
        BitTiming { tseg1: 1, ..good },
        BitTiming { tseg1: 17, ..good },
        BitTiming {
            tseg2: 1,
            sjw: 1,
            ..good
        },
        BitTiming { tseg2: 9, ..good },
        BitTiming { sjw: 0, ..good },
        BitTiming {
            sjw: 5,
            tseg2: 8,
            ..good
        },
        BitTiming {
            sjw: 4,
            tseg2: 3,
            ..good
        },
        BitTiming {
            tseg1: 2,
            tseg2: 2,
            sjw: 2,
            ..good
        },
    ];
    for t in outside {
        assert!(!t.fits(&FLEXCAN), "{t:?}");
    }
    // More quanta than a controller allows (FlexCAN's segments reach 25 at most).
    let twenty = BitTimingLimits {
        quanta: (8, 20),
        ..FLEXCAN
    };
    let long = BitTiming {
        tseg1: 16,
        tseg2: 8,
        ..good
    };
    assert!(long.fits(&FLEXCAN) && !long.fits(&twenty));
    assert_eq!(
        BitTiming {
            prescaler: 0,
            ..good
        }
        .bitrate(80_000_000),
        None
    );
    assert_eq!(
        good.bitrate(80_000_001),
        None,
        "not a whole number of bits per second"
    );
}

#[test]
fn bitrates_beyond_the_arithmetic_or_the_prescaler_are_refused() {
    // bitrate x quanta overflows 32 bits.
    assert!(find(4_000_000_000, u32::MAX, 875, &FLEXCAN).is_err());
    // A prescaler above 16 bits.
    assert!(find(4_000_000_000, 1, 875, &FLEXCAN).is_err());
}

/// Small limits, so that the rule's exhaustive search is quick.
const SMALL: BitTimingLimits = BitTimingLimits {
    prescaler: (1, 16),
    tseg1: (2, 16),
    tseg2: (2, 8),
    sjw_max: 4,
    quanta: (8, 25),
};

/// Any clock, bitrate and sample point: `find` keeps its rule.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(27))]
fn any_request_gets_the_exact_and_nearest_timing_or_a_refusal() {
    bolero::check!()
        .with_type::<(u16, u8, u8, u16)>()
        .cloned()
        .for_each(|(clock_khz, quanta, prescaler, sample)| {
            // Clocks and bitrates that meet often: a bitrate from a quantum count and a
            // prescaler, or any.
            let clock = u32::from(clock_khz % 200 + 1) * 100_000;
            let bitrate = clock / (u32::from(quanta % 30 + 1) * u32::from(prescaler % 20 + 1));
            let sample = 500 + sample % 450;
            assert!(spec::find_is_exact_and_nearest(
                clock, bitrate, sample, &SMALL
            ));
        });
}

#[test]
fn the_cia_sample_points_step_down_at_500_and_800_kbit_s() {
    assert_eq!(cia_sample_permille(125_000), 875);
    assert_eq!(cia_sample_permille(500_000), 875);
    assert_eq!(cia_sample_permille(500_001), 800);
    assert_eq!(cia_sample_permille(800_000), 800);
    assert_eq!(cia_sample_permille(800_001), 750);
    assert_eq!(cia_sample_permille(1_000_000), 750);
}
