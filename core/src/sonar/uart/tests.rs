//! The ranging module's protocol: the data sheet's example, the streaming decoder against
//! the batch rule on any bytes, noise and lost bytes, and the ranger's sample rules.
extern crate std;

use std::vec::Vec;

use super::*;
use crate::warning::Measurement;

/// The example of the modules' data sheets: `FF 07 A1 A7` is 1953 mm.
#[test]
fn data_sheet_example() {
    assert_eq!(encode(1953), [0xFF, 0x07, 0xA1, 0xA7]);
    let mut decoder = Decoder::new();
    let verdicts: [Option<Frame>; 4] = [0xFF, 0x07, 0xA1, 0xA7].map(|b| decoder.push(b));
    assert_eq!(
        verdicts,
        [None, None, None, Some(Frame::Distance { mm: 1953 })]
    );
    assert_eq!(decoder.pending(), 0);
}

/// A byte lost inside a frame (here its low byte) costs that frame, which ends with the
/// next frame's header and fails its sum, and nothing else: the hunt resumes at that
/// header.
#[test]
fn a_lost_byte_costs_its_own_frame() {
    let mut decoder = Decoder::new();
    let stream = [0xFF, 0x07, 0xA7, 0xFF, 0x05, 0xDC, checksum(1500)];
    let verdicts: Vec<(usize, Frame)> = stream
        .iter()
        .enumerate()
        .filter_map(|(at, &b)| decoder.push(b).map(|f| (at, f)))
        .collect();
    assert_eq!(
        verdicts,
        [(3, Frame::BadChecksum), (6, Frame::Distance { mm: 1500 })]
    );
    assert_eq!(
        decoder.stray_bytes(),
        2,
        "0x07 and 0xA7 were part of no frame"
    );
}

/// The streaming decoder is the batch rule of `spec::reference` on any stream: the same
/// verdicts at the same bytes, the same stray and pending counts.
///
/// Stated byte by byte: the decoder gives at most one verdict per byte, and the reference
/// gives its verdicts in byte order (checked here), so the two give the same verdicts at
/// the same bytes (`spec::matches_reference`) exactly when, after every byte, they agree
/// on whether a frame ended there and how. For Kani "every byte" is one symbolic byte
/// `at`; `spec::matches_reference` itself, which interleaves the two by nested iteration,
/// unwinds into a program of 1.6 million steps. The bolero runs check every byte and
/// `spec::matches_reference` as well.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(14))]
fn streaming_decoder_is_the_batch_rule() {
    bolero::check!()
        .with_type::<([u8; 12], u8, u8)>()
        .cloned()
        .for_each(|(bytes, len, at)| {
            let bytes = &bytes[..usize::from(len % 13)];
            let mut decoder = Decoder::new();
            let mut streamed = [None; 12];
            for (verdict, &b) in streamed.iter_mut().zip(bytes) {
                *verdict = decoder.push(b);
            }
            let mut batch = [None; 12];
            let mut in_byte_order = true;
            let mut next = 0;
            let (stray, pending) = spec::reference(bytes, |at, frame| {
                in_byte_order &= next <= at && at < bytes.len();
                next = at + 1;
                if let Some(verdict) = batch.get_mut(at) {
                    *verdict = Some(frame);
                }
            });
            assert!(in_byte_order);
            let at = usize::from(at % 12);
            assert_eq!(streamed[at], batch[at], "the verdicts at byte {at}");
            assert_eq!((decoder.stray_bytes(), decoder.pending()), (stray, pending));
            #[cfg(not(kani))]
            {
                assert_eq!(streamed, batch);
                assert!(spec::matches_reference(bytes));
            }
        });
}

/// The same on long streams, mostly of frames, as the wire carries them.
#[cfg(not(kani))]
#[test]
fn streaming_decoder_is_the_batch_rule_on_long_streams() {
    bolero::check!()
        .with_type::<Vec<(u8, u16)>>()
        .for_each(|parts: &Vec<(u8, u16)>| {
            let mut bytes = Vec::new();
            for &(kind, value) in parts {
                let frame = encode(value);
                match kind % 4 {
                    0 | 1 => bytes.extend_from_slice(&frame),
                    2 => bytes.extend_from_slice(&frame[..usize::from(kind / 4 % 4)]),
                    _ => bytes.extend_from_slice(&value.to_be_bytes()),
                }
            }
            assert!(spec::matches_reference(&bytes));
        });
}

/// Stray bytes (line noise with no header in it), then frames back to back: every frame
/// is decoded, in order, and the noise is counted byte for byte.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(16))]
fn clean_frames_after_noise_are_all_decoded() {
    bolero::check!()
        .with_type::<([u8; 3], u8, [u16; 3])>()
        .cloned()
        .for_each(|(noise, noise_len, distances)| {
            let noise_len = usize::from(noise_len % 4);
            let mut decoder = Decoder::new();
            for &b in &noise[..noise_len] {
                assert_eq!(decoder.push(if b == HEADER { 0 } else { b }), None);
            }
            for &mm in &distances {
                let [a, b, c, d] = encode(mm);
                assert_eq!(decoder.push(a), None);
                assert_eq!(decoder.push(b), None);
                assert_eq!(decoder.push(c), None);
                assert_eq!(decoder.push(d), Some(Frame::Distance { mm }));
            }
            assert_eq!(decoder.stray_bytes(), noise_len as u32);
            assert_eq!(decoder.pending(), 0);
        });
}

/// A frame with any one byte lost, then a good frame: the good frame is decoded unless
/// the bytes left of the damaged one, with the good frame's, form a false frame (a frame
/// whose 8-bit sum holds by chance, which no decoder of this protocol can tell from a
/// real one). Truncation alone never costs the next frame.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn only_a_false_frame_costs_the_frame_after_a_lost_byte() {
    bolero::check!()
        .with_type::<(u16, u8, u16)>()
        .cloned()
        .for_each(|(damaged, lost, next)| {
            let lost = usize::from(lost % 4);
            let mut decoder = Decoder::new();
            let mut false_frame = false;
            let mut last = None;
            let [a, b, c, d] = encode(damaged);
            let [e, f, g, h] = encode(next);
            // The lost byte is skipped by its index rather than filtered out and the
            // frames chained: Kani unwinds those iterator adapters into a program ten
            // times larger. `i` counts the bytes that arrive.
            let mut i = 0;
            for (at, &byte) in [a, b, c, d, e, f, g, h].iter().enumerate() {
                if at == lost {
                    continue;
                }
                if let Some(verdict) = decoder.push(byte) {
                    // A good verdict before the next frame's last byte is a false frame.
                    false_frame |= i < 6 && verdict != Frame::BadChecksum;
                    last = Some(verdict);
                }
                i += 1;
            }
            assert!(false_frame || last == Some(Frame::Distance { mm: next }));
        });
}

/// The kind of one sample's bytes in the ranger's model check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sent {
    Nothing,
    Good(u16),
    Bad(u16),
    NoiseThenGood(u8, u16),
}

impl Sent {
    fn from_raw(kind: u8, mm: u16) -> Self {
        // Distances around the blind zone and the rated range are the interesting ones.
        let mm = match kind / 4 % 4 {
            0 => mm % 64,
            1 => 3_990 + mm % 20,
            _ => mm,
        };
        match kind % 4 {
            0 => Self::Nothing,
            1 => Self::Good(mm),
            2 => Self::Bad(mm),
            _ => Self::NoiseThenGood(kind / 16, mm),
        }
    }

    fn bytes(self) -> ([u8; 5], usize) {
        let mut out = [0u8; 5];
        let n = match self {
            Self::Nothing => 0,
            Self::Good(mm) => {
                out[..4].copy_from_slice(&encode(mm));
                4
            }
            Self::Bad(mm) => {
                // No 0xFF after the header: the decoder's resynchronization inside a bad
                // frame is the business of the decoder's own harnesses.
                let mut f = encode(mm & 0x7F7F);
                f[3] = match f[3].wrapping_add(1) {
                    HEADER => f[3].wrapping_add(2),
                    sum => sum,
                };
                out[..4].copy_from_slice(&f);
                4
            }
            Self::NoiseThenGood(noise, mm) => {
                out[0] = noise;
                out[1..].copy_from_slice(&encode(mm));
                5
            }
        };
        (out, n)
    }

    fn good(self) -> Option<u16> {
        match self {
            Self::Good(mm) | Self::NoiseThenGood(_, mm) => Some(mm),
            _ => None,
        }
    }
}

/// Any sequence of samples (nothing, a good frame, a bad frame, noise then a good frame)
/// gives the measurement the rules say:
/// - a good frame outside the blind zone: its distance, classified by the rated range;
/// - a bad checksum or a blind-zone reading: invalid;
/// - nothing new: the newest good distance, if it came fewer than `silent_after`
///   samples ago, else invalid (the module is silent);
///
/// and the counts are what was sent (a bad frame's three bytes after its header are
/// stray).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(7))]
fn ranger_follows_its_rules() {
    bolero::check!()
        .with_type::<([(u8, u16); 5], u8)>()
        .cloned()
        .for_each(|(samples, silent_after)| {
            let silent_after = silent_after % 4 + 1;
            let config = SonarConfig::HC_SR04;
            let mut ranger = Ranger::new(silent_after);
            let mut newest_good: Option<(u16, usize)> = None;
            let mut sent = RangerCounts::default();
            for (n, &(kind, mm)) in samples.iter().enumerate() {
                let s = Sent::from_raw(kind, mm);
                let (bytes, len) = s.bytes();
                let got = ranger.sample(bytes[..len].iter().copied(), &config);
                let want = match s {
                    Sent::Nothing => match newest_good {
                        Some((mm, at)) if n - at < usize::from(silent_after) => {
                            config.classify_distance(u32::from(mm))
                        }
                        _ => Measurement::Invalid,
                    },
                    Sent::Bad(_) => Measurement::Invalid,
                    Sent::Good(mm) | Sent::NoiseThenGood(_, mm) if mm < BLIND_ZONE_MM => {
                        Measurement::Invalid
                    }
                    Sent::Good(mm) | Sent::NoiseThenGood(_, mm) => {
                        config.classify_distance(u32::from(mm))
                    }
                };
                assert_eq!(got, want, "sample {n}: {s:?}");
                if let Some(mm) = s.good() {
                    sent.frames += 1;
                    if mm < BLIND_ZONE_MM {
                        sent.blind += 1;
                    } else {
                        newest_good = Some((mm, n));
                    }
                }
                sent.stray_bytes += u32::from(matches!(s, Sent::NoiseThenGood(..)));
                if let Sent::Bad(_) = s {
                    // The three bytes after a bad frame's header, none a header, are
                    // hunted through as stray.
                    sent.bad_checksums += 1;
                    sent.stray_bytes += 3;
                }
            }
            let counts = ranger.counts();
            assert_eq!(
                (
                    counts.frames,
                    counts.bad_checksums,
                    counts.blind,
                    counts.stray_bytes
                ),
                (
                    sent.frames,
                    sent.bad_checksums,
                    sent.blind,
                    sent.stray_bytes
                )
            );
        });
}

/// The rated range and the blind zone, and a module that falls silent.
#[test]
fn ranger_limits_and_silence() {
    let config = SonarConfig::HC_SR04;
    let mut ranger = Ranger::new(3);
    assert_eq!(
        ranger.sample([], &config),
        Measurement::Invalid,
        "silent from the start"
    );
    assert_eq!(
        ranger.sample(encode(4001), &config),
        Measurement::NothingInRange
    );
    assert_eq!(
        ranger.sample(encode(4000), &config),
        Measurement::Distance { distance_mm: 4000 }
    );
    assert_eq!(ranger.sample(encode(29), &config), Measurement::Invalid);
    assert_eq!(
        ranger.sample(encode(30), &config),
        Measurement::Distance { distance_mm: 30 }
    );
    for _ in 0..2 {
        assert_eq!(
            ranger.sample([], &config),
            Measurement::Distance { distance_mm: 30 },
            "between frames the last distance stands"
        );
    }
    assert_eq!(ranger.sample([], &config), Measurement::Invalid, "silent");
    let counts = ranger.counts();
    assert_eq!(
        (counts.frames, counts.blind, counts.silent_samples),
        (4, 1, 2)
    );
}

/// A silence limit of 0 acts as 1: the last distance is never repeated.
#[test]
fn a_silence_limit_of_zero_acts_as_one() {
    let config = SonarConfig::HC_SR04;
    let mut zero = Ranger::new(0);
    let mut one = Ranger::new(1);
    for bytes in [
        encode(1234).to_vec(),
        Vec::new(),
        Vec::new(),
        encode(900).to_vec(),
    ] {
        let a = zero.sample(bytes.iter().copied(), &config);
        assert_eq!(a, one.sample(bytes.iter().copied(), &config));
        if bytes.is_empty() {
            assert_eq!(a, Measurement::Invalid);
        }
    }
    assert_eq!(zero.counts(), one.counts());
}
