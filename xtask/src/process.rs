//! Starting programs: every command is printed before it runs, gets no stdin, and runs in
//! the workspace root; failures name the program and the exact command line.

use crate::Result;
use std::ffi::OsStr;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

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

/// Output of a finished command whose output was captured.
pub struct Captured {
    /// Whether it exited with status 0.
    pub success: bool,
    /// Its standard output, lossily decoded.
    pub stdout: String,
    /// Its standard error, lossily decoded.
    pub stderr: String,
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
