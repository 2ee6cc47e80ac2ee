//! The host ECU in real time (Linux): the monotonic clock, sleeps to an absolute
//! deadline on it, and the real-time scheduling class where the system permits it. The
//! simulation itself runs in virtual time ([`crate::host`] reads no wall clock); this is
//! what paces it to the wall clock (`cw-ecu --realtime`) and what the evaluation's
//! real-time setting measures the jobs' starts with.
//!
//! A periodic real-time loop sleeps to absolute deadlines (`clock_nanosleep` with
//! `TIMER_ABSTIME` on `CLOCK_MONOTONIC`), so that the time spent between two wake-ups
//! does not add up: a relative sleep computed from the deadline wakes late by whatever
//! preempted the thread between the computation and the call.

use std::fmt;
use std::string::{String, ToString};

/// Nanoseconds on `CLOCK_MONOTONIC` (since an unspecified start, not set by anyone).
pub fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec through the pointer, which points to a
    // live local; CLOCK_MONOTONIC exists on every Linux.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    if rc != 0 {
        return 0;
    }
    u64::try_from(ts.tv_sec).unwrap_or(0) * 1_000_000_000 + u64::try_from(ts.tv_nsec).unwrap_or(0)
}

/// Sleeps until `deadline_ns` on [`now_ns`]'s clock (at once if it has passed), resuming
/// the sleep after a signal.
///
/// # Errors
/// The system refused the sleep (an invalid deadline): its error number.
pub fn sleep_until_ns(deadline_ns: u64) -> Result<(), i32> {
    let ts = libc::timespec {
        tv_sec: libc::time_t::try_from(deadline_ns / 1_000_000_000).map_err(|_| libc::EINVAL)?,
        tv_nsec: (deadline_ns % 1_000_000_000) as libc::c_long,
    };
    loop {
        // SAFETY: clock_nanosleep reads the deadline through the first pointer (a live
        // local) and, with TIMER_ABSTIME, never writes the remaining time (null).
        let rc = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                std::ptr::null_mut(),
            )
        };
        match rc {
            0 => return Ok(()),
            libc::EINTR => continue,
            other => return Err(other),
        }
    }
}

/// The scheduling the process runs under.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scheduling {
    /// `SCHED_FIFO` at this priority, or `None`: the default time-sharing class
    /// (`SCHED_OTHER`).
    pub fifo_priority: Option<i32>,
    /// Why `SCHED_FIFO` was not had (the system's words), where it was not.
    pub refused: Option<String>,
    /// Whether the process's memory is locked in RAM (`mlockall`: no page fault in the
    /// periodic loop).
    pub memory_locked: bool,
}

impl fmt::Display for Scheduling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.fifo_priority, &self.refused) {
            (Some(p), _) => write!(f, "SCHED_FIFO priority {p}")?,
            (None, Some(why)) => write!(f, "SCHED_OTHER (SCHED_FIFO refused: {why})")?,
            (None, None) => write!(f, "SCHED_OTHER")?,
        }
        if self.memory_locked {
            write!(f, ", memory locked")
        } else {
            write!(f, ", memory not locked")
        }
    }
}

/// The priority asked for: the middle of `SCHED_FIFO`'s 1 to 99, above the kernel's
/// threaded interrupts' default 50, below its own watchdogs at 99.
pub const FIFO_PRIORITY: i32 = 60;

/// Puts the calling process in `SCHED_FIFO` at [`FIFO_PRIORITY`] and locks its memory,
/// where the system permits each (root or `CAP_SYS_NICE` and `CAP_IPC_LOCK`, and a
/// real-time budget for the process's group); says what it got.
pub fn enter_realtime() -> Scheduling {
    let param = libc::sched_param {
        sched_priority: FIFO_PRIORITY,
    };
    // SAFETY: sched_setscheduler reads one sched_param through the pointer (a live
    // local); pid 0 is the calling process.
    let rc = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
    let (fifo_priority, refused) = if rc == 0 {
        (Some(FIFO_PRIORITY), None)
    } else {
        (None, Some(std::io::Error::last_os_error().to_string()))
    };
    // SAFETY: mlockall takes flags only.
    let memory_locked = unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0;
    Scheduling {
        fifo_priority,
        refused,
        memory_locked,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_goes_forward_and_a_sleep_ends_at_its_deadline_not_before() {
        let start = now_ns();
        assert!(start > 0);
        let deadline = start + 2_000_000;
        sleep_until_ns(deadline).unwrap();
        assert!(now_ns() >= deadline);
        // A deadline in the past returns at once.
        sleep_until_ns(start).unwrap();
    }

    #[test]
    fn the_scheduling_says_what_it_is() {
        let refused = Scheduling {
            fifo_priority: None,
            refused: Some("Operation not permitted (os error 1)".into()),
            memory_locked: false,
        };
        assert_eq!(
            refused.to_string(),
            "SCHED_OTHER (SCHED_FIFO refused: Operation not permitted (os error 1)), memory not locked"
        );
        let fifo = Scheduling {
            fifo_priority: Some(60),
            refused: None,
            memory_locked: true,
        };
        assert_eq!(fifo.to_string(), "SCHED_FIFO priority 60, memory locked");
    }
}
