//! `cargo xtask qemu`: builds the ECU's Cortex-M4 image and runs it on QEMU's mps2-an386;
//! with `--compare`, checks that it is the same ECU as the host simulation.
//!
//! The image's CAN controller is UART0 speaking SLCAN; QEMU writes it to
//! `target/qemu/slcan.txt` (or serves it on a TCP port with `--serial tcp:PORT`). The LED
//! register's writes go to `target/qemu/fpgaio.log` (QEMU's `mps2_fpgaio_write` trace).
//! The run uses `-icount shift=5` (`cw_bsp::icount`): 32 ns of virtual time per
//! instruction, so SysTick's milliseconds are the image's own, independent of the host's
//! speed, and the trace's SysTick counts measure a path to about one instruction.
//!
//! `--live` runs the image in real time (`-icount shift=5,sleep=on`: counted instructions
//! while the core runs, the host's clock while it sleeps) with UART0 (CAN, SLCAN) and
//! UART1 (the distance sensor, `--sensor uart`) each on a TCP port and `tests/live.py`
//! against them: a simulated A02YYUW module sends distances with bad checksums, noise
//! and a silence; python-can's `slcan` interface receives the distance frames and sends
//! malformed lines and a `ThresholdConfig` frame that the ECU must apply. The image's
//! counts of malformed lines, received frames, sensor frames, bad checksums, blind-zone
//! readings and stray bytes must equal what was sent. Then `cw-can decode --slcan` reads
//! Figure 7 live from the scenario image's UART, and `cw-can view --slcan` serves the
//! view of a real-time run: its sender panel's `ThresholdConfig` must reach the image and
//! change the level the image sends.
//!
//! `--scenario FILE` (repeatable; default `scenarios/figure7.txt`) names the scenarios the
//! image plays: it reads each over semihosting (`-semihosting-config ...,arg=--scenario,
//! arg=FILE`). Each run's files go to `target/qemu/<scenario name>/`.
//!
//! `--profile` runs each scenario instruction by instruction and counts where the
//! instructions go, per function (`crate::profile`): `target/qemu/<name>/profile.txt`.
//!
//! `--compare` runs the emulator-in-the-loop tests in `tests/` (package `cw-tests`) on
//! the image it built: on `scenarios/figure7.txt`, `scenarios/faults.txt`,
//! `scenarios/no-communication.txt` and `scenarios/shutdown.txt` the image
//! and the host simulation must give the same CAN frames the ECU sent (id and payload, in
//! order) and the same levels of each LED, in order, with times within one OS tick.

use std::path::{Path, PathBuf};

use crate::image::{build_bin, footprint};
use crate::process::{root, target_dir, Cmd};
use crate::Result;

/// The paper's Figure 7, the image's default scenario.
pub const FIGURE7: &str = "scenarios/figure7.txt";

/// Options of `cargo xtask qemu`.
#[derive(Default, clap::Args)]
pub struct Options {
    /// Run the image on this scenario file (repeatable; default scenarios/figure7.txt,
    /// read by the image over semihosting)
    #[arg(long = "scenario", value_name = "FILE")]
    scenarios: Vec<PathBuf>,
    /// The emulator-in-the-loop tests (tests/, cw-tests): the scenarios give the host
    /// simulation's CAN frames and LED levels, bad scenario files are refused
    #[arg(long)]
    compare: bool,
    /// Run the image in real time on TCP ports and test it with python-can (slcan) and a
    /// simulated UART sensor, then decode it live with cw-can --slcan
    #[arg(long)]
    live: bool,
    /// Run the extended-task and stack-guard demo image (cw-qemu-events)
    #[arg(long)]
    events: bool,
    /// Count where the image's instructions go, per function
    #[arg(long)]
    profile: bool,
    /// The production image (cw-mps2): its flash and RAM, then live
    #[arg(long)]
    flash: bool,
    /// Serve the SLCAN UART on a TCP port (python-can: slcan, socket://; cw-can --slcan)
    #[arg(long, value_name = "tcp:PORT", value_parser = serial_port)]
    serial: Option<String>,
    /// Build the scenario image with the OS in OSEK's standard status (the images are in
    /// extended status otherwise, as the production image is): its figures and profile
    #[arg(long)]
    standard_status: bool,
}

/// `--serial tcp:PORT`: QEMU's server on that loopback port, waiting for the client.
fn serial_port(text: &str) -> Result<String> {
    let port = text
        .strip_prefix("tcp:")
        .ok_or_else(|| format!("`{text}` is not tcp:PORT"))?;
    let port: u16 = port
        .parse()
        .map_err(|_| format!("`{port}` is not a TCP port"))?;
    Ok(format!("tcp:127.0.0.1:{port},server=on,wait=on"))
}

impl Options {
    /// The options of the check command's `qemu` stage: the extended-task demo, the
    /// production image live, the per-function profile of Figure 7, the comparison, then
    /// the live test.
    pub fn ci() -> Self {
        Self {
            scenarios: Vec::new(),
            compare: true,
            live: true,
            events: true,
            profile: true,
            flash: true,
            serial: None,
            standard_status: false,
        }
    }
}

/// Builds the ECU's scenario image; returns its path.
pub fn build() -> Result<PathBuf> {
    build_bin("cw-qemu", "scenario", "release")
}

/// Builds the scenario image with the paper's task structure (feature `extended-tasks`:
/// the periodic tasks wait for their alarms' events); returns its path, the same as
/// [`build`]'s (the build replaces that image).
pub fn build_extended() -> Result<PathBuf> {
    build_bin("cw-qemu", "scenario,extended-tasks", "release")
}

/// The production image's flash and RAM goals, in bytes.
const FLASH_GOAL: u64 = 24 * 1024;
const RAM_GOAL: u64 = 8 * 1024;

/// Builds the production image (`cw-mps2`, profile `flash`) with `features` and checks
/// its flash and RAM against the goals; returns its path.
fn production_image(features: &str, status: &str) -> Result<PathBuf> {
    let image = build_bin("cw-mps2", features, "flash")?;
    let (flash, ram) = footprint(&image)?;
    println!(
        "qemu: cw-mps2 (production image, opt-level z, {status} status): flash {flash} B = {:.1} KiB (goal 24 KiB), RAM {ram} B = {:.1} KiB (goal 8 KiB)",
        flash as f64 / 1024.0,
        ram as f64 / 1024.0
    );
    if flash > FLASH_GOAL || ram > RAM_GOAL {
        return Err(format!(
            "qemu: cw-mps2 in {status} status is over its goals: flash {flash} B (at most {FLASH_GOAL}), RAM {ram} B (at most {RAM_GOAL})"
        ));
    }
    Ok(image)
}

/// The production image (`cw-mps2`, profile `flash`): its flash and RAM against the goals
/// (24 KiB, 8 KiB) in OSEK's standard status and in extended status (the production
/// choice), then the latter live against python-can and the simulated UART sensor
/// (`tests/live.py`, which checks the frames itself); its log must hold its start line
/// and no fatal error.
fn flash(out: &Path) -> Result {
    production_image("mps2,standard-status", "standard")?;
    let image = production_image("mps2", "extended")?;
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let session = live_session(
        &image,
        cw_tests::qemu::machine("cw-mps2", &[]),
        &out.join("fpgaio-flash.log"),
        true,
    )?;
    std::fs::write(out.join("image-flash.txt"), &session.log)
        .map_err(|e| format!("writing {}: {e}", out.display()))?;
    print!("{}", session.log);
    let started = session
        .log
        .lines()
        .any(|l| l.starts_with("cw-mps2: collision-warning ECU"));
    if !started || session.log.contains("FATAL") {
        return Err(format!(
            "qemu: the production image's log is not a clean start:\n{}",
            session.log
        ));
    }
    println!("qemu: the production image passed the live test (python-can over SLCAN both ways, the UART sensor)");
    Ok(())
}

/// The machine and the image's log, exit and files (semihosting), for every run; the
/// image's command line names `scenario` if given, and the UART sensor if `uart_sensor`.
fn qemu_machine(scenario: Option<&Path>, uart_sensor: bool) -> Vec<String> {
    let scenario = scenario.map(|file| file.display().to_string());
    let mut args = Vec::new();
    if let Some(file) = scenario.as_deref() {
        args.extend(["--scenario", file]);
    }
    if uart_sensor {
        args.extend(["--sensor", "uart"]);
    }
    cw_tests::qemu::machine("cw-qemu", &args)
}

/// Prints the image's report without its event lines and keeps it whole in `path`.
fn keep_report(report: &str, path: &Path) -> Result {
    print!(
        "{}",
        report
            .lines()
            .filter(|l| !l.starts_with("cw-qemu: event "))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
    );
    std::fs::write(path, report).map_err(|e| format!("writing {}: {e}", path.display()))
}

/// Runs the image on QEMU; the SLCAN output and the LED trace go to `out`, the image's
/// semihosting report to `out/image.txt` (and the terminal).
fn run_image(image: &Path, out: &Path, serial: Option<&str>, scenario: Option<&Path>) -> Result {
    run_image_at(image, out, serial, scenario, false)
}

/// [`run_image`], in real time when `realtime` (`sleep=on`: the host's clock while the core
/// sleeps).
fn run_image_at(
    image: &Path,
    out: &Path,
    serial: Option<&str>,
    scenario: Option<&Path>,
    realtime: bool,
) -> Result {
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let slcan = out.join("slcan.txt");
    let leds = out.join("fpgaio.log");
    for f in [&slcan, &leds] {
        let _ = std::fs::remove_file(f);
    }
    let serial = serial.map_or_else(|| format!("file:{}", slcan.display()), str::to_string);
    let mut qemu = std::process::Command::new("qemu-system-arm");
    let icount = if realtime {
        cw_bsp::icount::REAL_TIME
    } else {
        cw_bsp::icount::VIRTUAL
    };
    qemu.args(qemu_machine(scenario, false))
        .args(["-icount", icount])
        .args(["-serial", &serial])
        .args(["-d", "trace:mps2_fpgaio_write", "-D"])
        .arg(&leds)
        .arg("-kernel")
        .arg(image);
    let report = decoded_run(qemu, image)?;
    keep_report(&report, &out.join("image.txt"))
}

/// Runs `qemu` (a QEMU command running `image`) to its end, showing the command; returns
/// the image's decoded log, or an error with it if the image did not exit with success.
fn decoded_run(qemu: std::process::Command, image: &Path) -> Result<String> {
    let shown = crate::process::shown(&qemu);
    println!(
        "$ {} | {} -e {} --log-format '{{s}}'",
        shown,
        cw_tests::qemu::DECODER,
        image.display()
    );
    let (success, log) = cw_tests::qemu::run(qemu, image)?;
    if success {
        Ok(log)
    } else {
        Err(format!("the image on QEMU failed:\n{log}"))
    }
}

/// `cargo xtask qemu-runner IMAGE [ARGS]..`, cargo's runner for the board's target: the
/// image on QEMU (`-icount shift=5`, UART0's SLCAN output to `target/qemu/runner-slcan.txt`)
/// with `ARGS` on its command line, its log decoded on the terminal as it comes; fails if
/// the image exits with failure.
pub fn runner(args: &[String]) -> Result {
    let Some((image, args)) = args.split_first() else {
        return Err("qemu-runner: no image given (cargo passes it: `cargo run --target thumbv7em-none-eabihf ...`)".into());
    };
    let image = Path::new(image);
    let program = image
        .file_name()
        .map_or_else(|| "image".into(), |n| n.to_string_lossy().into_owned());
    if program == "cw-s32k144" {
        // Not an image for QEMU: the board's, through its debug probe.
        crate::s32k144::check(image)?;
        return crate::s32k144::flash(image, None);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = target_dir().join("qemu");
    std::fs::create_dir_all(&out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let slcan = out.join("runner-slcan.txt");
    let mut qemu = std::process::Command::new("qemu-system-arm");
    qemu.args(cw_tests::qemu::machine(&program, &args))
        .args(["-icount", cw_bsp::icount::VIRTUAL])
        .arg("-serial")
        .arg(format!("file:{}", slcan.display()))
        .arg("-kernel")
        .arg(image);
    let (success, _) = cw_tests::qemu::Decoded::shown(qemu, image)?.finish()?;
    println!(
        "qemu-runner: the ECU's CAN frames (SLCAN) are in {}",
        slcan.display()
    );
    if success {
        Ok(())
    } else {
        Err(format!("{} exited with failure", image.display()))
    }
}

/// Runs `cargo xtask qemu`.
pub fn run(options: &Options) -> Result {
    let out = target_dir().join("qemu");
    if options.events {
        events(&out)?;
    }
    if options.flash {
        flash(&out)?;
    }
    let only_others =
        (options.events || options.flash) && options.scenarios.is_empty() && !options.profile;
    if only_others && !options.compare && !options.live && options.serial.is_none() {
        return Ok(());
    }
    let image = if options.standard_status {
        build_bin("cw-qemu", "scenario,standard-status", "release")?
    } else {
        build()?
    };
    if !options.scenarios.is_empty() || options.profile || !(options.compare || options.live) {
        let default = [root().join(FIGURE7)];
        let scenarios = if options.scenarios.is_empty() {
            &default[..]
        } else {
            &options.scenarios[..]
        };
        for scenario in scenarios {
            let name = scenario
                .file_stem()
                .map_or_else(|| "scenario".into(), |s| s.to_string_lossy().to_string());
            println!("qemu: scenario {}", scenario.display());
            if options.profile {
                let dir = out.join(&name);
                std::fs::create_dir_all(&dir)
                    .map_err(|e| format!("creating {}: {e}", dir.display()))?;
                crate::profile::run(
                    &image,
                    &qemu_machine(Some(scenario), false),
                    &dir.join("profile.txt"),
                )?;
                continue;
            }
            run_image(
                &image,
                &out.join(&name),
                options.serial.as_deref(),
                Some(scenario),
            )?;
        }
    }
    if options.compare {
        compare(&image)?;
    }
    if options.live {
        live(&image, &out)?;
        cw_can_live(&image, &out)?;
        cw_can_view_live(&image, &out)?;
    }
    Ok(())
}

/// `cw-can` on the running image's bus: the scenario image plays Figure 7 with its SLCAN
/// UART on a TCP port, and `cw-can decode --slcan socket://...` decodes the frames as they
/// come, until the image ends. Every line must decode (exit status 0), and every frame
/// must be one of the ECU's DistanceFrames.
fn cw_can_live(image: &Path, out: &Path) -> Result {
    Cmd::new("cargo")
        .args(["build", "-q", "-p", "cw-can"])
        .run()?;
    let tool = target_dir().join("debug").join("cw-can");
    let port = free_port()?;
    let serial = format!("tcp:127.0.0.1:{port},server=on,wait=on");
    let image = image.to_path_buf();
    let dir = out.join("cw-can-live");
    let qemu = std::thread::spawn(move || {
        run_image(&image, &dir, Some(&serial), Some(&root().join(FIGURE7)))
    });
    let url = format!("socket://127.0.0.1:{port}");
    println!(
        "$ {} decode --dbc firmware/ecu.dbc --slcan {url}",
        tool.display()
    );
    // QEMU listens once it has started; try until it does.
    let mut attempt = 0;
    let output = loop {
        let output = std::process::Command::new(&tool)
            .args(["decode", "--dbc"])
            .arg(root().join("firmware").join("ecu.dbc"))
            .args(["--slcan", &url])
            .stdin(std::process::Stdio::null())
            .output()
            .map_err(|e| format!("running {}: {e}", tool.display()))?;
        let refused = String::from_utf8_lossy(&output.stderr).contains("cannot connect");
        attempt += 1;
        if !refused || attempt >= 100 {
            break output;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    qemu.join()
        .map_err(|_| "qemu: the image's thread panicked".to_string())??;
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let frames = stdout.lines().count();
    let distance = stdout
        .lines()
        .filter(|l| l.contains(" 100#") && l.contains(" DistanceFrame(Distance: "))
        .count();
    if !output.status.success() || frames == 0 || distance != frames {
        return Err(format!(
            "qemu: cw-can on the image's SLCAN port: exit {:?}, {frames} lines, {distance} DistanceFrames\n{stderr}{}",
            output.status.code(),
            stdout.lines().take(5).collect::<Vec<_>>().join("\n")
        ));
    }
    println!(
        "qemu: cw-can decoded {distance} DistanceFrames live from the image's SLCAN port (Figure 7), every line"
    );
    Ok(())
}

/// One HTTP/1.1 request to `addr` (the view's server): the status and the body.
fn http(addr: &str, method: &str, path: &str, json: &str) -> Result<(u16, String)> {
    use std::io::{Read, Write};
    let timeout = std::time::Duration::from_secs(5);
    let socket: std::net::SocketAddr = addr.parse().map_err(|e| format!("{addr}: {e}"))?;
    let mut s = std::net::TcpStream::connect_timeout(&socket, timeout)
        .and_then(|s| s.set_read_timeout(Some(timeout)).map(|()| s))
        .map_err(|e| format!("{addr}: {e}"))?;
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{json}",
        json.len()
    );
    let mut reply = String::new();
    s.write_all(request.as_bytes())
        .and_then(|()| s.read_to_string(&mut reply))
        .map_err(|e| format!("{addr}{path}: {e}"))?;
    let status = reply
        .get(9..12)
        .and_then(|c| c.parse().ok())
        .ok_or_else(|| format!("{addr}{path}: no HTTP status in {reply:?}"))?;
    let body = reply.split_once("\r\n\r\n").map_or("", |(_, b)| b);
    Ok((status, body.to_string()))
}

/// What the view shows, from its `/state`: (distance mm, level, red, yellow), when live.
fn shown(state: &serde_json::Value) -> Option<(u64, String, bool, bool)> {
    let shown = state.get("shown")?;
    if shown.get("status")?.as_str()? != "Live" {
        return None;
    }
    let sample = shown.get("sample")?;
    Some((
        sample.get("reading")?.get("mm")?.as_u64()?,
        sample.get("level")?.as_str()?.to_string(),
        shown.get("red")?.as_bool()?,
        shown.get("yellow")?.as_bool()?,
    ))
}

/// `cw-can view` on the running image's bus, in real time: the scenario image holds the
/// obstacle at 0.5 m, then 2.5 m, with its SLCAN UART on a TCP port, and `cw-can view
/// --slcan socket://...` serves the page. Its `/state` must show 0.5 m red, then 2.5 m with
/// both LEDs off; the sender panel's request (red below 2.0 m, yellow below 3.0 m) must
/// reach the image over SLCAN and turn 2.5 m yellow; when the image ends, the view names
/// the stream's end.
fn cw_can_view_live(image: &Path, out: &Path) -> Result {
    use std::io::BufRead;
    let tool = target_dir().join("debug").join("cw-can");
    let dir = out.join("cw-can-view");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let scenario = dir.join("hold.txt");
    std::fs::write(&scenario, "hold 500 1500\nhold 2500 4000\n")
        .map_err(|e| format!("writing {}: {e}", scenario.display()))?;
    let port = free_port()?;
    let serial = format!("tcp:127.0.0.1:{port},server=on,wait=on");
    let (image, image_dir) = (image.to_path_buf(), dir.clone());
    let qemu = std::thread::spawn(move || {
        run_image_at(&image, &image_dir, Some(&serial), Some(&scenario), true)
    });
    let url = format!("socket://127.0.0.1:{port}");
    let dbc = root().join("firmware").join("ecu.dbc");
    println!(
        "$ {} view --dbc {} --slcan {url} --listen 127.0.0.1:0",
        tool.display(),
        dbc.display()
    );
    // QEMU listens once it has started; try until it does.
    let mut attempt = 0;
    let (mut view, addr) = loop {
        let mut view = std::process::Command::new(&tool)
            .args(["view", "--dbc"])
            .arg(&dbc)
            .args(["--slcan", &url, "--listen", "127.0.0.1:0"])
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .map_err(|e| format!("running {}: {e}", tool.display()))?;
        let mut line = String::new();
        if let Some(stdout) = view.stdout.take() {
            let _ = std::io::BufReader::new(stdout).read_line(&mut line);
        }
        if let Some(addr) = line
            .split("http://")
            .nth(1)
            .and_then(|rest| rest.split('/').next())
        {
            break (view, addr.to_string());
        }
        let _ = view.wait();
        attempt += 1;
        if attempt >= 100 {
            return Err(format!("qemu: cw-can view could not reach {url}"));
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    let result = (|| -> Result {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
        let mut seen: Vec<(u64, String, bool, bool)> = Vec::new();
        let mut sent = false;
        let steps = [
            (500, "Red", true, false),
            (2500, "Off", false, false),
            (2500, "Yellow", false, true),
        ];
        while !steps
            .iter()
            .all(|step| seen.iter().any(|s| (s.0, s.1.as_str(), s.2, s.3) == *step))
        {
            if std::time::Instant::now() > deadline {
                return Err(format!(
                    "qemu: cw-can view over SLCAN did not show {steps:?} in 30 s; it showed {seen:?}"
                ));
            }
            let (status, body) = http(&addr, "GET", "/state", "")?;
            let state: serde_json::Value = serde_json::from_str(&body)
                .map_err(|e| format!("qemu: /state answered {status}: {e}: {body}"))?;
            if let Some(now) = shown(&state) {
                if !seen.contains(&now) {
                    seen.push(now.clone());
                }
                if !sent && (now.0, now.1.as_str()) == (2500, "Off") {
                    let (status, body) = http(
                        &addr,
                        "POST",
                        "/send",
                        r#"{"red_below_mm": 2000, "yellow_below_mm": 3000}"#,
                    )?;
                    if status != 200 {
                        return Err(format!("qemu: POST /send answered {status}: {body}"));
                    }
                    sent = true;
                }
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        Ok(())
    })();
    qemu.join()
        .map_err(|_| "qemu: the image's thread panicked".to_string())??;
    // The view's reader sees the end of the stream a moment after QEMU exits.
    let mut ended = Ok(false);
    for _ in 0..100 {
        ended = http(&addr, "GET", "/state", "")
            .map(|(_, body)| body.contains("the adapter's stream ended"));
        if ended != Ok(false) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // The chart draws what the view sent: an adapter does not hand its own frames back.
    let drawn = http(&addr, "GET", "/state", "").map(|(_, body)| {
        serde_json::from_str::<serde_json::Value>(&body)
            .ok()
            .and_then(|state| {
                let t = state.get("thresholds")?;
                Some((
                    t.get("red_below_mm")?.as_u64()?,
                    t.get("yellow_below_mm")?.as_u64()?,
                ))
            })
    });
    let _ = view.kill();
    let _ = view.wait();
    result?;
    if drawn != Ok(Some((2000, 3000))) {
        return Err(format!(
            "qemu: the view's chart draws the thresholds {drawn:?}, not the 2000/3000 mm it sent"
        ));
    }
    if ended != Ok(true) {
        return Err(format!(
            "qemu: the view did not name the end of the image's stream: {ended:?}"
        ));
    }
    println!(
        "qemu: cw-can view over the image's SLCAN port, in real time: 0.5 m red, 2.5 m off; thresholds 2000/3000 mm sent from the view reached the image: 2.5 m yellow, and the chart draws them; the stream's end named"
    );
    Ok(())
}

/// The faults the extended-task demo plays (`cw-qemu-events --fault NAME`), each with
/// whether the run must succeed and the lines its log must hold.
const EVENT_FAULTS: &[(&str, bool, &[&str])] = &[
    (
        "task-stack",
        true,
        &[
            "cw-qemu-events: the port reports: stack overflow on the stack of Waiter",
            "cw-qemu-events: ShutdownHook saw E_OS_STACKFAULT",
            "cw-qemu-events: ok",
        ],
    ),
    (
        "in-kernel",
        true,
        &[
            "cw-qemu-events: the port reports: stack overflow on the stack of Waiter",
            "cw-qemu-events: ShutdownHook saw E_OS_STACKFAULT",
            "cw-qemu-events: ok",
        ],
    ),
    (
        "main-stack",
        true,
        &[
            "cw-qemu-events: the port reports: stack overflow on the main stack (ISRs)",
            "cw-qemu-events: ShutdownHook saw E_OS_STACKFAULT",
            "cw-qemu-events: ok",
        ],
    ),
    (
        "missing-end",
        true,
        &[
            "cw-qemu-events: kernel calls that opened the caller's critical section: 0",
            "cw-qemu-events: ok",
        ],
    ),
    (
        "no-own-stack",
        false,
        &["cw-qemu-events: the port reports: an extended task needs a stack of its own: Waiter"],
    ),
    (
        "reset",
        true,
        &["cw-qemu-events: the port reports: fault panic", "RESET"],
    ),
];

/// The faults [`events`] plays again on a Cortex-M4 built without the MPU (QEMU's
/// `pmsav7-dregion=0`, as the S32K144's core is): the port checks the painted guards
/// instead, and the same overflows must end the same way. An overflow inside a kernel
/// call is not among them: the kernel lock masks the OS tick whose check would find it
/// (the book's limits of stack monitoring).
const NO_MPU_FAULTS: &[&str] = &["task-stack", "main-stack"];

/// The extended-task demo (`cw-qemu-events`), once per fault it plays: each run must end
/// as the port's guarantees say (`EVENT_FAULTS`): its waiter woke on every alarm to the
/// millisecond and on the ISR's events, then the fault was caught and ended the run the
/// way the port promises (`E_OS_STACKFAULT` through the ShutdownHook, `E_OS_MISSINGEND`
/// and the tasks going on, a refusal naming the task, or a reset); then the stack faults
/// of [`NO_MPU_FAULTS`] on a core without an MPU.
fn events(out: &Path) -> Result {
    let image = build_bin("cw-qemu-events", "trace", "release")?;
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    for &(fault, success, lines) in EVENT_FAULTS {
        event_run(&image, fault, success, lines, false)?;
    }
    for &(fault, success, lines) in EVENT_FAULTS {
        if NO_MPU_FAULTS.contains(&fault) {
            event_run(&image, fault, success, lines, true)?;
        }
    }
    println!("qemu: extended tasks woke on alarm and ISR events; stack overflows (a task's stack, inside a kernel call, the main stack) shut the OS down with E_OS_STACKFAULT, and on a core without an MPU (a task's stack, the main stack) too; a refused TerminateTask ended with E_OS_MISSINGEND; an extended task without its own stack was refused; a panic reset the board");
    Ok(())
}

/// One run of the demo with `--fault fault` (on a core without an MPU if `no_mpu`): it
/// must end successfully or not as `success` says, its log holding every line of `lines`.
fn event_run(image: &Path, fault: &str, success: bool, lines: &[&str], no_mpu: bool) -> Result {
    let mut qemu = std::process::Command::new("qemu-system-arm");
    qemu.args(cw_tests::qemu::machine(
        "cw-qemu-events",
        &["--fault", fault],
    ));
    if no_mpu {
        qemu.args(["-global", "cortex-m4-arm-cpu.pmsav7-dregion=0"]);
    }
    qemu.args(["-icount", cw_bsp::icount::VIRTUAL])
        .args(["-serial", "null"])
        .arg("-kernel")
        .arg(image);
    let shown = crate::process::shown(&qemu);
    println!("$ {}", shown);
    let (ended_ok, report) = cw_tests::qemu::run(qemu, image)?;
    print!("{report}");
    let missing: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| !report.lines().any(|r| r == *l))
        .collect();
    if ended_ok != success || !missing.is_empty() {
        return Err(format!(
            "qemu: the demo's fault `{fault}`{} ended {} (expected {}); lines missing: {missing:?}",
            if no_mpu { " without an MPU" } else { "" },
            if ended_ok { "successfully" } else { "failed" },
            if success { "success" } else { "a failure" },
        ));
    }
    Ok(())
}

/// A free TCP port on the loopback interface (the OS picks it; QEMU binds it next).
fn free_port() -> Result<u16> {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("qemu: no free TCP port: {e}"))
}

/// What a live session gave: the test's output and the image's decoded log.
struct LiveSession {
    test: String,
    log: String,
}

/// The image's verdicts on its own timing: WdgM's alive supervision failed, or the
/// watchdog expired. In real time (`cw_bsp::icount::REAL_TIME`) QEMU's virtual clock
/// follows the host's while the core sleeps; a host that stalls QEMU for tens of
/// milliseconds makes the clock jump, and the SysTick expiries the jump passes over reach
/// the core as one interrupt: the image's milliseconds fall behind the watchdog's clock,
/// which is the virtual clock itself (the book's `docs/src/limits.md`, "The live tests
/// run in the host's real time").
const TIMING_VERDICTS: [&str; 2] = [
    "WdgM: the alive supervision of",
    "watchdog: not triggered since",
];

/// A failed live run's error ended on one of the image's [`TIMING_VERDICTS`], in the
/// image's own log, with no kernel error the image counted (an `E_OS_LIMIT` there is a
/// fault of the image's: a task still running when its alarm came).
fn emulator_timing(error: &str) -> bool {
    let Some((_, log)) = error.split_once("the image's output:") else {
        return false;
    };
    let kernel_errors = log
        .lines()
        .filter_map(|l| l.split_once(": kernel errors "))
        .filter_map(|(_, rest)| rest.split(',').next()?.trim().parse::<u32>().ok())
        .any(|n| n > 0);
    TIMING_VERDICTS.iter().any(|v| log.contains(v)) && !kernel_errors
}

/// [`live_session_once`], run once more where the first run ended on one of the image's
/// [`TIMING_VERDICTS`] with no kernel error ([`emulator_timing`]; printed whole, with the
/// image's log): a host stall is not the image's fault, but the same verdict twice is.
/// Every other failure fails at once.
fn live_session(
    image: &Path,
    machine: Vec<String>,
    leds: &Path,
    runs_forever: bool,
) -> Result<LiveSession> {
    let first = live_session_once(image, machine.clone(), leds, runs_forever);
    match first {
        Err(e) if emulator_timing(&e) => {
            println!(
                "qemu: the live run ended on the image's timing verdict (a stalled host makes \
                 QEMU's real-time clock jump: docs/src/limits.md); its failure:\n{e}\n\
                 qemu: running the live test once more"
            );
            live_session_once(image, machine, leds, runs_forever)
                .map_err(|again| format!("the live test failed twice; the second time:\n{again}"))
        }
        other => other,
    }
}

/// Runs `image` in real time with UART0 (CAN) and UART1 (the sensor) on TCP ports and
/// `tests/live.py` against them, the LED register's writes going to `leds`. An image
/// that `runs_forever` is stopped when the test ends; one that ends by itself (its
/// scenario's length) must exit with success.
fn live_session_once(
    image: &Path,
    machine: Vec<String>,
    leds: &Path,
    runs_forever: bool,
) -> Result<LiveSession> {
    let (can_port, sensor_port) = (free_port()?, free_port()?);
    let can_serial = format!("tcp:127.0.0.1:{can_port},server=on,wait=on");
    let sensor_serial = format!("tcp:127.0.0.1:{sensor_port},server=on,wait=on");
    println!(
        "$ qemu-system-arm -machine mps2-an386 -icount {} -serial {can_serial} -serial {sensor_serial} -kernel {}",
        cw_bsp::icount::REAL_TIME,
        image.display()
    );
    let mut command = std::process::Command::new("qemu-system-arm");
    command
        .args(machine)
        // 32 ns per instruction while the core runs, real time while it sleeps (WFI): the
        // run keeps pace with the test, and the image's spans are instructions.
        .args(["-icount", cw_bsp::icount::REAL_TIME])
        .args(["-serial", &can_serial])
        .args(["-serial", &sensor_serial])
        .args(["-d", "trace:mps2_fpgaio_write", "-D"])
        .arg(leds)
        .arg("-kernel")
        .arg(image);
    let mut qemu = cw_tests::qemu::Decoded::spawn(command, image)?;
    let test = Cmd::new(crate::setup::venv_python())
        .arg(root().join("tests").join("live.py"))
        .arg(can_port.to_string())
        .arg(sensor_port.to_string())
        .arg(root().join("firmware").join("ecu.dbc"))
        .read();
    if test.is_err() || runs_forever {
        qemu.kill();
    }
    let finished = qemu.finish();
    let test = match test {
        Ok(test) => test,
        // The image's own report says why it ended, where it did: kept with the failure.
        Err(e) => {
            let log = finished.map_or_else(|e| e, |(_, log)| log);
            return Err(format!(
                "{e}
the image's output:
{log}"
            ));
        }
    };
    print!("{test}");
    let (success, log) = finished?;
    if !runs_forever && !success {
        return Err(format!("qemu: the live image ended with a failure:\n{log}"));
    }
    Ok(LiveSession { test, log })
}

/// The scenario image live (`--sensor uart`): its report (with the receive path's
/// instruction counts) goes to `out/image-live.txt`, and its counts of malformed lines,
/// received frames, sensor frames, bad checksums, blind-zone readings and stray bytes
/// must equal what the test sent.
fn live(image: &Path, out: &Path) -> Result {
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let session = live_session(
        image,
        qemu_machine(None, true),
        &out.join("fpgaio-live.log"),
        false,
    )?;
    let (test, image_out) = (session.test, session.log);
    keep_report(&image_out, &out.join("image-live.txt"))?;
    let sent = counts_after(&test, "live: sent ", &[" malformed lines and ", " frames"])?;
    let got = counts_after(
        &image_out,
        "cw-qemu: slcan received ",
        &[" frames, ", " commands, ", " malformed lines"],
    )?;
    let (sent_malformed, sent_frames) = (sent[0], sent[1]);
    let (got_frames, got_malformed) = (got[0], got[2]);
    if (got_malformed, got_frames) != (sent_malformed, sent_frames) {
        return Err(format!(
            "qemu: python-can sent {sent_malformed} malformed lines and {sent_frames} frames; \
             the image counted {got_malformed} malformed lines and received {got_frames} frames"
        ));
    }
    println!(
        "qemu: live SLCAN both ways: the image counted the {got_malformed} malformed lines python-can \
         sent and received its {got_frames} frames"
    );
    let sensor_sent = counts_after(
        &test,
        "live: sensor sent ",
        &[
            " frames, ",
            " bad checksums, ",
            " in the blind zone, ",
            " stray bytes",
        ],
    )?;
    let sensor_got = counts_after(
        &image_out,
        "cw-qemu: sensor received ",
        &[
            " bytes: ",
            " frames, ",
            " bad checksums, ",
            " in the blind zone, ",
            " stray bytes; ",
            " overruns",
        ],
    )?;
    if sensor_got[1..5] != sensor_sent[..] || sensor_got[5] != 0 {
        return Err(format!(
            "qemu: the sensor sent {sensor_sent:?} (frames, bad checksums, blind-zone readings, \
             stray bytes); the image counted {:?} and {} overruns",
            &sensor_got[1..5],
            sensor_got[5]
        ));
    }
    println!(
        "qemu: live sensor: the image decoded the {} frames the module sent ({} in the blind zone) \
         and counted its {} bad checksums and {} stray bytes, with no overrun",
        sensor_sent[0], sensor_sent[2], sensor_sent[1], sensor_sent[3]
    );
    Ok(())
}

/// The numbers in the line of `text` that starts with `prefix`, each followed by the
/// next separator (`12 malformed lines and 1 frames` with separators ` malformed lines
/// and `, ` frames`).
fn counts_after(text: &str, prefix: &str, separators: &[&str]) -> Result<Vec<u32>> {
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix(prefix))
        .ok_or_else(|| format!("qemu: no line starting `{prefix}` in:\n{text}"))?;
    let mut rest = line;
    let mut numbers = Vec::new();
    for sep in separators {
        let (number, tail) = rest
            .split_once(sep)
            .ok_or_else(|| format!("qemu: `{line}` lacks `{sep}`"))?;
        numbers.push(
            number
                .trim()
                .parse()
                .map_err(|_| format!("qemu: `{number}` in `{line}` is not a count"))?,
        );
        rest = tail;
    }
    Ok(numbers)
}

/// The emulator-in-the-loop tests (`tests/`, package `cw-tests`) on `image`: the image
/// on Figure 7 and on the faults scenario against the host simulation, and its refusals
/// of scenarios it cannot play.
fn compare(image: &Path) -> Result {
    Cmd::new("cargo")
        .args([
            "test",
            "-p",
            "cw-tests",
            "--",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("CW_QEMU_IMAGE", image)
        .run()
}

#[cfg(test)]
mod tests {
    use super::emulator_timing;

    #[test]
    fn only_the_images_timing_verdict_without_a_kernel_error_is_run_again() {
        let failure = |log: &str| format!("live.py failed\nthe image's output:\n{log}");
        let wdgm = "cw-mps2: WdgM: the alive supervision of OsSonarTask failed at 900 ms (0 of 1 alive indications): LEDs dark, the watchdog no longer triggered";
        assert!(emulator_timing(&failure(&format!(
            "{wdgm}\ncw-mps2: kernel errors 0, ISR entries refused 0; the last error: service 255, status 0"
        ))));
        assert!(emulator_timing(&failure(
            "watchdog: not triggered since 800 ms; expired at 807 ms (NMI), its reset follows"
        )));
        // The image's own fault: an activation refused.
        assert!(!emulator_timing(&failure(&format!(
            "{wdgm}\ncw-mps2: kernel errors 3, ISR entries refused 0; the last error: service 0, status 4"
        ))));
        // A verdict in the test's output, not in the image's log, or no verdict at all.
        assert!(!emulator_timing(&format!(
            "{wdgm}\nthe image's output:\ncw-mps2: started"
        )));
        assert!(!emulator_timing(&failure(
            "live: Distance 5 mm was never sent"
        )));
        assert!(!emulator_timing(wdgm));
    }
}
