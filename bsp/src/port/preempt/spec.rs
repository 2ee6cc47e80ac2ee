//! The switch's bookkeeping ([`decide`]) against a model of the jobs: for the bsp's tests,
//! the `port_switch` fuzz target and a Kani proof.
//!
//! The model runs a legal schedule on a layout of four basic tasks on the shared stack and
//! two tasks with stacks of their own (which may wait): a step starts a job of a task
//! above the running one (by the switch, or by a call from a job on the shared stack:
//! [`start_by_call`]), lets the running job use stack, ends it (a job started by a call
//! gives the context back to its caller, [`back_to_caller`], whose call returns or, where
//! the kernel chose a new job, is saved below the ended job's frames), makes it wait (a
//! task with its own stack), or resumes a waiting one. After each switch the property
//! holds:
//!
//! - a new job on the shared stack starts at or below every context saved on it (no
//!   job's first frame lands on a preempted job's context, no called job's frames on its
//!   caller's), and above its guard;
//! - a new job of a task with its own stack starts at that stack's top;
//! - a resumed context gets back exactly the stack pointer it left with;
//! - when every job has ended, the shared stack is whole again (the next job starts at
//!   the idle loop's stack pointer).

use super::{back_to_caller, callable, decide, start_by_call, Sched, Switch, IDLE, MAX_TASKS};

/// The guard's bytes in the model.
pub const GUARD: u32 = 256;
/// The shared stack in the model.
pub const SHARED: (u32, u32) = (0x1000, 0x1800);
/// Bytes of each own stack in the model.
pub const OWN_BYTES: u32 = 0x400;
/// Tasks below this index run on the shared stack; the others on their own.
pub const OWN_FROM: u8 = 4;
/// Tasks in the model.
pub const TASKS: u8 = 6;
/// Bytes a first frame takes in the model.
const FRAME: u32 = 72;

/// A context the model keeps: its slot and saved stack pointer, whether its job was
/// started by a call, and the stack pointer it goes back to when the frames of a called
/// job that ended under it are left (0: none).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Saved {
    slot: u8,
    sp: u32,
    called: bool,
    unwind: u32,
}

impl Saved {
    const fn new(slot: u8, sp: u32) -> Self {
        Self {
            slot,
            sp,
            called: false,
            unwind: 0,
        }
    }

    /// The context resumes: the frames of a called job that ended under it are left.
    fn resumed(mut self) -> Self {
        if self.unwind != 0 {
            self.sp = self.unwind;
            self.unwind = 0;
        }
        self
    }
}

/// The running job ends and the context below it resumes: whether the switch gave that
/// context back exactly its saved stack pointer (a job started by a call: whether the
/// context is its caller's again, with no switch, and the call returns).
fn end_running(s: &mut Sched, running: &mut Saved, below: &[Saved], depth: &mut usize) -> bool {
    *depth -= 1;
    let Some(&back) = below.get(*depth) else {
        return false;
    };
    s.ended = true;
    s.next = back.slot;
    if running.called {
        if !back_to_caller(s) || s.current != back.slot || s.ended {
            return false;
        }
    } else if decide(s, running.sp, GUARD) != Switch::Resume(back.sp) {
        return false;
    }
    *running = back.resumed();
    true
}

/// Runs the schedule `steps` (each `(op, arg)`) and returns whether the switch kept every
/// property above at every step.
pub fn stacks_stay_apart(steps: &[(u8, u8)]) -> bool {
    let mut s = Sched::new();
    s.shared = SHARED;
    s.basic_top = SHARED.1;
    for t in OWN_FROM..TASKS {
        let bottom = 0x2000 + u32::from(t - OWN_FROM) * OWN_BYTES;
        s.set_own_stack(usize::from(t), bottom, bottom + OWN_BYTES);
    }
    // The running context: its slot and stack pointer.
    let idle_sp = SHARED.1 - 64;
    let mut running = Saved::new(IDLE, idle_sp);
    // Preempted contexts, innermost last (the LIFO of preemption).
    let mut below = [Saved::new(0, 0); MAX_TASKS + 1];
    let mut depth = 0usize;
    // Waiting contexts (tasks with their own stacks), by task.
    let mut waiting = [None::<u32>; MAX_TASKS];
    let started = |below: &[Saved], depth: usize, running: Saved, t: u8| {
        running.slot == t || below.iter().take(depth).any(|c| c.slot == t)
    };
    for &(op, arg) in steps {
        match op % 7 {
            // A job of a task above the running one starts (the running context is
            // preempted).
            0 => {
                let t = arg % TASKS;
                if started(&below, depth, running, t)
                    || waiting[usize::from(t)].is_some()
                    || (running.slot != IDLE && t <= running.slot)
                    || depth >= below.len()
                {
                    continue;
                }
                // The lowest stack pointer saved on the shared stack, the running one's
                // included once saved.
                let on_shared = |c: &Saved| c.slot == IDLE || c.slot < OWN_FROM;
                let lowest_shared = below
                    .iter()
                    .take(depth)
                    .chain(core::iter::once(&running))
                    .filter(|c| on_shared(c))
                    .map(|c| c.sp)
                    .min()
                    .unwrap_or(SHARED.1);
                if t < OWN_FROM && lowest_shared < SHARED.0 + GUARD + FRAME {
                    // No room for a first frame: on the CPU the guard faults (a stack
                    // fault); a schedule that fits its stacks does not do this.
                    continue;
                }
                s.next = t;
                let Switch::Start { task, top } = decide(&mut s, running.sp, GUARD) else {
                    return false;
                };
                if task != t {
                    return false;
                }
                let right_place = if t < OWN_FROM {
                    top <= lowest_shared && top >= SHARED.0 + GUARD + FRAME
                } else {
                    top == s.own_stack[usize::from(t)].1
                };
                if !right_place {
                    return false;
                }
                below[depth] = running;
                depth += 1;
                running = Saved::new(t, top - FRAME);
            }
            // The running job uses stack (within its stack, above the guard).
            1 => {
                let (bottom, _) = s.stack_of(usize::from(running.slot));
                let room = running.sp.saturating_sub(bottom + GUARD + FRAME);
                running.sp -= (u32::from(arg) * 4).min(room) & !7;
            }
            // The running job ends; the context below resumes.
            2 => {
                if running.slot == IDLE || depth == 0 {
                    continue;
                }
                if !end_running(&mut s, &mut running, &below, &mut depth) {
                    return false;
                }
            }
            // The running task, one with its own stack, waits; the context below resumes.
            3 => {
                if running.slot == IDLE || running.slot < OWN_FROM || depth == 0 {
                    continue;
                }
                depth -= 1;
                let back = below[depth];
                waiting[usize::from(running.slot)] = Some(running.sp);
                s.next = back.slot;
                if decide(&mut s, running.sp, GUARD) != Switch::Resume(back.sp) {
                    return false;
                }
                running = back.resumed();
            }
            // A job of a task on the shared stack above the running job, also on it, starts
            // by a call: its frames go right below the caller's.
            5 => {
                let t = arg % OWN_FROM;
                if started(&below, depth, running, t)
                    || running.slot == IDLE
                    || running.slot >= OWN_FROM
                    || t <= running.slot
                    || depth >= below.len()
                {
                    continue;
                }
                s.next = t;
                if !callable(&s) {
                    return false;
                }
                start_by_call(&mut s);
                if s.current != t {
                    return false;
                }
                below[depth] = running;
                depth += 1;
                running = Saved {
                    called: true,
                    ..Saved::new(t, running.sp)
                };
            }
            // The running job, started by a call, ends, and the kernel chose a new job of
            // a task above its caller: the context is the caller's again, and the switch
            // saves it below the ended job's frames (a new job on the shared stack starts
            // below them). The caller leaves those frames when it resumes.
            6 => {
                let t = arg % TASKS;
                if !running.called
                    || depth == 0
                    || started(&below, depth, running, t)
                    || waiting[usize::from(t)].is_some()
                    || below[depth - 1].slot >= t
                    || (t < OWN_FROM && running.sp < SHARED.0 + GUARD + FRAME)
                {
                    continue;
                }
                depth -= 1;
                let caller = below[depth];
                s.ended = true;
                s.next = t;
                if !back_to_caller(&mut s) || s.current != caller.slot {
                    return false;
                }
                let dead_frames = Saved {
                    sp: running.sp,
                    unwind: caller.sp,
                    ..caller
                };
                let Switch::Start { task, top } = decide(&mut s, dead_frames.sp, GUARD) else {
                    return false;
                };
                let right_place = if t < OWN_FROM {
                    top <= dead_frames.sp && top >= SHARED.0 + GUARD + FRAME
                } else {
                    top == s.own_stack[usize::from(t)].1
                };
                if task != t || !right_place {
                    return false;
                }
                below[depth] = dead_frames;
                depth += 1;
                running = Saved::new(t, top - FRAME);
            }
            // A waiting task's event arrives: it resumes above the running context.
            _ => {
                let t = OWN_FROM + arg % (TASKS - OWN_FROM);
                let Some(sp) = waiting[usize::from(t)] else {
                    continue;
                };
                if depth >= below.len() {
                    continue;
                }
                s.next = t;
                if decide(&mut s, running.sp, GUARD) != Switch::Resume(sp) {
                    return false;
                }
                waiting[usize::from(t)] = None;
                below[depth] = running;
                depth += 1;
                running = Saved::new(t, sp);
            }
        }
    }
    // Every job still under way ends, innermost first; waiting tasks are resumed and
    // ended too. The shared stack must then be whole.
    loop {
        if running.slot != IDLE && depth > 0 {
            if !end_running(&mut s, &mut running, &below, &mut depth) {
                return false;
            }
        } else if let Some(t) = (OWN_FROM..TASKS).find(|&t| waiting[usize::from(t)].is_some()) {
            let Some(sp) = waiting[usize::from(t)].take() else {
                return false;
            };
            s.next = t;
            if decide(&mut s, running.sp, GUARD) != Switch::Resume(sp) {
                return false;
            }
            below[depth] = running;
            depth += 1;
            running = Saved::new(t, sp);
        } else {
            break;
        }
    }
    // The next job starts right at the idle loop's stack pointer.
    s.next = 0;
    running.slot == IDLE
        && decide(&mut s, running.sp, GUARD)
            == Switch::Start {
                task: 0,
                top: running.sp,
            }
}
