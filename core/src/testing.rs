//! Helpers for the crate's tests and Kani proofs.

use core::fmt;

/// Text written into a fixed buffer, without the heap (Kani proofs cannot use `String`).
pub struct FixedText<const N: usize> {
    buf: [u8; N],
    len: usize,
}

impl<const N: usize> FixedText<N> {
    /// An empty text.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
        }
    }

    /// What was written, if it is text (`None` only if a write split a character, which
    /// `write_str` never does).
    ///
    /// The text is the first chunk of valid UTF-8: `core::str::from_utf8`'s validation
    /// (word at a time, in nested loops) is beyond Kani on symbolic bytes, while
    /// `utf8_chunks` walks them once.
    pub fn as_str(&self) -> Option<&str> {
        let bytes = self.buf.get(..self.len).unwrap_or(&[]);
        match bytes.utf8_chunks().next() {
            None => Some(""),
            Some(chunk) if chunk.invalid().is_empty() => Some(chunk.valid()),
            Some(_) => None,
        }
    }
}

impl<const N: usize> fmt::Write for FixedText<N> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let bytes = s.as_bytes();
        if self.len + bytes.len() > N {
            return Err(fmt::Error);
        }
        // Byte by byte, by index: a piece's length is known to Kani where the text's is
        // not, and a copy into a range that starts at a symbolic length is beyond it.
        let mut k = 0;
        while k < bytes.len() {
            self.buf[self.len + k] = bytes[k];
            k += 1;
        }
        self.len += bytes.len();
        Ok(())
    }
}
