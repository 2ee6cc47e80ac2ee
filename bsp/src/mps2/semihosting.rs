//! Files and the command line of the host running QEMU, over semihosting (Arm's
//! semihosting specification: `SYS_GET_CMDLINE`, `SYS_OPEN`, `SYS_FLEN`, `SYS_READ`,
//! `SYS_CLOSE`). QEMU answers them with `-semihosting-config enable=on,target=native`;
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
}

impl core::fmt::Display for HostFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::PathTooLong => write!(f, "the path is longer than 255 bytes"),
            Self::Open => write!(f, "the host cannot open it"),
            Self::TooLarge(len) => write!(f, "{len} bytes is more than the image reads"),
            Self::Read => write!(f, "the host failed to read it"),
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

/// Reads the host file `path` into `buf`; returns the text's length.
///
/// # Errors
/// [`HostFileError`]: the path is too long, the host cannot open or read it, or it does
/// not fit in `buf`.
pub fn read_file(path: &str, buf: &mut [u8]) -> Result<usize, HostFileError> {
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
    // the third word); mode 0 is "r". The name outlives the call.
    let handle = unsafe {
        cortex_m_semihosting::syscall(
            nr::OPEN,
            &[name.as_ptr() as usize, nr::open::R, bytes.len()],
        )
    };
    if handle == usize::MAX {
        return Err(HostFileError::Open);
    }
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
    // SAFETY: SYS_CLOSE reads one word, the handle opened above.
    let _ = unsafe { cortex_m_semihosting::syscall(nr::CLOSE, &[handle]) };
    result
}
