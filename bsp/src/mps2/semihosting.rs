//! Files and the command line of the host running QEMU, over semihosting (Arm's
//! semihosting specification: `SYS_GET_CMDLINE`, `SYS_OPEN`, `SYS_FLEN`, `SYS_READ`,
//! `SYS_WRITE`, `SYS_CLOSE`). QEMU answers them with `-semihosting-config enable=on,target=native`;
//! the command line is its `arg=` values joined by spaces.

use cortex_m_semihosting::nr;

/// Why a host file could not be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostFileError {
    /// The path is longer than the image passes (255 bytes).
    PathTooLong,
    /// The host refused to open it.
    Open,
    /// It is larger than the buffer (its length).
    TooLarge(usize),
    /// The host failed to read it.
    Read,
    /// The host failed to write it.
    Write,
}

impl core::fmt::Display for HostFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::PathTooLong => write!(f, "the path is longer than 255 bytes"),
            Self::Open => write!(f, "the host cannot open it"),
            Self::TooLarge(len) => write!(f, "{len} bytes is more than the image reads"),
            Self::Read => write!(f, "the host failed to read it"),
            Self::Write => write!(f, "the host failed to write it"),
        }
    }
}

/// The semihosting command line into `buf`: `None` if the host gave none or it does not
/// fit.
pub fn command_line(buf: &mut [u8]) -> Option<&str> {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE takes a two-word block (buffer address, its length), writes
    // at most that many bytes into the buffer and the written length into the block's
    // second word; both live through the call.
    let failed =
        unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if failed != 0 {
        return None;
    }
    let len = block[1].min(buf.len());
    core::str::from_utf8(buf.get(..len)?).ok()
}

/// Opens the host file `path` in semihosting's `mode`: its handle.
fn open(path: &str, mode: usize) -> Result<usize, HostFileError> {
    let mut name = [0u8; 256];
    let bytes = path.as_bytes();
    // The name is NUL-terminated for the host.
    if bytes.len() >= name.len() {
        return Err(HostFileError::PathTooLong);
    }
    name.get_mut(..bytes.len())
        .ok_or(HostFileError::PathTooLong)?
        .copy_from_slice(bytes);
    // SAFETY: SYS_OPEN reads the NUL-terminated name (its length excluding the NUL is
    // the third word) and the mode. The name outlives the call.
    let handle = unsafe {
        cortex_m_semihosting::syscall(nr::OPEN, &[name.as_ptr() as usize, mode, bytes.len()])
    };
    if handle == usize::MAX {
        return Err(HostFileError::Open);
    }
    Ok(handle)
}

/// Closes a handle [`open`] returned.
fn close(handle: usize) {
    // SAFETY: SYS_CLOSE reads one word, the handle.
    let _ = unsafe { cortex_m_semihosting::syscall(nr::CLOSE, &[handle]) };
}

/// Reads the host file `path` into `buf`; returns the text's length.
///
/// # Errors
/// [`HostFileError`]: the path is too long, the host cannot open or read it, or it does
/// not fit in `buf`.
pub fn read_file(path: &str, buf: &mut [u8]) -> Result<usize, HostFileError> {
    let handle = open(path, nr::open::R)?;
    // SAFETY: SYS_FLEN reads one word, the open handle.
    let len = unsafe { cortex_m_semihosting::syscall(nr::FLEN, &[handle]) };
    let result = if len == usize::MAX {
        Err(HostFileError::Read)
    } else if len > buf.len() {
        Err(HostFileError::TooLarge(len))
    } else {
        // SAFETY: SYS_READ writes at most `len` bytes (checked against the buffer above)
        // into `buf`, which lives through the call; it returns the bytes not read.
        let missing = unsafe {
            cortex_m_semihosting::syscall(nr::READ, &[handle, buf.as_mut_ptr() as usize, len])
        };
        if missing == 0 {
            Ok(len)
        } else {
            Err(HostFileError::Read)
        }
    };
    close(handle);
    result
}

/// A host file the image writes, created empty (or emptied) by [`HostFile::create`] and
/// closed when dropped.
pub struct HostFile(usize);

impl HostFile {
    /// Creates the host file `path`, or empties it, to be written in binary.
    ///
    /// # Errors
    /// [`HostFileError`]: the path is too long or the host cannot open it.
    pub fn create(path: &str) -> Result<Self, HostFileError> {
        open(path, nr::open::W_TRUNC_BINARY).map(Self)
    }

    /// Appends `bytes` to the file.
    ///
    /// # Errors
    /// [`HostFileError::Write`]: the host wrote less than all of them.
    pub fn write(&self, bytes: &[u8]) -> Result<(), HostFileError> {
        // SAFETY: SYS_WRITE reads `bytes.len()` bytes from the slice, which lives through
        // the call; it returns the bytes not written.
        let missing = unsafe {
            cortex_m_semihosting::syscall(
                nr::WRITE,
                &[self.0, bytes.as_ptr() as usize, bytes.len()],
            )
        };
        if missing == 0 {
            Ok(())
        } else {
            Err(HostFileError::Write)
        }
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        close(self.0);
    }
}
