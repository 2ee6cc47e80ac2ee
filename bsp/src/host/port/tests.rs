//! The host port's lock outside the kernel, with the real kernel: a store, handed to the
//! kernel at the next kernel call, and any sequence of locks, releases, ISRs and kernel
//! calls leaving the kernel as kernel calls would.

use cw_core::os::{
    CounterConfig, IsrConfig, IsrId, Os, OsConfig, OsDescription, OsError, ResourceId, TaskConfig,
    TaskId, OSDEFAULTAPPMODE,
};

use super::HostPort;
use crate::host::clock::VirtualClock;
use crate::port::lazy::{check_any_steps, word};
use crate::port::{Held, Port};

const LOW: TaskId = TaskId(0);
const HIGH: TaskId = TaskId(1);

// Low uses both resources: 0 with the ISR, 1 with High.
static OS: OsConfig<2, 2, 1, 0, 1> = match OsConfig::new(OsDescription::new(
    [
        TaskConfig::basic("Low", 1).autostart().uses(0b11),
        TaskConfig::basic("High", 2).uses(0b10),
    ],
    [CounterConfig {
        max_allowed_value: 0xFFFF,
        ticks_per_base: 1,
        min_cycle: 1,
    }],
    [],
    [IsrConfig::cat2("Isr", 1).uses(0b01)],
)) {
    Ok(cfg) => cfg,
    Err(_) => panic!("the test configuration is inconsistent"),
};

type Kernel = Os<2, 2, 1, 0, 1, 2>;

/// The port after `StartOS`: Low (autostart) runs.
fn started() -> HostPort<Kernel> {
    HELD.with_borrow_mut(|all| *all = [const { None }; 3]);
    let Ok(kernel) = Kernel::new(&OS) else {
        panic!("the test kernel");
    };
    let port = HostPort::new(kernel, &VirtualClock::new());
    assert_eq!(port.kernel(|os| os.start_os(OSDEFAULTAPPMODE)), Ok(()));
    assert_eq!(port.kernel(|os| os.running()), Some(LOW));
    port
}

/// The kernel itself, without a hand-over.
fn kernel_now(port: &HostPort<Kernel>) -> Kernel {
    *port.kernel.borrow()
}

/// The kernel a kernel call would see: a lock kept outside it handed over.
fn kernel_view(port: &HostPort<Kernel>) -> Kernel {
    let mut view = kernel_now(port);
    let lazy = port.lazy.word();
    if word::is_locked(lazy) {
        assert!(
            view.try_get_resource(word::resource(lazy)).is_some(),
            "the hand-over"
        );
    }
    view
}

#[test]
fn a_tasks_lock_is_a_store_and_the_next_kernel_call_hands_it_over() {
    let port = started();
    let before = kernel_now(&port);
    for res in [ResourceId(0), ResourceId(1)] {
        assert_eq!(port.get_resource(res), Ok(()));
        assert!(word::is_locked(port.lazy.word()));
        assert!(kernel_now(&port) == before, "the kernel was not called");
        assert_eq!(kernel_view(&port).resource_owner(res), Some(LOW));
        assert_eq!(port.release_resource(res), Ok(()));
        assert_eq!(port.lazy.word(), LOW_ANSWER, "the answer again");
        assert!(kernel_now(&port) == before, "the pair left no trace");
    }
    // A kernel call inside the lock: the kernel holds it for Low first, so High, which
    // shares resource 1, waits for the release, which goes through the kernel.
    assert_eq!(port.get_resource(ResourceId(1)), Ok(()));
    assert_eq!(port.kernel(|os| os.activate_task(HIGH)), Ok(()));
    assert_eq!(kernel_now(&port).resource_owner(ResourceId(1)), Some(LOW));
    assert_eq!(kernel_now(&port).running(), Some(LOW));
    assert_eq!(port.release_resource(ResourceId(1)), Ok(()));
    assert!(!word::is_locked(port.lazy.word()));
    assert_eq!(kernel_now(&port).resource_owner(ResourceId(1)), None);
    assert_eq!(kernel_now(&port).running(), Some(HIGH));
}

/// A lock taken by [`Port::get_resource_of_kind`] is the general lock and its release the
/// general release (the host's default): outside the kernel, the answer back in the word;
/// where a kernel call inside the lock handed it over, through the kernel.
#[test]
fn a_lock_of_a_kind_is_the_general_lock_on_the_host() {
    let port = started();
    let before = kernel_now(&port);
    let held = port.get_resource_of_kind::<true>(ResourceId(0));
    assert_eq!(
        held,
        Ok(Held::other()),
        "the general release finds the lock"
    );
    assert!(word::is_locked(port.lazy.word()), "outside the kernel");
    assert_eq!(port.release_held(ResourceId(0), Held::other()), Ok(()));
    assert_eq!(port.lazy.word(), LOW_ANSWER);
    assert!(kernel_now(&port) == before, "the pair left no trace");
    // A kernel call inside it hands it over, so the release goes to the kernel, which
    // lets High in.
    assert_eq!(
        port.get_resource_of_kind::<false>(ResourceId(1)),
        Ok(Held::other())
    );
    assert_eq!(port.kernel(|os| os.activate_task(HIGH)), Ok(()));
    assert_eq!(port.lazy.answer(), 0);
    assert_eq!(port.release_held(ResourceId(1), Held::other()), Ok(()));
    assert_eq!(kernel_now(&port).resource_owner(ResourceId(1)), None);
    assert_eq!(kernel_now(&port).running(), Some(HIGH));
}

#[test]
fn a_nested_lock_of_the_same_resource_is_refused_by_the_kernel_as_ever() {
    let port = started();
    assert_eq!(port.get_resource(ResourceId(1)), Ok(()));
    assert_eq!(port.get_resource(ResourceId(1)), Err(OsError::Access));
    assert_eq!(kernel_now(&port).resource_owner(ResourceId(1)), Some(LOW));
    assert_eq!(port.release_resource(ResourceId(1)), Ok(()));
    assert_eq!(port.lazy.word(), LOW_ANSWER);
    assert_eq!(kernel_now(&port).resource_owner(ResourceId(1)), None);
}

#[test]
fn what_is_read_of_the_kernel_includes_a_lock_kept_outside_it() {
    let port = started();
    assert_eq!(port.get_resource(ResourceId(0)), Ok(()));
    // The ISR that shares resource 0 is masked: the interrupt mask read for it is the
    // kernel's with the lock handed over.
    assert_eq!(
        port.inspect(|os| os.resource_owner(ResourceId(0))),
        Some(LOW)
    );
    assert!(!port.inspect(|os| os.interrupt_mask()).admits(1));
    assert_eq!(port.release_resource(ResourceId(0)), Ok(()));
    assert!(port.inspect(|os| os.interrupt_mask()).admits(1));
}

#[test]
fn isrs_lock_through_the_kernel() {
    let port = started();
    assert_eq!(port.kernel(|os| os.enter_isr(IsrId(0))), Ok(()));
    assert_eq!(port.lazy.word(), 0);
    assert_eq!(port.get_resource(ResourceId(0)), Ok(()));
    assert_eq!(port.lazy.word(), 0);
    assert_eq!(port.release_resource(ResourceId(0)), Ok(()));
    assert_eq!(port.kernel(|os| os.exit_isr()), Ok(()));
    // Resource 0, which the ISR shares, by the lock that masks it; 1 by the other.
    assert_eq!(port.lazy.word(), LOW_ANSWER);
}

/// Low's answer: resource 0, which the ISR shares, by the lock that masks it (bit 12);
/// resource 1 by the other (bit 1).
const LOW_ANSWER: u32 = 1 << 12 | 1 << 1;

std::thread_local! {
    /// How [`step_on_both`] took each resource by its kind, for the release.
    static HELD: core::cell::RefCell<[Option<Held>; 3]> =
        const { core::cell::RefCell::new([None, None, None]) };
}

/// One step on the port and on the reference kernel, called for every lock.
fn step_on_both(port: &HostPort<Kernel>, reference: &mut Kernel, op: u8) {
    let res = ResourceId(op / 7 % 3);
    let slot = usize::from(res.0);
    match op % 7 {
        0 => assert_eq!(port.get_resource(res), reference.get_resource(res)),
        1 => {
            HELD.with_borrow_mut(|all| all[slot] = None);
            assert_eq!(port.release_resource(res), reference.release_resource(res));
        }
        5 => {
            // As the firmware's `Resource` locks: the way kept for the release.
            let held = port.get_resource_of_kind::<false>(res);
            assert_eq!(
                held.as_ref().map(|_| ()).map_err(|e| *e),
                reference.get_resource(res)
            );
            if let Ok(held) = held {
                HELD.with_borrow_mut(|all| all[slot] = Some(held));
            }
        }
        6 => {
            let held = HELD.with_borrow_mut(|all| all[slot].take());
            assert_eq!(
                port.release_held(res, held.unwrap_or_else(Held::other)),
                reference.release_resource(res)
            );
        }
        2 => {
            // An ISR that enters (where the mask lets it) and returns.
            let entered = port.kernel(|os| os.enter_isr(IsrId(0)));
            assert_eq!(entered, reference.enter_isr(IsrId(0)), "ISR entry");
            if entered.is_ok() {
                assert_eq!(port.kernel(|os| os.exit_isr()), reference.exit_isr());
            }
        }
        3 => assert_eq!(
            port.kernel(|os| os.activate_task(HIGH)),
            reference.activate_task(HIGH)
        ),
        _ => {
            // High's job ends where it runs (the host runs it nested, then Low goes on).
            if reference.running() == Some(HIGH) {
                assert_eq!(
                    port.kernel(|os| os.terminate_task()),
                    reference.terminate_task()
                );
            }
        }
    }
}

/// Any sequence of locks, releases (of either resource, or an invalid one), ISRs,
/// activations and job ends: after each step the kernel a kernel call would see (the
/// lock kept outside it handed over) is the kernel that was called for every lock, and
/// every call returned the same. (A bolero test and fuzz target.)
#[test]
fn any_locks_and_calls_leave_the_kernel_as_kernel_calls_would() {
    check_any_steps(started, kernel_now, step_on_both, kernel_view);
}
