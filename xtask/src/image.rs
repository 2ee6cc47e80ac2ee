//! The boards' images: building one of cw-firmware's image binaries, and reading an ELF
//! back (its sections' addresses and sizes, a section's bytes, flash and RAM) with the
//! LLVM tools, for the checks of `cargo xtask qemu`, `s32k144` and `mpc5748g`.

use std::path::{Path, PathBuf};

use crate::process::{target_dir, Cmd};
use crate::Result;

/// The Cortex-M images' target.
const TARGET: &str = "thumbv7em-none-eabihf";

/// Builds image `bin` of cw-firmware for the board with `features` and cargo `profile`;
/// returns its path. (Each image is built on its own: its features are its own.)
pub fn build_bin(bin: &str, features: &str, profile: &str) -> Result<PathBuf> {
    Cmd::new("cargo")
        .args([
            "build",
            "--profile",
            profile,
            "-p",
            "cw-firmware",
            "--no-default-features",
            "--features",
            features,
            "--bin",
            bin,
            "--target",
            TARGET,
        ])
        .run()?;
    Ok(target_dir().join(TARGET).join(profile).join(bin))
}

/// Flash (vector table, code, read-only data, `.data`'s initial values) and RAM (`.data`,
/// `.bss`, `.uninit`: the task stack) of `image`, in bytes, from `llvm-size -A`.
pub fn footprint(image: &Path) -> Result<(u64, u64)> {
    let out = Cmd::new("llvm-size").arg("-A").arg(image).read()?;
    let size = |name: &str| {
        out.lines()
            .find_map(|l| {
                let mut words = l.split_whitespace();
                (words.next() == Some(name)).then(|| words.next()?.parse::<u64>().ok())?
            })
            .unwrap_or(0)
    };
    let flash = [".vector_table", ".text", ".rodata", ".data"]
        .map(size)
        .iter()
        .sum();
    let ram = [".data", ".bss", ".uninit"].map(size).iter().sum();
    Ok((flash, ram))
}

/// The address and size of each allocated section, from `llvm-size -A`.
pub fn sections(image: &Path) -> Result<Vec<(String, u64, u64)>> {
    let out = Cmd::new("llvm-size").arg("-A").arg(image).read()?;
    Ok(out
        .lines()
        .filter_map(|line| {
            let mut words = line.split_whitespace();
            let name = words.next()?;
            let size = words.next()?.parse().ok()?;
            let addr = words.next()?.parse().ok()?;
            name.starts_with('.')
                .then(|| (name.to_string(), addr, size))
        })
        .collect())
}

/// The address and size of section `name` among `sections` (of `image`, for the error).
pub fn section(sections: &[(String, u64, u64)], image: &Path, name: &str) -> Result<(u64, u64)> {
    sections
        .iter()
        .find(|(n, _, _)| n == name)
        .map(|&(_, addr, size)| (addr, size))
        .ok_or_else(|| format!("{}: no {name} section", image.display()))
}

/// The bytes of section `name` of `image`.
pub fn section_bytes(image: &Path, name: &str) -> Result<Vec<u8>> {
    let out = target_dir().join("elf-sections");
    std::fs::create_dir_all(&out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let file = out.join(format!("{}.bin", name.trim_start_matches('.')));
    Cmd::new("llvm-objcopy")
        .arg("--dump-section")
        .arg(format!("{name}={}", file.display()))
        .arg(image)
        .arg(out.join("objcopy-scratch.elf"))
        .run()?;
    std::fs::read(&file).map_err(|e| format!("reading {}: {e}", file.display()))
}
