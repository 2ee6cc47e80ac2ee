//! The memory layout of the board the image is linked for (cortex-m-rt's `memory.x`), and
//! the interrupt vector's default names (`device.x`; each board defines its whole vector
//! itself, so the file is empty).
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/mps2/memory.x");
    println!("cargo:rerun-if-changed=src/s32k144evb/memory.x");
    println!("cargo:rerun-if-changed=src/mpc5748g/mpc5748g.ld");
    let target = std::env::var("TARGET").unwrap_or_default();
    if target.starts_with("powerpc-e200") && std::env::var_os("CARGO_FEATURE_MPC5748G").is_some() {
        search_beside("src/mpc5748g/mpc5748g.ld", "mpc5748g.ld", false);
        return;
    }
    if !target.starts_with("thumbv7em") {
        return;
    }
    let layout = if std::env::var_os("CARGO_FEATURE_S32K144EVB").is_some() {
        "src/s32k144evb/memory.x"
    } else if std::env::var_os("CARGO_FEATURE_MPS2").is_some() {
        "src/mps2/memory.x"
    } else {
        return;
    };
    search_beside(layout, "memory.x", true);
}

/// Copies the linker script `from` into OUT_DIR as `name` (with an empty `device.x` for
/// cortex-m-rt if `device`) and puts OUT_DIR on the linker's search path.
fn search_beside(from: &str, name: &str, device: bool) {
    let Some(out) = std::env::var_os("OUT_DIR").map(PathBuf::from) else {
        println!("cargo:warning=OUT_DIR is not set");
        return;
    };
    let copied = std::fs::copy(from, out.join(name)).and_then(|_| {
        if device {
            std::fs::write(out.join("device.x"), "")
        } else {
            Ok(())
        }
    });
    if let Err(e) = copied {
        println!("cargo:warning=cannot write the linker scripts: {e}");
        return;
    }
    println!("cargo:rustc-link-search={}", out.display());
}
