//! `cargo xtask s32k144 [--uart-sensor] [--flash] [--probe SELECTOR]`: the ECU's image
//! for NXP's S32K144EVB (`cw-s32k144`, profile `flash`; with the HC-SR04, or the UART
//! ranging module on LPUART0), built and checked as it will lie in the chip's flash, then,
//! with `--flash`, written to a board through a debug probe with probe-rs, run, and its
//! defmt log shown.
//!
//! The checks read the linked ELF back (`llvm-size -A`, `llvm-objcopy --dump-section`):
//!
//! - the flash configuration field is 16 bytes at 0x400 and equals
//!   `cw_bsp::s32k144evb::FLASH_CONFIG` (unsecured, mass erase enabled): a wrong byte
//!   there can lock the chip for good;
//! - the vector table ends below 0x400, its initial stack pointer is the top of SRAM_U
//!   (0x2000_7000), its reset vector a Thumb address inside `.text`, and FlexCAN0's lines
//!   (`CAN_IRQS`) have a handler other than the one of unused lines;
//! - flash and RAM fit the chip (512 KiB, and the 28 KiB of SRAM_U the image uses), and
//!   both are printed.

use std::path::{Path, PathBuf};

use cw_bsp::s32k144evb::{CAN_IRQS, FLASH_CONFIG, IRQ_LINES};

use crate::image::{build_bin, footprint, section, section_bytes, sections};
use crate::process::Cmd;
use crate::Result;

/// The chip as probe-rs's target list names it: its S32K144 in the 100-pin LQFP, which
/// covers the EVB's part S32K144HFT0VLLT (probe-rs 0.32.0 matches that name to this one
/// with a warning).
pub const PROBE_RS_CHIP: &str = "S32K144HFxxxLLx";

/// The image's program flash and the RAM it links into (SRAM_U).
const FLASH_BYTES: u64 = 512 * 1024;
const RAM_BYTES: u64 = 28 * 1024;
/// The top of SRAM_U: the initial main stack pointer.
const RAM_END: u32 = 0x2000_7000;
/// Where the flash configuration field lies.
const FLASH_CONFIG_ADDRESS: u64 = 0x400;

/// `cargo xtask s32k144`'s options.
#[derive(clap::Args)]
pub struct Options {
    /// Then write the image to the board through a debug probe (probe-rs, installed if
    /// missing), reset it and show its defmt log until Ctrl-C
    #[arg(long)]
    flash: bool,
    /// The image with a UART ranging module on LPUART0 (PTB0) as its sensor instead of
    /// the HC-SR04
    #[arg(long)]
    uart_sensor: bool,
    /// The probe to use when several are attached (probe-rs's `VID:PID[:SERIAL]`)
    #[arg(long, value_name = "VID:PID[:SERIAL]")]
    probe: Option<String>,
}

/// Runs `cargo xtask s32k144`.
pub fn run(options: &Options) -> Result {
    let image = build_variant(options.uart_sensor)?;
    if options.flash {
        flash(&image, options.probe.as_deref())?;
    }
    Ok(())
}

/// Builds `cw-s32k144` with the HC-SR04 (profile `flash`) and checks it; returns its path.
pub fn build() -> Result<PathBuf> {
    build_variant(false)
}

/// Builds `cw-s32k144` with the HC-SR04 or, if `uart_sensor`, the UART ranging module
/// (profile `flash`), and checks it; returns its path.
fn build_variant(uart_sensor: bool) -> Result<PathBuf> {
    let features = if uart_sensor {
        "s32k144evb-uart"
    } else {
        "s32k144evb"
    };
    let image = build_bin("cw-s32k144", features, "flash")?;
    check(&image)?;
    Ok(image)
}

fn word(bytes: &[u8], index: usize) -> Result<u32> {
    bytes
        .get(4 * index..4 * index + 4)
        .and_then(|w| w.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or_else(|| format!("the vector table has no entry {index}"))
}

/// The image's checks (the module's list); prints its flash and RAM.
pub fn check(image: &Path) -> Result {
    let sections = sections(image)?;
    let find = |name: &str| section(&sections, image, name);
    let (fcf_addr, fcf_size) = find(".flash_config")?;
    if (fcf_addr, fcf_size) != (FLASH_CONFIG_ADDRESS, 16) {
        return Err(format!(
            "the flash configuration field is {fcf_size} bytes at {fcf_addr:#x}, not 16 at 0x400"
        ));
    }
    let fcf = section_bytes(image, ".flash_config")?;
    if fcf != FLASH_CONFIG.bytes() {
        return Err(format!(
            "the flash configuration field holds {fcf:02x?}, not the unsecured {:02x?}",
            FLASH_CONFIG.bytes()
        ));
    }
    let (vt_addr, vt_size) = find(".vector_table")?;
    if vt_addr != 0 || vt_addr + vt_size > FLASH_CONFIG_ADDRESS {
        return Err(format!(
            "the vector table lies at {vt_addr:#x}..{:#x}: it must start at 0 and end below 0x400",
            vt_addr + vt_size
        ));
    }
    let vectors = section_bytes(image, ".vector_table")?;
    if vectors.len() != 4 * (16 + IRQ_LINES) {
        return Err(format!(
            "the vector table has {} entries, not the S32K144's 16 + {IRQ_LINES}",
            vectors.len() / 4
        ));
    }
    let (text_addr, text_size) = find(".text")?;
    let sp = word(&vectors, 0)?;
    let reset = word(&vectors, 1)?;
    if sp != RAM_END {
        return Err(format!(
            "the initial stack pointer is {sp:#x}, not SRAM_U's top {RAM_END:#x}"
        ));
    }
    let in_text =
        |pc: u32| pc & 1 == 1 && (text_addr..text_addr + text_size).contains(&u64::from(pc & !1));
    if !in_text(reset) {
        return Err(format!(
            "the reset vector {reset:#x} is not a Thumb address in .text"
        ));
    }
    let unused = word(&vectors, 16)?;
    for line in CAN_IRQS {
        let handler = word(&vectors, 16 + usize::from(line))?;
        if handler == unused || !in_text(handler) {
            return Err(format!(
                "FlexCAN0's line {line} has no handler of its own ({handler:#x})"
            ));
        }
    }
    let (flash, ram) = footprint(image)?;
    let flash = flash + fcf_size;
    if flash > FLASH_BYTES || ram > RAM_BYTES {
        return Err(format!(
            "the image needs {flash} B of flash and {ram} B of RAM: more than the S32K144's \
             {FLASH_BYTES} and SRAM_U's {RAM_BYTES}"
        ));
    }
    println!(
        "s32k144: cw-s32k144 (opt-level z): flash {flash} B = {:.1} KiB of 512 KiB, RAM {ram} B = {:.1} KiB of SRAM_U's 28 KiB",
        flash as f64 / 1024.0,
        ram as f64 / 1024.0
    );
    println!(
        "s32k144: flash configuration at 0x400: {fcf:02x?} (unsecured, mass erase enabled); \
         vector table 0x0..{:#x}, stack {sp:#x}, reset {reset:#x}, CAN lines {CAN_IRQS:?} handled",
        vt_addr + vt_size
    );
    println!("s32k144: {}", image.display());
    Ok(())
}

/// Writes `image` to the board through the probe, resets it and shows its log (probe-rs
/// `run`: flash, reset, then the defmt frames from RTT, decoded with the ELF).
pub fn flash(image: &Path, probe: Option<&str>) -> Result {
    crate::setup::probe_rs()?;
    let mut cmd = Cmd::new("probe-rs")
        .args(["run", "--chip", PROBE_RS_CHIP])
        .arg(image);
    if let Some(probe) = probe {
        cmd = cmd.args(["--probe", probe]);
    }
    cmd.run().map_err(|e| {
        format!(
            "{e}\nprobe-rs needs a debug probe it supports (a J-Link, or a CMSIS-DAP \
             probe) on the EVB's SWD connector and the board powered; the book's \
             \"Flashing\" section says more (docs/src/nxp-boards.md)"
        )
    })
}
