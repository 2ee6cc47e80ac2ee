//! `cargo xtask mpc5748g`: the paper's board's layer (MPC574XG-MB) built for its MCU
//! with the pinned nightly (`-Z build-std=core` for the Book E target
//! `targets/powerpc-e200-none-eabi.json`), linked into the bring-up image `cw-mpc5748g`,
//! and checked from its ELF:
//!
//! - a 32-bit big-endian PowerPC executable;
//! - the boot header, 24 bytes at 0x00F9_0000: the boot ID 0x5A with core Z4A enabled,
//!   Z4A's start address the ELF's entry (`_start`, inside `.text`), the other cores'
//!   and the reserved words 0;
//! - `.data` and `.bss` inside the boot core's 256 KiB of SRAM from 0x4000_0000.
//!
//! Flash and RAM are printed. The image cannot run on the MPC5748G (its cores execute
//! only VLE code); nothing here runs it.

use std::path::{Path, PathBuf};

use cw_bsp::mpc5748g::{BOOT_HEADER_ADDRESS, BOOT_ID_Z4A};

use crate::image::{section, section_bytes, sections};
use crate::process::{root, target_dir, Cmd};
use crate::setup::NIGHTLY;
use crate::Result;

/// The target's specification, and its name (cargo's folder under `target/`).
const TARGET_SPEC: &str = "targets/powerpc-e200-none-eabi.json";
const TARGET: &str = "powerpc-e200-none-eabi";
/// The boot core's SRAM.
const RAM: std::ops::Range<u64> = 0x4000_0000..0x4004_0000;

/// Runs `cargo xtask mpc5748g`: clippy, the build, the checks.
pub fn run() -> Result {
    clippy()?;
    let image = build()?;
    check(&image)
}

/// clippy (the pinned nightly's) on the board layer and the image for the Book E target,
/// warnings denied: the code no host build compiles (the start-up, the bring-up).
pub fn clippy() -> Result {
    cargo("clippy", "release")
        .args(["--", "-D", "warnings"])
        .run()
}

/// Builds `cw-mpc5748g` (profile `flash`); returns its path.
pub fn build() -> Result<PathBuf> {
    cargo("build", "flash").run()?;
    Ok(target_dir().join(TARGET).join("flash").join("cw-mpc5748g"))
}

/// `cargo +NIGHTLY SUBCOMMAND` on `cw-mpc5748g` for the Book E target with `profile`.
fn cargo(subcommand: &str, profile: &str) -> Cmd {
    Cmd::new("cargo")
        .arg(format!("+{NIGHTLY}"))
        .args([
            subcommand,
            "-Z",
            "build-std=core",
            "-Z",
            "json-target-spec",
            "-p",
            "cw-firmware",
            "--bin",
            "cw-mpc5748g",
            "--no-default-features",
            "--features",
            "mpc5748g",
            "--profile",
            profile,
            "--target",
        ])
        .arg(root().join(TARGET_SPEC))
}

/// The 32-bit big-endian word at `index` of `bytes`.
fn word(bytes: &[u8], index: usize) -> Result<u32> {
    bytes
        .get(4 * index..4 * index + 4)
        .and_then(|w| w.try_into().ok())
        .map(u32::from_be_bytes)
        .ok_or_else(|| format!("the boot header has no word {index}"))
}

/// The image's checks (the module's list); prints its flash and RAM.
pub fn check(image: &Path) -> Result {
    let header = Cmd::new("llvm-readelf").arg("-h").arg(image).read()?;
    let field = |name: &str| {
        header
            .lines()
            .find_map(|l| l.trim().strip_prefix(name).map(|v| v.trim().to_string()))
            .unwrap_or_default()
    };
    if !field("Class:").contains("ELF32")
        || !field("Data:").contains("big endian")
        || !field("Machine:").contains("PowerPC")
    {
        return Err(format!(
            "{} is not a 32-bit big-endian PowerPC ELF:\n{header}",
            image.display()
        ));
    }
    let entry = u64::from_str_radix(field("Entry point address:").trim_start_matches("0x"), 16)
        .map_err(|e| format!("the ELF's entry address: {e}"))?;
    let sections = sections(image)?;
    let find = |name: &str| section(&sections, image, name);
    let (boot_addr, boot_size) = find(".boot_header")?;
    if (boot_addr, boot_size) != (u64::from(BOOT_HEADER_ADDRESS), 24) {
        return Err(format!(
            "the boot header is {boot_size} bytes at {boot_addr:#x}, not 24 at {BOOT_HEADER_ADDRESS:#x}"
        ));
    }
    let boot = section_bytes(image, ".boot_header")?;
    let words = (0..6).map(|i| word(&boot, i)).collect::<Result<Vec<_>>>()?;
    let (text_addr, text_size) = find(".text")?;
    let start = u64::from(words.get(4).copied().unwrap_or(0));
    if words.first() != Some(&BOOT_ID_Z4A)
        || start != entry
        || !(text_addr..text_addr + text_size).contains(&start)
        || [1, 2, 3, 5].iter().any(|&i| words.get(i) != Some(&0))
    {
        return Err(format!(
            "the boot header holds {words:08x?}: not the boot ID {BOOT_ID_Z4A:#010x}, Z4A \
             starting at the entry {entry:#x} in .text, the rest 0"
        ));
    }
    let (data_addr, data_size) = find(".data")?;
    let (bss_addr, bss_size) = find(".bss")?;
    for (name, addr, size) in [
        (".data", data_addr, data_size),
        (".bss", bss_addr, bss_size),
    ] {
        if size > 0 && !(RAM.start <= addr && addr + size <= RAM.end) {
            return Err(format!(
                "{name} lies at {addr:#x}..{:#x}, outside the boot core's SRAM",
                addr + size
            ));
        }
    }
    let rodata = find(".rodata").map_or(0, |(_, size)| size);
    let flash = boot_size + text_size + rodata + data_size;
    let ram = data_size + bss_size;
    println!(
        "mpc5748g: cw-mpc5748g (Book E, opt-level z): flash {flash} B = {:.1} KiB, RAM {ram} B (and the stack, from the top of the boot core's 256 KiB)",
        flash as f64 / 1024.0
    );
    println!(
        "mpc5748g: boot header at {boot_addr:#x}: {words:08x?} (boot ID 0x5A, Z4A starts at {entry:#x}, _start); 32-bit big-endian PowerPC; cannot run on the MPC5748G (VLE only)"
    );
    Ok(())
}
