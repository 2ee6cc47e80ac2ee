//! The `setup` stage: check every tool the later stages use and install what is missing.
//! Each check runs first, so a second run on a ready machine only reads versions.

use crate::process::{root, Cmd};
use crate::Result;
use std::path::PathBuf;

/// The pinned nightly used for Miri and the libFuzzer engine. `nightly-2026-05-20` is
/// `rustc 1.97.0-nightly (e50aa6fba 2026-05-19)`: checked with
/// `rustup toolchain install nightly-2026-05-20 --profile minimal` and `rustup run
/// nightly-2026-05-20 rustc -V` (a dated channel carries the previous day's build).
pub const NIGHTLY: &str = "nightly-2026-05-20";

/// Components the pinned nightly needs (Miri, and the library sources Miri builds its
/// sysroot from, for the host and for s390x; LLVM's profile tools for the coverage stage).
const NIGHTLY_COMPONENTS: &[&str] = &["miri", "rust-src", "llvm-tools", "clippy"];

/// Components of the default (stable) toolchain.
const STABLE_COMPONENTS: &[&str] = &["rustfmt", "clippy"];

/// Cross targets: the Cortex-M4F of the QEMU board and the S32K144, big-endian s390x for
/// Miri. (The MPC5748G's Book E target, `targets/powerpc-e200-none-eabi.json`, has no
/// rustup target: the nightly builds its `core` from `rust-src`.)
pub const TARGETS: &[&str] = &["thumbv7em-none-eabihf", "s390x-unknown-linux-gnu"];

/// The cargo-bolero version the fuzz stage is written against.
pub const CARGO_BOLERO_VERSION: &str = "0.13.5";

/// The cargo-mutants version the `mutation` stage is written against (its `mutants.out`
/// layout and exit codes).
pub const CARGO_MUTANTS_VERSION: &str = "27.1.0";

/// The cargo-llvm-cov version the `coverage` stage is written against (its JSON export).
pub const CARGO_LLVM_COV_VERSION: &str = "0.9.1";

/// The defmt-print version that decodes the image's log (defmt 1.x, wire format 4).
pub const DEFMT_PRINT_VERSION: &str = "1.2.0";

/// The mdBook version that builds the book (`cargo xtask docs`, `cargo xtask book`).
pub const MDBOOK_VERSION: &str = "0.5.4";

/// mdBook's features: only the search index. The default features also have `serve` and
/// `watch` (`mdbook serve`), which pull in an HTTP server and a file watcher that building
/// and checking the book never use.
const MDBOOK_FEATURES: &[&str] = &["--no-default-features", "--features", "search"];

/// Python virtual environment for the cantools / python-can tools (gitignored).
pub fn venv_dir() -> PathBuf {
    root().join(".venv")
}

/// The venv's interpreter.
pub fn venv_python() -> PathBuf {
    venv_dir().join("bin").join("python")
}

/// A Python tool of `tools/` run by the venv's interpreter (cantools, python-can), with
/// `args` after the script.
///
/// # Errors
/// The venv is missing (`cargo xtask setup` makes it), or the tool fails.
pub fn run_python_tool(script: &str, args: &[&std::path::Path]) -> Result {
    let python = venv_python();
    if !python.exists() {
        return Err(format!(
            "{} not found: the cantools / python-can venv is missing; run `cargo xtask setup` (or `cargo xtask ci --only setup`)",
            python.display()
        ));
    }
    let mut cmd = Cmd::new(&python).arg(root().join("tools").join(script));
    for a in args {
        cmd = cmd.arg(a);
    }
    cmd.run()
}

/// Runs every check and installation of the `setup` stage.
pub fn run() -> Result {
    rustup_stable()?;
    rustup_targets()?;
    rustup_nightly()?;
    cargo_bolero()?;
    cargo_mutants()?;
    cargo_llvm_cov()?;
    defmt_print()?;
    mdbook()?;
    valgrind()?;
    qemu()?;
    debian_tool("llvm-symbolizer", &["--version"], "llvm")?;
    // The `view` stage opens `cw-can view` in it, headless.
    debian_tool("chromium", &["--version"], "chromium")?;
    python_venv()?;
    Ok(())
}

/// Names in `rustup ... list --installed` output (first word of each line).
fn installed(list: &str) -> Vec<String> {
    list.lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

/// Whether a component named `name` (e.g. `miri` for `miri-x86_64-unknown-linux-gnu`) is
/// in an installed-components list.
fn has_component(installed: &[String], name: &str) -> bool {
    installed
        .iter()
        .any(|c| c == name || c.starts_with(&format!("{name}-")))
}

fn rustup_stable() -> Result {
    let list = installed(
        &Cmd::new("rustup")
            .args(["component", "list", "--installed"])
            .read()?,
    );
    let missing: Vec<&str> = STABLE_COMPONENTS
        .iter()
        .copied()
        .filter(|c| !has_component(&list, c))
        .collect();
    if missing.is_empty() {
        println!("ok: components {} installed", STABLE_COMPONENTS.join(", "));
        return Ok(());
    }
    Cmd::new("rustup")
        .args(["component", "add"])
        .args(STABLE_COMPONENTS)
        .run()
}

fn rustup_targets() -> Result {
    let list = installed(
        &Cmd::new("rustup")
            .args(["target", "list", "--installed"])
            .read()?,
    );
    if TARGETS.iter().all(|t| list.iter().any(|i| i == t)) {
        println!("ok: targets {} installed", TARGETS.join(", "));
        return Ok(());
    }
    Cmd::new("rustup")
        .args(["target", "add"])
        .args(TARGETS)
        .run()
}

fn rustup_nightly() -> Result {
    let toolchains = installed(&Cmd::new("rustup").args(["toolchain", "list"]).read()?);
    let present = toolchains
        .iter()
        .any(|t| t == NIGHTLY || t.starts_with(&format!("{NIGHTLY}-")));
    let components_ok = present && {
        let list = installed(
            &Cmd::new("rustup")
                .args(["component", "list", "--installed", "--toolchain", NIGHTLY])
                .read()?,
        );
        NIGHTLY_COMPONENTS.iter().all(|c| has_component(&list, c))
    };
    if !components_ok {
        Cmd::new("rustup")
            .args([
                "toolchain",
                "install",
                NIGHTLY,
                "--profile",
                "minimal",
                "--component",
            ])
            .arg(NIGHTLY_COMPONENTS.join(","))
            .run()?;
    }
    let version = Cmd::new("rustup")
        .args(["run", NIGHTLY, "rustc", "-V"])
        .read()?;
    println!(
        "ok: {NIGHTLY} is {} with {}",
        version.trim(),
        NIGHTLY_COMPONENTS.join(", ")
    );
    Ok(())
}

fn cargo_bolero() -> Result {
    cargo_tool(
        "cargo",
        &["bolero", "--version"],
        "cargo-bolero",
        CARGO_BOLERO_VERSION,
        &[],
    )
}

/// Mutation testing of the kernels (`cargo xtask mutation`).
fn cargo_mutants() -> Result {
    cargo_tool(
        "cargo",
        &["mutants", "--version"],
        "cargo-mutants",
        CARGO_MUTANTS_VERSION,
        &[],
    )
}

/// Branch coverage of the core (`cargo xtask coverage`).
fn cargo_llvm_cov() -> Result {
    cargo_tool(
        "cargo",
        &["llvm-cov", "--version"],
        "cargo-llvm-cov",
        CARGO_LLVM_COV_VERSION,
        &[],
    )
}

/// The decoder of the image's defmt log (`cw_tests::qemu`).
fn defmt_print() -> Result {
    cargo_tool(
        "defmt-print",
        &["--version"],
        "defmt-print",
        DEFMT_PRINT_VERSION,
        &[],
    )
}

/// The probe-rs version that writes the S32K144EVB's image (`cargo xtask s32k144
/// --flash`): its target list names the chip [`crate::s32k144::PROBE_RS_CHIP`].
pub const PROBE_RS_VERSION: &str = "0.32.0";

/// probe-rs (crate `probe-rs-tools`), installed if missing: only `cargo xtask s32k144
/// --flash` needs it (the check command has no board to write to). It prints its version
/// as `probe-rs VERSION (git commit: ...)`.
pub fn probe_rs() -> Result {
    let found = tool_line("probe-rs", &["--version"]);
    let says = |line: &str| line.starts_with(&format!("probe-rs {PROBE_RS_VERSION}"));
    if let Some(line) = found.as_deref().filter(|l| says(l)) {
        println!("ok: {line}");
        return Ok(());
    }
    println!(
        "probe-rs: wanted {PROBE_RS_VERSION}, found {}; installing probe-rs-tools (a few minutes)",
        found.map_or_else(|| "none".into(), |f| format!("`{f}`"))
    );
    Cmd::new("cargo")
        .args([
            "install",
            "--locked",
            "probe-rs-tools",
            "--version",
            PROBE_RS_VERSION,
        ])
        .run()?;
    match tool_line("probe-rs", &["--version"]) {
        Some(line) if says(&line) => {
            println!("ok: {line}");
            Ok(())
        }
        other => Err(format!(
            "probe-rs-tools {PROBE_RS_VERSION} installed, but `probe-rs --version` says {} \
             (is another probe-rs earlier on PATH?)",
            other.map_or_else(|| "nothing".into(), |f| format!("`{f}`"))
        )),
    }
}

/// The book's builder (`cargo xtask docs`, `cargo xtask book`), installed if missing.
pub fn mdbook() -> Result {
    cargo_tool(
        "mdbook",
        &["--version"],
        "mdbook",
        MDBOOK_VERSION,
        MDBOOK_FEATURES,
    )
}

/// Fails unless mdBook is installed at [`MDBOOK_VERSION`], naming `cargo xtask setup`
/// (which installs it); installs nothing.
pub fn require_mdbook() -> Result {
    match tool_line("mdbook", &["--version"]) {
        Some(line) if says_version(&line, "mdbook", MDBOOK_VERSION) => Ok(()),
        found => Err(format!(
            "mdBook {MDBOOK_VERSION} is needed to build the book, found {}; \
             `cargo xtask setup` installs it",
            found.map_or_else(|| "none".into(), |f| format!("`{f}`"))
        )),
    }
}

/// The first line `program probe..` prints, when it runs and exits 0.
fn tool_line(program: &str, probe: &[&str]) -> Option<String> {
    match Cmd::new(program).args(probe).capture() {
        Ok(out) if out.success => Some(out.stdout.lines().next().unwrap_or("").trim().into()),
        _ => None,
    }
}

/// Whether a tool's version line names `krate` at `version`: `cargo-bolero 0.13.5`, or with
/// a `v` as mdBook prints it, `mdbook v0.5.4`.
fn says_version(line: &str, krate: &str, version: &str) -> bool {
    line == format!("{krate} {version}") || line == format!("{krate} v{version}")
}

/// Checks that `program probe..` names crate `krate` at `version` on its first line (see
/// [`says_version`]); if not, installs that version with `cargo install --locked`, followed
/// by `install_args` (features), and checks again.
fn cargo_tool(
    program: &str,
    probe: &[&str],
    krate: &str,
    version: &str,
    install_args: &[&str],
) -> Result {
    let wanted = format!("{krate} {version}");
    let found = tool_line(program, probe);
    if let Some(line) = found.as_deref().filter(|l| says_version(l, krate, version)) {
        println!("ok: {line}");
        return Ok(());
    }
    println!(
        "{krate}: wanted `{wanted}`, found {}",
        found.map_or_else(|| "none".into(), |f| format!("`{f}`"))
    );
    Cmd::new("cargo")
        .args(["install", "--locked", krate, "--version", version])
        .args(install_args)
        .run()?;
    let out = Cmd::new(program).args(probe).read()?;
    let found = out.lines().next().unwrap_or("").trim();
    if says_version(found, krate, version) {
        println!("ok: {found}");
        Ok(())
    } else {
        Err(format!(
            "{krate}: installed version {version} but `{program} {}` says `{found}` \
             (is another {krate} earlier on PATH?)",
            probe.join(" ")
        ))
    }
}

fn valgrind() -> Result {
    debian_tool("valgrind", &["--version"], "valgrind")
}

fn qemu() -> Result {
    debian_tool("qemu-system-arm", &["--version"], "qemu-system-arm")
}

/// Checks that `program` runs (`program probe..` exits 0); if not, installs the Debian
/// `package` with apt-get when running as root, and fails loudly otherwise.
fn debian_tool(program: &str, probe_args: &[&str], package: &str) -> Result {
    let probe = Cmd::new(program).args(probe_args).capture();
    if let Ok(out) = &probe {
        if out.success {
            println!("ok: {}", out.stdout.lines().next().unwrap_or("").trim());
            return Ok(());
        }
    }
    let why = match probe {
        Ok(out) => format!("`{program}` failed: {}", out.stderr.trim()),
        Err(e) => e,
    };
    let uid = Cmd::new("id").arg("-u").read().unwrap_or_default();
    if uid.trim() != "0" {
        return Err(format!(
            "{program} is missing ({why}); not running as root, so it cannot be installed \
             here: install it (Debian/Ubuntu: `sudo apt-get install {package}`) and run again"
        ));
    }
    println!("{program} missing ({why}); installing {package} with apt-get");
    Cmd::new("apt-get")
        .env("DEBIAN_FRONTEND", "noninteractive")
        .arg("update")
        .run()
        .map_err(|e| format!("installing {package}: {e}"))?;
    Cmd::new("apt-get")
        .env("DEBIAN_FRONTEND", "noninteractive")
        .args(["install", "-y", package])
        .run()
        .map_err(|e| format!("installing {package}: {e}"))?;
    let version = Cmd::new(program).args(probe_args).read()?;
    println!("ok: {}", version.lines().next().unwrap_or("").trim());
    Ok(())
}

fn python_venv() -> Result {
    let requirements_path = root().join("tools").join("requirements.txt");
    let requirements = std::fs::read_to_string(&requirements_path)
        .map_err(|e| format!("reading {}: {e}", requirements_path.display()))?;
    let python = venv_python();
    let stamp = venv_dir().join(".xtask-requirements.txt");
    let up_to_date =
        python.exists() && std::fs::read_to_string(&stamp).is_ok_and(|s| s == requirements);
    if up_to_date {
        // The stamp says pip installed exactly these pins; make sure they still import.
        let check = Cmd::new(&python)
            .args(["-c", "import cantools, can, serial, websocket, canmatrix, lxml; print('cantools', cantools.__version__, '/ python-can', can.__version__, '/ pyserial', serial.__version__, '/ websocket-client', websocket.__version__, '/ canmatrix', canmatrix.__version__)"])
            .capture()?;
        if check.success {
            println!("ok: .venv has {}", check.stdout.trim());
            return Ok(());
        }
        println!(
            "the .venv does not import its tools any more; reinstalling:\n{}",
            check.stderr
        );
    }
    if !python.exists() {
        Cmd::new("python3")
            .args(["-m", "venv"])
            .arg(venv_dir())
            .run()
            .map_err(|e| {
                format!("{e}\n(on Debian/Ubuntu `python3 -m venv` needs the python3-venv package)")
            })?;
    }
    Cmd::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "--no-input",
            "-r",
        ])
        .arg(&requirements_path)
        .run()?;
    Cmd::new(&python)
        .args(["-c", "import cantools, can, serial, websocket, canmatrix, lxml; print('cantools', cantools.__version__, '/ python-can', can.__version__, '/ pyserial', serial.__version__, '/ websocket-client', websocket.__version__, '/ canmatrix', canmatrix.__version__)"])
        .run()?;
    std::fs::write(&stamp, requirements).map_err(|e| format!("writing {}: {e}", stamp.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_version_line_names_the_crate_and_version_with_or_without_a_v() {
        assert!(says_version(
            "cargo-bolero 0.13.5",
            "cargo-bolero",
            "0.13.5"
        ));
        assert!(says_version("mdbook v0.5.4", "mdbook", "0.5.4"));
        assert!(!says_version("mdbook v0.5.3", "mdbook", "0.5.4"));
        assert!(!says_version("mdbook v0.5.40", "mdbook", "0.5.4"));
        assert!(!says_version("mdbook", "mdbook", "0.5.4"));
    }
}
