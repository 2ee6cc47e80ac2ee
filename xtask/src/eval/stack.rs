//! The communication stack's latency per layer (the paper's Figure 10): the same probes
//! (`cw_firmware::stack_probe`) counted on the Cortex-M4 image by its trace and on x86-64
//! by callgrind, beside the paper's totals and Arctic Core's layers counted on x86-64. A
//! transmit layer's share is the difference between a probe from that layer down and the
//! probe from the next layer down (the paper's method: its Figure 9); the receive layers
//! are probed each alone (receiving runs up the stack, so no probe ends at a layer's
//! call), and their sum is not the whole path's, which inlines them into each other.

use std::fmt::Write as _;
use std::path::Path;

use plotters::prelude::*;

use crate::Result;

/// The MPC5748G's clock, MHz: the paper's board.
pub(super) const PAPER_MHZ: f64 = 160.0;

/// The paper's totals, µs: SWC to the CAN controller, transmit and receive.
const PAPER_TX_US: f64 = 36.0;
const PAPER_RX_US: f64 = 34.0;

/// How a layer's figure comes from the probes: the probe from it down, less the probe
/// from the next layer down (`None`: nothing below).
struct Layer {
    name: &'static str,
    from: &'static str,
    less: Option<&'static str>,
    /// Arctic Core 21's own module (gcc -O2, x86-64, callgrind), instructions.
    arctic: Option<u64>,
}

const TX: [Layer; 4] = [
    Layer {
        name: "SWC -> RTE -> CanTranslate",
        from: "tx_path",
        less: Some("tx_com_down"),
        arctic: None,
    },
    Layer {
        name: "Com (`Com_SendSignal`: pack, transfer property, I-PDU)",
        from: "tx_com_down",
        less: Some("tx_pdur_down"),
        arctic: Some(273),
    },
    Layer {
        name:
            "PduR + CanIf (`PduR_ComTransmit` -> `CanIf_Transmit`: the static route adds no code)",
        from: "tx_pdur_down",
        less: Some("tx_can"),
        arctic: Some(76 + 56),
    },
    Layer {
        name: "Can (`Can_Write`, a mailbox in RAM)",
        from: "tx_can",
        less: None,
        arctic: Some(18),
    },
];

const RX: [Layer; 3] = [
    Layer {
        name: "CanIf (`CanIf_RxIndication`: id, HRH, DLC)",
        from: "rx_canif",
        less: None,
        arctic: Some(78),
    },
    Layer {
        name: "PduR + Com (`PduR_CanIfRxIndication` -> `Com_RxIndication`)",
        from: "rx_pdur_com",
        less: None,
        arctic: Some(71 + 95),
    },
    Layer {
        name: "Com (`Com_ReceiveSignal`: unpack)",
        from: "rx_com_read",
        less: None,
        arctic: Some(125),
    },
];

/// The whole paths, Arctic Core's from Com down (transmit) and from CanIf up (receive).
const TX_WHOLE: (&str, u64) = ("tx_path", 423);
const RX_WHOLE: (&str, u64) = ("rx_path", 369);

/// Every probe's figure, in both settings, and the ECU's own paths with their locks.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct Stack {
    /// (probe, mean instructions) on the Cortex-M4 image.
    pub image: Vec<(String, f64)>,
    /// Calls of each probe the image measured.
    pub image_calls: u64,
    /// (probe, instructions per call) on x86-64.
    pub x86: Vec<(String, f64)>,
    /// The ECU's own send on the image: (what, calls, mean instructions).
    pub image_paths: Vec<(String, u64, f64)>,
    /// The same paths on x86-64: (what, instructions per call, calls).
    pub x86_paths: Vec<(String, f64, u64)>,
}

/// Reads the image's `stack probe` lines and its spans of the ECU's send; an error names
/// the malformed line or says that there is none.
pub(super) fn parse_image(log: &str, stack: &mut Stack) -> Result {
    for (n, line) in log.lines().enumerate() {
        let bad = || format!("the image's log, line {}: `{line}` is malformed", n + 1);
        let (is_probe, rest) = if let Some(rest) = line.strip_prefix("cw-qemu: stack probe ") {
            (true, rest)
        } else if let Some(rest) = line.strip_prefix("cw-qemu: span OsComTask send") {
            (false, rest)
        } else {
            continue;
        };
        let (name, figures) = rest.rsplit_once(": ").ok_or_else(bad)?;
        let words: Vec<&str> = figures.split_whitespace().collect();
        let [count, "times,", "instructions", "mean", mean, "min", _, "max", _] = words.as_slice()
        else {
            return Err(bad());
        };
        let count: u64 = count.parse().map_err(|_| bad())?;
        let mean: f64 = mean.parse().map_err(|_| bad())?;
        if is_probe {
            stack.image.push((name.to_string(), mean));
            stack.image_calls = count;
        } else {
            stack
                .image_paths
                .push((format!("OsComTask send{name}"), count, mean));
        }
    }
    if stack.image.is_empty() {
        return Err("the image's log has no `stack probe` line".into());
    }
    Ok(())
}

/// Measures the probes and the ECU's paths on x86-64 (callgrind), showing the time left.
pub(super) fn measure_x86(stack: &mut Stack) -> Result {
    let binary = crate::callgrind::stack_probe_binary()?;
    let probes = crate::callgrind::STACK_PROBES;
    let bar = super::progress(
        probes.len() as u64,
        "stack probes on x86-64 (callgrind)",
        "probes",
    )?;
    stack.x86.clear();
    for &(op, _) in probes {
        stack
            .x86
            .push((op.to_string(), crate::callgrind::stack_probe(&binary, op)?));
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!("eval: the ECU's own paths on x86-64 (callgrind, cw-ecu on Figure 7)");
    stack.x86_paths = crate::callgrind::ecu_paths()?
        .into_iter()
        .map(|(what, measured)| {
            measured.map(|(per_call, calls)| (what.to_string(), per_call, calls))
        })
        .collect::<Result<_>>()?;
    Ok(())
}

fn figure(probes: &[(String, f64)], name: &str) -> Option<f64> {
    probes.iter().find(|(n, _)| n == name).map(|&(_, v)| v)
}

/// A layer's share in one setting.
fn share(probes: &[(String, f64)], layer: &Layer) -> Option<f64> {
    let from = figure(probes, layer.from)?;
    match layer.less {
        Some(less) => Some(from - figure(probes, less)?),
        None => Some(from),
    }
}

/// The check: every probe measured in both settings, finite and above zero, and both whole
/// paths there.
pub(super) fn check(stack: &Stack) -> Result {
    let names = TX
        .iter()
        .chain(&RX)
        .flat_map(|l| [Some(l.from), l.less])
        .flatten()
        .chain([TX_WHOLE.0, RX_WHOLE.0]);
    for name in names {
        for (setting, probes) in [
            ("the Cortex-M4 image", &stack.image),
            ("x86-64", &stack.x86),
        ] {
            match figure(probes, name) {
                Some(v) if v.is_finite() && v > 0.0 => {}
                Some(v) => {
                    return Err(format!(
                        "eval: the stack probe {name} on {setting} measured {v} instructions"
                    ))
                }
                None => {
                    return Err(format!(
                        "eval: the stack probe {name} on {setting} is missing"
                    ))
                }
            }
        }
    }
    if stack.image_paths.is_empty() {
        return Err("eval: the image's log has no span of OsComTask's send".into());
    }
    Ok(())
}

/// µs at the paper's clock, at one instruction per cycle.
fn us(instructions: f64) -> f64 {
    instructions / PAPER_MHZ
}

/// The report's section; the plots are under `plots_dir`.
pub(super) fn markdown(stack: &Stack, plots_dir: &str, md: &mut String) {
    let _ = writeln!(
        md,
        "\n## The communication stack, per layer (the paper's Figure 10)\n\n\
         The paper timed each layer with the Gpt module's timer, as the time from a layer's \
         call down less the time from the next layer's call down (its Figure 9), and gave \
         36 µs from the SWC to the CAN controller to transmit and 34 µs to receive on its \
         160 MHz MPC5748G. Here the same differences are taken between probes of the ECU's \
         own stack with its own configuration (`cw_firmware::stack_probe`: each probe one \
         function, from one layer's call down to a controller's mailbox in RAM, without the \
         OS's locks), counted in instructions: on the Cortex-M4 image by its trace ({} \
         calls each before the OS starts, its marks' cost taken off) and on x86-64 by \
         callgrind (the host build, `cargo xtask callgrind`). The time at 160 MHz assumes \
         one instruction per cycle, an assumption, not a measurement: the e200z4 is a \
         dual-issue core, and its flash wait states and caches are not modelled. Arctic Core \
         21's own Com, PduR and CanIf were counted the same way on x86-64 (gcc -O2, \
         callgrind: that build is not part of this repository, so its figures have no \
         command here). A layer's share can be below zero where the compiler inlines the \
         layers into each other: the whole path then costs less than its parts alone.\n",
        stack.image_calls
    );
    let row = |md: &mut String,
               name: &str,
               image: Option<f64>,
               x86: Option<f64>,
               arctic: Option<u64>,
               paper: Option<f64>| {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} | {} | {} |",
            f(image),
            image.map_or("-".to_string(), |v| format!("{:.2}", us(v))),
            f(x86),
            arctic.map_or("-".to_string(), |a| format!("{a} ({:.2} µs)", us(a as f64))),
            paper.map_or("-".to_string(), |p| format!("{p} µs")),
        );
    };
    for (direction, layers, whole, paper) in [
        ("Transmit", &TX[..], TX_WHOLE, PAPER_TX_US),
        ("Receive", &RX[..], RX_WHOLE, PAPER_RX_US),
    ] {
        let _ = writeln!(
            md,
            "**{direction}**\n\n\
             | layer | Cortex-M4 image (instructions) | at 160 MHz (µs) | x86-64 (instructions) | Arctic Core, x86-64 | the paper |\n\
             |---|---|---|---|---|---|"
        );
        for layer in layers {
            row(
                md,
                layer.name,
                share(&stack.image, layer),
                share(&stack.x86, layer),
                layer.arctic,
                None,
            );
        }
        row(
            md,
            "**whole path**",
            figure(&stack.image, whole.0),
            figure(&stack.x86, whole.0),
            Some(whole.1),
            Some(paper),
        );
        let _ = writeln!(
            md,
            "\n![{direction}: each layer at 160 MHz]({plots_dir}/{})\n",
            plot_name(direction)
        );
    }
    let _ = writeln!(
        md,
        "The ECU's own send, as it runs in `OsComTask` with its locks (`GetResource` and \
         `ReleaseResource` of `RES_COM`, both signals, the board's CAN controller):\n"
    );
    for (what, calls, mean) in &stack.image_paths {
        let _ = writeln!(
            md,
            "- Cortex-M4 image: {what}: {mean:.0} instructions per call ({calls} calls), \
             {:.2} µs at 160 MHz (the QEMU board's controller writes an SLCAN line: about 71 \
             of them);",
            us(*mean)
        );
    }
    for (what, per_call, calls) in &stack.x86_paths {
        let _ = writeln!(
            md,
            "- x86-64 (`cw-ecu` on Figure 7): {what}: {per_call:.0} instructions per call \
             ({calls} calls);"
        );
    }
    let _ = writeln!(
        md,
        "\nWhere this is stronger than the paper's figure: both settings count the same \
         source's instructions, deterministically, per layer and for the whole path, with \
         the command that reproduces them. Where it is weaker: instructions are not time on \
         a chip, and the probes drive a mailbox in RAM, not a FlexCAN's registers (the \
         FlexCAN driver's own paths are counted apart: [Performance](performance.md)).\n"
    );
}

/// The plot of one direction's layers.
pub(super) fn plot_name(direction: &str) -> String {
    format!("stack-{}.svg", direction.to_lowercase())
}

/// One bar chart per direction: each layer's µs at 160 MHz (one instruction per cycle) on
/// the image and Arctic Core's, and the paper's whole path, on a log scale.
pub(super) fn write_plots(stack: &Stack, dir: &Path) -> Result {
    for (direction, layers, whole, paper) in [
        ("Transmit", &TX[..], TX_WHOLE, PAPER_TX_US),
        ("Receive", &RX[..], RX_WHOLE, PAPER_RX_US),
    ] {
        let path = dir.join(plot_name(direction));
        bars(stack, direction, layers, whole, paper, &path)
            .map_err(|e| format!("plotting {}: {e}", path.display()))?;
    }
    Ok(())
}

fn bars(
    stack: &Stack,
    direction: &str,
    layers: &[Layer],
    whole: (&str, u64),
    paper: f64,
    path: &Path,
) -> std::result::Result<(), String> {
    let e = |e: &dyn std::fmt::Display| e.to_string();
    // (label, this ECU's image, Arctic Core, the paper), µs.
    type Row = (String, Option<f64>, Option<f64>, Option<f64>);
    let mut rows: Vec<Row> = layers
        .iter()
        .map(|l| {
            let short = l.name.split(" (").next().unwrap_or(l.name).to_string();
            (
                short,
                share(&stack.image, l).map(us),
                l.arctic.map(|a| us(a as f64)),
                None,
            )
        })
        .collect();
    rows.push((
        "whole path".into(),
        figure(&stack.image, whole.0).map(us),
        Some(us(whole.1 as f64)),
        Some(paper),
    ));
    let root = SVGBackend::new(path, (720, 80 + 60 * rows.len() as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let n = rows.len() as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{direction}: µs per layer at 160 MHz, one instruction per cycle (log scale)"),
            ("sans-serif", 14),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(200)
        .build_cartesian_2d((0.01f64..100.0).log_scale(), 0.0..n)
        .map_err(|x| e(&x))?;
    let labels: Vec<String> = rows.iter().map(|r| r.0.clone()).collect();
    chart
        .configure_mesh()
        .x_desc("µs")
        .y_labels(rows.len() * 2 + 1)
        .y_label_formatter(&|y| {
            let i = (n - *y - 0.5).round();
            if (n - *y - 0.5 - i).abs() < 0.01 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .draw()
        .map_err(|x| e(&x))?;
    let series: [(&str, RGBColor, usize); 3] = [
        ("this ECU, Cortex-M4 image", BLUE, 1),
        ("Arctic Core 21 (x86-64 count)", RED, 2),
        ("the paper, measured", BLACK, 3),
    ];
    for (label, color, k) in series {
        let bars: Vec<_> = rows
            .iter()
            .enumerate()
            .filter_map(|(i, r)| {
                let v = match k {
                    1 => r.1,
                    2 => r.2,
                    _ => r.3,
                }?;
                (v > 0.0).then(|| {
                    let top = n - i as f64 - 0.1 - 0.25 * (k - 1) as f64;
                    Rectangle::new([(0.01, top - 0.22), (v, top)], color.mix(0.7).filled())
                })
            })
            .collect();
        chart
            .draw_series(bars)
            .map_err(|x| e(&x))?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], color.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))
}

#[cfg(test)]
mod tests {
    use super::*;

    const LOG: &str = "cw-qemu: stack probe tx_path: 20 times, instructions mean 30 min 29 max 31\n\
        cw-qemu: span OsComTask send (Com, PduR, CanIf, controller, RES_COM): 375 times, instructions mean 167 min 160 max 170\n\
        cw-qemu: stack probe tx_com_down: 20 times, instructions mean 25 min 25 max 25\n";

    #[test]
    fn the_images_probes_and_send_are_read_and_a_bad_line_is_named() {
        let mut s = Stack::default();
        parse_image(LOG, &mut s).unwrap();
        assert_eq!(
            s.image,
            [
                ("tx_path".to_string(), 30.0),
                ("tx_com_down".to_string(), 25.0)
            ]
        );
        assert_eq!(s.image_paths.len(), 1);
        assert_eq!(s.image_paths[0].1, 375);
        let bad = LOG.replace("mean 25 min", "mean x min");
        assert!(parse_image(&bad, &mut Stack::default())
            .unwrap_err()
            .contains("line 3"));
        assert!(parse_image("", &mut Stack::default())
            .unwrap_err()
            .contains("no `stack probe`"));
    }

    #[test]
    fn a_layer_is_the_difference_to_the_next_and_a_missing_probe_fails_the_check() {
        let probes: Vec<(String, f64)> = [
            ("tx_path", 30.0),
            ("tx_com_down", 25.0),
            ("tx_pdur_down", 12.0),
            ("tx_can", 6.0),
            ("rx_path", 16.0),
            ("rx_canif", 18.0),
            ("rx_pdur_com", 24.0),
            ("rx_com_read", 2.0),
        ]
        .map(|(n, v)| (n.to_string(), v))
        .to_vec();
        assert_eq!(share(&probes, &TX[0]), Some(5.0));
        assert_eq!(share(&probes, &TX[1]), Some(13.0));
        assert_eq!(share(&probes, &TX[2]), Some(6.0));
        assert_eq!(share(&probes, &TX[3]), Some(6.0));
        let mut s = Stack {
            image: probes.clone(),
            image_calls: 20,
            x86: probes,
            image_paths: vec![("send".into(), 1, 167.0)],
            x86_paths: vec![],
        };
        assert_eq!(check(&s), Ok(()));
        s.x86.retain(|(n, _)| n != "tx_can");
        assert!(check(&s)
            .unwrap_err()
            .contains("tx_can on x86-64 is missing"));
    }
}
