//! `cargo xtask view` (the check command's `view` stage): `cw-can view` as a person sees
//! it. The ECU simulation writes its Figure 7 log and trace and a 30-minute log; then
//! `tools/view_check.py` replays them in `cw-can view` (the debug build), opens the page in
//! headless Chromium over the DevTools protocol and checks the scene, the LEDs and the
//! readout at 0.5, 1.0, 1.5 and 2.0 m against the trace, the fault and "no signal"
//! pictures, bad lines, ten clients (five cut mid-stream) and the server's memory over the
//! long replay. The four screenshots (the paper's Figure 8 a-d) go to `docs/src/view/`.

use crate::ci::ecu_run;
use crate::process::{root, target_dir, Cmd};
use crate::Result;

/// Runs the check; the screenshots are written to `docs/src/view/`.
///
/// # Errors
/// A build, the simulation or a check fails.
pub fn run() -> Result {
    let out = target_dir().join("view");
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    // The debug build the test stage made (dependencies at opt-level 2): no second build
    // of the HTTP stack in release.
    Cmd::new("cargo")
        .args(["build", "--quiet", "-p", "cw-can", "--bin", "cw-can"])
        .run()?;
    let (log, trace) = (out.join("figure7.log"), out.join("figure7.csv"));
    ecu_run()
        .args(["--scenario", "scenarios/figure7.txt", "--trace"])
        .arg(&trace)
        .arg("--can-log")
        .arg(&log)
        .run()?;
    // The paper ran its ECU for 30 minutes.
    let long = out.join("approach-30min.log");
    ecu_run()
        .args([
            "--scenario",
            "scenarios/approach.txt",
            "--duration",
            "1800",
            "--can-log",
        ])
        .arg(&long)
        .run()?;
    let cw_can = target_dir().join("debug").join("cw-can");
    let dbc = root().join("firmware").join("ecu.dbc");
    let shots = root().join("docs").join("src").join("view");
    crate::setup::run_python_tool(
        "view_check.py",
        &[&cw_can, &dbc, &log, &trace, &long, &shots],
    )
}
