//! The memory functions of the Cortex-M images: `memcpy`, `memmove`, `memset` and the ARM
//! EABI's `__aeabi_memcpy*`, `__aeabi_memmove*`, `__aeabi_memset*` and `__aeabi_memclr*`,
//! as one small loop each (a word at a time, then the last bytes), in place of
//! the unrolled ones of the toolchain's `compiler_builtins`, whose definitions are weak
//! symbols made to be replaced so.
//!
//! Why: the production image must fit 24 KiB of flash, and `compiler_builtins`' versions
//! take about 1.5 KiB of it (`memcpy` alone 730 bytes: aligned, misaligned and tail
//! copies unrolled for speed), where these take 146 bytes. The ECU calls them while it
//! starts (its tables and state built and moved into place) and in its reports; the
//! production image (`opt-level = "z"`) also on its CAN path, three 16-byte frame copies
//! per send, where these loops execute 45 instructions a call and `compiler_builtins`'
//! 111 (QEMU's log of every executed instruction: the book,
//! [Performance](../../../book/performance.html#image-size)). The loops are written here
//! once, over plain pointers, and checked on the host against the standard library's
//! copies on any buffer, offset, length and overlap (bolero harnesses, which are also
//! fuzz targets and Kani proofs); the symbols themselves exist only in the Cortex-M
//! builds.
//!
//! The words are read and written unaligned where the addresses are not word-aligned:
//! the Cortex-M3, M4 and M7 (ARMv7-M) load and store a word at any address in normal
//! memory, the code's and the data's here (unless `CCR.UNALIGN_TRP` is set, which no image
//! does), and the production image's CAN path copies frames between addresses two bytes
//! apart. Each word's loop ends in `keep_loop`, so that the compiler keeps it a loop
//! instead of recognising a copy and compiling it to a call of `memcpy`, which would be
//! itself; the bytes at the end are volatile for the same reason.

/// An empty instruction with the effects the compiler must assume of any: the loop that
/// contains it stays a loop of loads and stores (a loop of nothing else it may turn into
/// a call of the very function being defined).
#[inline(always)]
fn keep_loop() {
    // SAFETY: no instruction: it reads, writes and changes nothing.
    unsafe { core::arch::asm!("", options(nostack, preserves_flags)) };
}

/// Copies `n` bytes from `src` to `dest`, lowest address first: a word at a time while
/// four bytes are left, then bytes.
///
/// # Safety
/// `src` must be valid for reading and `dest` for writing `n` bytes; where they overlap,
/// `dest` must not lie above `src` (a copy towards lower addresses, as `memmove` makes).
pub unsafe fn copy_forward(dest: *mut u8, src: *const u8, n: usize) {
    let mut i = 0;
    while n - i >= 4 {
        // SAFETY: `i + 4 <= n`: within the caller's ranges; unaligned accesses.
        unsafe {
            let word = src.add(i).cast::<u32>().read_unaligned();
            dest.add(i).cast::<u32>().write_unaligned(word);
        }
        keep_loop();
        i += 4;
    }
    while i < n {
        // SAFETY: `i < n`: within the caller's ranges.
        unsafe { dest.add(i).write_volatile(src.add(i).read_volatile()) };
        i += 1;
    }
}

/// Copies `n` bytes from `src` to `dest`, highest address first (for `memmove` where
/// `dest` lies above an overlapping `src`): a word at a time while four bytes are left
/// (each read whole before it is written, so an overlap of less than a word is kept),
/// then bytes.
///
/// # Safety
/// `src` must be valid for reading and `dest` for writing `n` bytes.
pub unsafe fn copy_backward(dest: *mut u8, src: *const u8, n: usize) {
    let mut i = n;
    while i >= 4 {
        i -= 4;
        // SAFETY: `i + 4 <= n`: within the caller's ranges; unaligned accesses.
        unsafe {
            let word = src.add(i).cast::<u32>().read_unaligned();
            dest.add(i).cast::<u32>().write_unaligned(word);
        }
        keep_loop();
    }
    while i > 0 {
        i -= 1;
        // SAFETY: `i < n`: within the caller's ranges.
        unsafe { dest.add(i).write_volatile(src.add(i).read_volatile()) };
    }
}

/// `memmove`: a copy of `n` bytes from `src` to `dest` that may overlap.
///
/// # Safety
/// `src` must be valid for reading and `dest` for writing `n` bytes.
pub unsafe fn copy(dest: *mut u8, src: *const u8, n: usize) {
    // `dest` lies above `src` within the copy's reach: backwards, so that no byte is
    // overwritten before it is read.
    if (dest as usize).wrapping_sub(src as usize) < n {
        // SAFETY: the caller's contract.
        unsafe { copy_backward(dest, src, n) };
    } else {
        // SAFETY: the caller's contract; `dest` is not above an overlapping `src`.
        unsafe { copy_forward(dest, src, n) };
    }
}

/// Writes `c` to the `n` bytes at `dest`: a word at a time while four bytes are left,
/// then bytes.
///
/// # Safety
/// `dest` must be valid for writing `n` bytes.
pub unsafe fn set(dest: *mut u8, c: u8, n: usize) {
    let word = u32::from_ne_bytes([c; 4]);
    let mut i = 0;
    while n - i >= 4 {
        // SAFETY: `i + 4 <= n`: within the caller's range; an unaligned access.
        unsafe { dest.add(i).cast::<u32>().write_unaligned(word) };
        keep_loop();
        i += 4;
    }
    while i < n {
        // SAFETY: `i < n`: within the caller's range.
        unsafe { dest.add(i).write_volatile(c) };
        i += 1;
    }
}

/// The symbols, in the Cortex-M builds only (a host build keeps its C library's). The
/// EABI's aligned variants may assume more alignment than the loops need, so they are the
/// same functions; `__aeabi_memset` takes its arguments in another order than `memset`.
#[cfg(all(target_arch = "arm", target_os = "none"))]
mod symbols {
    use super::{copy, copy_forward, set};

    /// # Safety
    /// C's `memcpy`.
    #[no_mangle]
    pub unsafe extern "C" fn memcpy(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
        // SAFETY: C's contract, which is this function's.
        unsafe { copy_forward(dest, src, n) };
        dest
    }

    /// # Safety
    /// C's `memmove`.
    #[no_mangle]
    pub unsafe extern "C" fn memmove(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
        // SAFETY: C's contract, which is this function's.
        unsafe { copy(dest, src, n) };
        dest
    }

    /// # Safety
    /// C's `memset`.
    #[no_mangle]
    pub unsafe extern "C" fn memset(dest: *mut u8, c: i32, n: usize) -> *mut u8 {
        // SAFETY: C's contract, which is this function's. (`c` is converted to a byte,
        // as C says.)
        unsafe { set(dest, c as u8, n) };
        dest
    }

    /// The EABI's functions of one kind, each `$body` over the arguments `$args`, with
    /// C's contract `$contract`, under each of the names.
    macro_rules! eabi {
        ($contract:literal, $args:tt => $body:expr; $($name:ident),*) => {$(
            /// # Safety
            #[doc = $contract]
            #[no_mangle]
            pub unsafe extern "aapcs" fn $name $args {
                // SAFETY: C's contract, which is this function's.
                unsafe { $body };
            }
        )*};
    }
    // The copies and moves: `memcpy` and `memmove` without the result.
    eabi!("C's `memcpy`.", (dest: *mut u8, src: *const u8, n: usize) => copy_forward(dest, src, n);
        __aeabi_memcpy, __aeabi_memcpy4, __aeabi_memcpy8);
    eabi!("C's `memmove`.", (dest: *mut u8, src: *const u8, n: usize) => copy(dest, src, n);
        __aeabi_memmove, __aeabi_memmove4, __aeabi_memmove8);
    // The fills, the length before the value, and the clears, fills with 0.
    eabi!("C's `memset`.", (dest: *mut u8, n: usize, c: i32) => set(dest, c as u8, n);
        __aeabi_memset, __aeabi_memset4, __aeabi_memset8);
    eabi!("C's `memset` with 0.", (dest: *mut u8, n: usize) => set(dest, 0, n);
        __aeabi_memclr, __aeabi_memclr4, __aeabi_memclr8);
}

pub mod spec;
#[cfg(test)]
mod tests;
