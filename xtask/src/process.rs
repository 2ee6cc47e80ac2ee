//! Starting programs: every command is printed before it runs, gets no stdin, and runs in
//! the workspace root; failures name the program and the exact command line.

use crate::Result;
use std::ffi::OsStr;
use std::io::{ErrorKind, Read, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{mpsc, Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// How long [`Cmd::within`] waits, once the program has exited, for the processes it left
/// behind to close its output before it kills them.
const LINGER: Duration = Duration::from_secs(10);

/// Root of the workspace (the parent of this crate's directory).
pub fn root() -> PathBuf {
    let manifest_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest_dir
        .parent()
        .map_or_else(|| manifest_dir.to_path_buf(), Path::to_path_buf)
}

/// The workspace's target directory (`CARGO_TARGET_DIR` when set, else `<root>/target`).
pub fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) if !dir.is_empty() => root().join(dir),
        _ => root().join("target"),
    }
}

/// A command as a shell would show it: the program and its arguments, space-separated
/// (for the `$ ...` line printed before it runs).
pub fn shown(command: &Command) -> String {
    std::iter::once(command.get_program())
        .chain(command.get_args())
        .map(|a| a.to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Output of a finished command whose output was captured.
pub struct Captured {
    /// Whether it exited with status 0.
    pub success: bool,
    /// Its standard output, lossily decoded.
    pub stdout: String,
    /// Its standard error, lossily decoded.
    pub stderr: String,
}

/// Output of a command run by [`Cmd::within`].
pub struct Timed {
    /// Its exit code; `None` when a signal ended it (also when it overran its time limit).
    pub code: Option<i32>,
    /// Its standard output, lossily decoded.
    pub stdout: String,
    /// Its standard error, lossily decoded.
    pub stderr: String,
    /// It overran its time limit, and its process group was killed.
    pub timed_out: bool,
    /// It exited, but processes it started kept its output open; they were killed.
    pub lingered: bool,
}

/// A command to run, with the shell-like line shown to the user.
pub struct Cmd {
    inner: Command,
    program: String,
    shown: String,
}

impl Cmd {
    /// A command running `program` in the workspace root with stdin closed.
    pub fn new(program: impl AsRef<OsStr>) -> Self {
        let program = program.as_ref();
        let mut inner = Command::new(program);
        inner.current_dir(root()).stdin(Stdio::null());
        let program = program.to_string_lossy().into_owned();
        Self {
            inner,
            shown: quote(&program),
            program,
        }
    }

    /// Appends one argument.
    pub fn arg(mut self, arg: impl AsRef<OsStr>) -> Self {
        let arg = arg.as_ref();
        self.shown.push(' ');
        self.shown.push_str(&quote(&arg.to_string_lossy()));
        self.inner.arg(arg);
        self
    }

    /// Appends arguments.
    pub fn args<I, S>(mut self, args: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: AsRef<OsStr>,
    {
        for arg in args {
            self = self.arg(arg);
        }
        self
    }

    /// Runs the command in `dir` instead of the workspace root (shown before the program).
    pub fn dir(mut self, dir: &Path) -> Self {
        self.shown = format!("(cd {} && {})", quote(&dir.to_string_lossy()), self.shown);
        self.inner.current_dir(dir);
        self
    }

    /// Sets an environment variable for the command (shown before the program).
    pub fn env(mut self, key: &str, value: impl AsRef<OsStr>) -> Self {
        let value = value.as_ref();
        self.shown = format!("{key}={} {}", quote(&value.to_string_lossy()), self.shown);
        self.inner.env(key, value);
        self
    }

    /// Shows the command as `shown` instead (when the caller has a clearer form of it, such
    /// as the line a shell script is run for).
    pub fn show_as(mut self, shown: impl Into<String>) -> Self {
        self.shown = shown.into();
        self
    }

    fn spawn_error(&self, e: &std::io::Error) -> String {
        if e.kind() == ErrorKind::NotFound {
            format!(
                "`{}` not found on PATH (tried to run `{}`)",
                self.program, self.shown
            )
        } else {
            format!("could not start `{}`: {e}", self.shown)
        }
    }

    /// Prints the command, runs it with inherited stdout/stderr, fails unless it exits 0.
    pub fn run(mut self) -> Result {
        println!("$ {}", self.shown);
        let status = self.inner.status().map_err(|e| self.spawn_error(&e))?;
        if status.success() {
            Ok(())
        } else {
            Err(format!("`{}` failed ({status})", self.shown))
        }
    }

    /// Prints the command, runs it with inherited stdout/stderr and returns its exit code
    /// (`None` when a signal ended it); only failing to start is an error.
    pub fn status(mut self) -> Result<Option<i32>> {
        println!("$ {}", self.shown);
        let status = self.inner.status().map_err(|e| self.spawn_error(&e))?;
        Ok(status.code())
    }

    /// Prints the command, runs it capturing its output; an exit status other than 0 is
    /// not an error here (the caller decides), failing to start is.
    pub fn capture(mut self) -> Result<Captured> {
        println!("$ {}", self.shown);
        let out = self.inner.output().map_err(|e| self.spawn_error(&e))?;
        Ok(Captured {
            success: out.status.success(),
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        })
    }

    /// Prints the command without ending the line (the caller adds the outcome), runs it in
    /// a process group of its own capturing its output, and kills the group when it runs
    /// longer than `limit`, or when the program has exited but processes it started keep its
    /// output open for [`LINGER`] more. An exit status other than 0 is not an error here,
    /// failing to start is. (Being in a group of its own, the command does not get the
    /// terminal's Ctrl-C: stopping the runner leaves it to finish on its own.)
    pub fn within(mut self, limit: Duration) -> Result<Timed> {
        print!("$ {}", self.shown);
        // The line is finished by the caller; show it while the command runs.
        let _ = std::io::stdout().flush();
        let start = Instant::now();
        let mut child = self
            .inner
            .process_group(0)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| self.spawn_error(&e))?;
        let (done_tx, done) = mpsc::channel();
        let mut pipes = Vec::new();
        if let Some(out) = child.stdout.take() {
            pipes.push(drain(out, done_tx.clone()));
        }
        if let Some(err) = child.stderr.take() {
            pipes.push(drain(err, done_tx));
        }
        let group = child.id();
        let kill_group = || {
            // The whole group: the shell and everything it started.
            let _ = Command::new("kill")
                .args(["-KILL", "--", &format!("-{group}")])
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status();
        };
        let mut timed_out = false;
        let status = loop {
            if let Some(status) = child
                .try_wait()
                .map_err(|e| format!("waiting for `{}`: {e}", self.shown))?
            {
                break status;
            }
            if start.elapsed() >= limit {
                timed_out = true;
                kill_group();
                break child
                    .wait()
                    .map_err(|e| format!("waiting for `{}`: {e}", self.shown))?;
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        // Both pipes at their end, unless something the program left running holds them.
        let mut lingered = false;
        let mut open = pipes.len();
        while open > 0 {
            if done.recv_timeout(LINGER).is_ok() {
                open -= 1;
            } else if lingered || timed_out {
                break;
            } else {
                lingered = true;
                kill_group();
            }
        }
        let text = |buffer: &Arc<Mutex<Vec<u8>>>| {
            let bytes = buffer.lock().unwrap_or_else(PoisonError::into_inner);
            String::from_utf8_lossy(&bytes).into_owned()
        };
        Ok(Timed {
            code: if timed_out { None } else { status.code() },
            stdout: pipes.first().map(text).unwrap_or_default(),
            stderr: pipes.get(1).map(text).unwrap_or_default(),
            timed_out,
            lingered,
        })
    }

    /// Like [`Cmd::capture`], but also fails unless the command exits 0, showing its stderr.
    pub fn read(self) -> Result<String> {
        let shown = self.shown.clone();
        let out = self.capture()?;
        if out.success {
            Ok(out.stdout)
        } else {
            Err(format!("`{shown}` failed:\n{}{}", out.stdout, out.stderr))
        }
    }
}

/// Reads `pipe` to its end on a thread of its own, into the returned buffer (what was read
/// so far stays there if the end never comes); says `()` on `done` at the end.
fn drain(mut pipe: impl Read + Send + 'static, done: mpsc::Sender<()>) -> Arc<Mutex<Vec<u8>>> {
    let buffer = Arc::new(Mutex::new(Vec::new()));
    let filled = Arc::clone(&buffer);
    std::thread::spawn(move || {
        let mut chunk = [0u8; 8192];
        // A read error ends the output like its end does.
        while let Ok(n @ 1..) = pipe.read(&mut chunk) {
            filled
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .extend_from_slice(&chunk[..n]);
        }
        let _ = done.send(());
    });
    buffer
}

/// Quotes a word for display when a shell would need it.
fn quote(word: &str) -> String {
    let plain = !word.is_empty()
        && word.chars().all(|c| {
            c.is_ascii_alphanumeric()
                || matches!(c, '-' | '_' | '.' | '/' | ',' | '=' | ':' | '+' | '@' | '%')
        });
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}
