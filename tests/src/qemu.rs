//! The image on QEMU's mps2-an386: the machine's options, the image's command line (over
//! semihosting), and its log, decoded.
//!
//! The image logs with `defmt`: binary frames written to QEMU's standard output over
//! semihosting, whose format strings stay in the ELF. [`Decoded`] pipes that output
//! through `defmt-print -e IMAGE` (installed by `cargo xtask setup`) as it comes, so a
//! run's log reads as text, one message per line. `cargo xtask qemu`, the emulator tests
//! and `cargo run` on the image (the runner, `cargo xtask qemu-runner`) all run it here.

use std::io::Read;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::thread::JoinHandle;

/// The decoder: `defmt-print`.
pub const DECODER: &str = "defmt-print";

/// QEMU's options for the image: the machine, no display or monitor, and semihosting
/// (the image's log, exit and host files) with the command line `program args...`.
pub fn machine(program: &str, args: &[&str]) -> Vec<String> {
    let mut semihosting = String::from("enable=on,target=native");
    for word in std::iter::once(program).chain(args.iter().copied()) {
        // QEMU's option syntax doubles a comma inside a value.
        semihosting.push_str(",arg=");
        semihosting.push_str(&word.replace(',', ",,"));
    }
    [
        "-machine",
        "mps2-an386",
        "-nographic",
        "-monitor",
        "none",
        // A reset (a production image's end after a fatal fault) ends QEMU instead of
        // starting the image again.
        "-no-reboot",
        "-semihosting-config",
        &semihosting,
    ]
    .map(str::to_string)
    .to_vec()
}

/// A run of the image on QEMU whose log is being decoded.
pub struct Decoded {
    qemu: Child,
    decoder: Child,
    text: Option<JoinHandle<std::io::Result<String>>>,
}

impl Decoded {
    /// Starts `qemu` (a `qemu-system-arm` command running `image`), its standard output
    /// piped into the decoder, whose text a thread collects (neither pipe can fill up).
    ///
    /// # Errors
    /// QEMU or the decoder cannot be started (the decoder's absence is named with how
    /// to install it).
    pub fn spawn(qemu: Command, image: &Path) -> Result<Self, String> {
        Self::start(qemu, image, true)
    }

    /// Starts the run with the decoded log on this process's standard output as it
    /// comes, instead of collected ([`Decoded::finish`] then returns no text).
    ///
    /// # Errors
    /// As [`Decoded::spawn`].
    pub fn shown(qemu: Command, image: &Path) -> Result<Self, String> {
        Self::start(qemu, image, false)
    }

    fn start(mut qemu: Command, image: &Path, collect: bool) -> Result<Self, String> {
        let mut qemu = qemu
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("qemu-system-arm: {e}"))?;
        let Some(log) = qemu.stdout.take() else {
            let _ = qemu.kill();
            return Err("qemu-system-arm: its output was not piped".into());
        };
        let decoder = Command::new(DECODER)
            .arg("-e")
            .arg(image)
            .args(["--log-format", "{s}"])
            .stdin(Stdio::from(log))
            .stdout(if collect {
                Stdio::piped()
            } else {
                Stdio::inherit()
            })
            .spawn();
        let mut decoder = match decoder {
            Ok(child) => child,
            Err(e) => {
                let _ = qemu.kill();
                let _ = qemu.wait();
                return Err(if e.kind() == std::io::ErrorKind::NotFound {
                    format!("`{DECODER}` not found on PATH: `cargo xtask setup` installs it")
                } else {
                    format!("{DECODER}: {e}")
                });
            }
        };
        let text = decoder.stdout.take().map(|mut out| {
            std::thread::spawn(move || {
                let mut text = String::new();
                out.read_to_string(&mut text).map(|_| text)
            })
        });
        Ok(Self {
            qemu,
            decoder,
            text,
        })
    }

    /// Ends the run at once (a test beside it failed).
    pub fn kill(&mut self) {
        let _ = self.qemu.kill();
    }

    /// Waits for QEMU and the decoder to end; returns whether the image exited with
    /// success (semihosting `SYS_EXIT`) and its decoded log.
    ///
    /// # Errors
    /// Waiting failed, the decoder failed, or its output was not text.
    pub fn finish(mut self) -> Result<(bool, String), String> {
        let status = self
            .qemu
            .wait()
            .map_err(|e| format!("qemu-system-arm: {e}"))?;
        let decoded = self.decoder.wait().map_err(|e| format!("{DECODER}: {e}"))?;
        let text = match self.text.take().map(JoinHandle::join) {
            Some(Ok(Ok(text))) => text,
            Some(Ok(Err(e))) => return Err(format!("reading {DECODER}'s output: {e}")),
            Some(Err(_)) => return Err(format!("{DECODER}'s output was lost")),
            // Shown as it came.
            None => String::new(),
        };
        if !decoded.success() {
            return Err(format!("{DECODER} failed ({decoded}) on:\n{text}"));
        }
        Ok((status.success(), text))
    }
}

/// Runs `qemu` (running `image`) to its end; returns whether the image exited with
/// success and its decoded log.
///
/// # Errors
/// As [`Decoded::spawn`] and [`Decoded::finish`].
pub fn run(qemu: Command, image: &Path) -> Result<(bool, String), String> {
    Decoded::spawn(qemu, image)?.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_goes_to_semihosting_with_commas_doubled() {
        let options = machine("cw-qemu", &["--scenario", "a,b.txt"]);
        assert_eq!(
            options.last().map(String::as_str),
            Some("enable=on,target=native,arg=cw-qemu,arg=--scenario,arg=a,,b.txt")
        );
        assert_eq!(options.get(1).map(String::as_str), Some("mps2-an386"));
        assert!(options.iter().any(|o| o == "-no-reboot"));
    }
}
