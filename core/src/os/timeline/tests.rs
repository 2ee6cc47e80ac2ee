extern crate std;
use super::*;
use std::vec::Vec;

/// The jobs in the order they ended, the releases refused (time, item, cost, why), the
/// CPU's busy time.
type Schedule = (Vec<Job>, Vec<(u64, usize, u64, Refused)>, u64);

const TASK: Item = Item {
    priority: 1,
    limit: 1,
};

/// Replays `releases` (time, item, cost), in time order, to `horizon`: the jobs in the
/// order they ended, and the releases refused.
fn replay<const N: usize>(
    items: [Item; N],
    releases: &[(u64, usize, u64)],
    horizon: u64,
) -> Schedule {
    let mut timeline = Timeline::<N, 2>::new(items);
    let (mut jobs, mut refused) = (Vec::new(), Vec::new());
    for &(at, item, cost) in releases {
        while let Some(job) = timeline.advance(at) {
            jobs.push(job);
        }
        assert_eq!(timeline.now(), at.max(timeline.now()));
        if let Err(why) = timeline.release(item, cost) {
            refused.push((at, item, cost, why));
        }
    }
    while let Some(job) = timeline.advance(horizon) {
        jobs.push(job);
    }
    (jobs, refused, timeline.busy())
}

/// The same schedule, one unit of time at a time: at each time the jobs that ended go,
/// the releases of that time come, then jobs without cost end as they are chosen, and
/// the chosen job runs one unit (highest priority; earliest released among equals; lowest
/// index).
fn unit_steps<const N: usize>(
    items: [Item; N],
    releases: &[(u64, usize, u64)],
    horizon: u64,
) -> Schedule {
    // Per item: (released, started, left), in release order.
    let mut queues: Vec<Vec<(u64, Option<u64>, u64)>> = (0..N).map(|_| Vec::new()).collect();
    let (mut jobs, mut refused, mut busy) = (Vec::new(), Vec::new(), 0);
    let limit = |i: usize| usize::from(items[i].limit).min(2);
    let chosen = |queues: &Vec<Vec<(u64, Option<u64>, u64)>>| {
        (0..N)
            .filter(|&i| !queues[i].is_empty())
            .min_by_key(|&i| (u16::MAX - items[i].priority, queues[i][0].0, i))
    };
    for t in 0..horizon {
        for &(at, item, cost) in releases.iter().filter(|r| r.0 == t) {
            if item >= N {
                refused.push((at, item, cost, Refused::NoItem));
            } else if queues[item].len() >= limit(item) {
                refused.push((at, item, cost, Refused::Limit));
            } else {
                queues[item].push((t, None, cost));
            }
        }
        while let Some(i) = chosen(&queues) {
            let head = &mut queues[i][0];
            let started = *head.1.get_or_insert(t);
            if head.2 == 0 {
                jobs.push(Job {
                    item: i,
                    released: head.0,
                    started,
                    ended: t,
                });
                queues[i].remove(0);
                continue;
            }
            head.2 -= 1;
            busy += 1;
            if head.2 == 0 {
                jobs.push(Job {
                    item: i,
                    released: head.0,
                    started,
                    ended: t + 1,
                });
                queues[i].remove(0);
            }
            break;
        }
    }
    (jobs, refused, busy)
}

#[test]
fn a_higher_release_preempts_and_the_lower_job_resumes() {
    let items = [
        TASK,
        Item {
            priority: 2,
            limit: 1,
        },
    ];
    let (jobs, refused, busy) = replay(items, &[(0, 0, 10), (3, 1, 4)], 100);
    assert!(refused.is_empty());
    assert_eq!(busy, 14);
    assert_eq!(
        jobs,
        [
            Job {
                item: 1,
                released: 3,
                started: 3,
                ended: 7
            },
            Job {
                item: 0,
                released: 0,
                started: 0,
                ended: 14
            },
        ]
    );
}

#[test]
fn equal_priorities_run_in_release_order_without_preempting() {
    let (jobs, _, _) = replay([TASK, TASK], &[(0, 1, 5), (2, 0, 1)], 100);
    let order: Vec<(usize, u64, u64)> = jobs.iter().map(|j| (j.item, j.started, j.ended)).collect();
    assert_eq!(order, [(1, 0, 5), (0, 5, 6)]);
    // Released together: the lower index first.
    let (jobs, _, _) = replay([TASK, TASK], &[(0, 1, 5), (0, 0, 1)], 100);
    let order: Vec<(usize, u64, u64)> = jobs.iter().map(|j| (j.item, j.started, j.ended)).collect();
    assert_eq!(order, [(0, 0, 1), (1, 1, 6)]);
}

#[test]
fn a_release_past_the_limit_or_of_no_item_is_refused_and_lost() {
    let (jobs, refused, busy) = replay([TASK], &[(0, 0, 5), (1, 0, 5), (2, 3, 1)], 100);
    assert_eq!(
        refused,
        [(1, 0, 5, Refused::Limit), (2, 3, 1, Refused::NoItem)]
    );
    assert_eq!(jobs.len(), 1);
    assert_eq!(busy, 5);
    // An interrupt may have one job pending beside the one in service.
    let isr = Item {
        priority: 9,
        limit: 2,
    };
    let (jobs, refused, _) = replay([isr], &[(0, 0, 5), (1, 0, 5), (2, 0, 5)], 100);
    assert_eq!(refused, [(2, 0, 5, Refused::Limit)]);
    assert_eq!(jobs.last().map(|j| (j.started, j.ended)), Some((5, 10)));
    let mut timeline = Timeline::<1, 2>::new([isr]);
    assert_eq!(timeline.release(0, 1), Ok(()));
    assert_eq!(timeline.pending(0), 1);
    assert_eq!(timeline.pending(1), 0);
}

#[test]
fn a_job_without_cost_ends_after_the_releases_of_its_time() {
    let high = Item {
        priority: 2,
        limit: 1,
    };
    // The job without cost is released at 0 and ends at 0; released behind a running job,
    // it ends where that job does, after what is released there above it.
    let (jobs, _, _) = replay(
        [TASK, high],
        &[(0, 0, 0), (1, 1, 3), (2, 0, 0), (4, 1, 1)],
        100,
    );
    let order: Vec<(usize, u64, u64)> = jobs.iter().map(|j| (j.item, j.started, j.ended)).collect();
    assert_eq!(order, [(0, 0, 0), (1, 1, 4), (1, 4, 5), (0, 5, 5)]);
}

#[test]
fn the_running_item_is_the_highest_then_the_earliest_released() {
    let low = TASK;
    let high = Item {
        priority: 2,
        limit: 1,
    };
    let mut timeline = Timeline::<3, 2>::new([high, low, high]);
    assert_eq!(timeline.release(1, 4), Ok(()));
    assert_eq!(timeline.running(), Some(1));
    assert_eq!(timeline.advance(1), None);
    assert_eq!(timeline.release(2, 4), Ok(()));
    assert_eq!(timeline.advance(2), None);
    // Item 0 ties with item 2 on priority, released later: item 2 keeps the CPU.
    assert_eq!(timeline.release(0, 4), Ok(()));
    assert_eq!(timeline.running(), Some(2));
    assert_eq!(
        timeline.advance(100).map(|j| (j.item, j.ended)),
        Some((2, 5))
    );
    assert_eq!(timeline.running(), Some(0));
}

#[test]
fn time_passes_idle_and_never_goes_back() {
    let mut timeline = Timeline::<1, 2>::new([TASK]);
    assert_eq!(timeline.running(), None);
    assert_eq!(timeline.advance(50), None);
    assert_eq!(timeline.now(), 50);
    assert_eq!(timeline.advance(20), None);
    assert_eq!(timeline.now(), 50);
    assert_eq!(timeline.release(0, 7), Ok(()));
    assert_eq!(timeline.running(), Some(0));
    assert_eq!(timeline.advance(53), None);
    assert_eq!(timeline.busy(), 3);
    assert_eq!(
        timeline.advance(u64::MAX),
        Some(Job {
            item: 0,
            released: 50,
            started: 50,
            ended: 57
        })
    );
    assert_eq!(timeline.busy(), 7);
}

/// Any releases of three items with any priorities and limits, at times and costs below
/// 4: the model's schedule is the unit-step schedule, job for job, with the same releases
/// refused and the CPU busy exactly for the costs of the jobs that ran.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(17))]
fn any_releases_give_the_unit_step_schedule() {
    bolero::check!()
        .with_type::<([(u8, u8); 3], [(u8, u8, u8); 4])>()
        .cloned()
        .for_each(|(items, releases)| {
            let items = items.map(|(priority, limit)| Item {
                priority: u16::from(priority % 3),
                limit: limit % 3,
            });
            let mut releases: Vec<(u64, usize, u64)> = releases
                .iter()
                .map(|&(at, item, cost)| {
                    (
                        u64::from(at % 4),
                        usize::from(item % 4),
                        u64::from(cost % 4),
                    )
                })
                .collect();
            releases.sort_by_key(|r| r.0);
            let horizon = 4 + releases.iter().map(|r| r.2).sum::<u64>();
            let model = replay(items, &releases, horizon);
            assert_eq!(model, unit_steps(items, &releases, horizon));
            // Every job accepted ran to its end before the horizon: the CPU was busy for
            // exactly their costs.
            let accepted: u64 = releases.iter().map(|r| r.2).sum::<u64>()
                - model.1.iter().map(|r| r.2).sum::<u64>();
            assert_eq!(model.2, accepted);
            for job in &model.0 {
                assert!(job.released <= job.started && job.started <= job.ended);
            }
        });
}

/// Longer runs: times to 40, costs to 9, five items. Not under Miri, where a run takes
/// most of a second (the short runs above compare the same way there).
#[test]
#[cfg_attr(miri, ignore)]
fn generated_runs_give_the_unit_step_schedule() {
    bolero::check!()
        .with_type::<([(u8, u8); 5], Vec<(u8, u8, u8)>)>()
        .cloned()
        .for_each(|(items, releases)| {
            let items = items.map(|(priority, limit)| Item {
                priority: u16::from(priority % 4),
                limit: limit % 3,
            });
            let mut releases: Vec<(u64, usize, u64)> = releases
                .iter()
                .take(24)
                .map(|&(at, item, cost)| {
                    (
                        u64::from(at % 40),
                        usize::from(item % 6),
                        u64::from(cost % 10),
                    )
                })
                .collect();
            releases.sort_by_key(|r| r.0);
            let horizon = 40 + releases.iter().map(|r| r.2).sum::<u64>();
            assert_eq!(
                replay(items, &releases, horizon),
                unit_steps(items, &releases, horizon)
            );
        });
}

/// Any releases of four items, with any gaps and costs up to `u32::MAX`: the model keeps
/// its promises (`spec::replay_keeps_its_promises`).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(6))]
fn any_releases_keep_the_promises() {
    bolero::check!()
        .with_type::<([(u16, u8); 4], [(u32, u8, u32); 4])>()
        .cloned()
        .for_each(|(items, releases)| {
            let items = items.map(|(priority, limit)| Item { priority, limit });
            assert!(spec::replay_keeps_its_promises(&items, &releases));
        });
}

#[test]
fn refused_releases_are_no_jobs() {
    // A release refused for its limit is no job: the busy time is the accepted costs'.
    let items = [TASK; 4];
    assert!(spec::replay_keeps_its_promises(
        &items,
        &[(0, 0, 5), (1, 0, 5), (0, 7, 1)]
    ));
    // Four items of limit 0: every release is refused.
    let none = [Item {
        priority: 1,
        limit: 0,
    }; 4];
    assert!(spec::replay_keeps_its_promises(&none, &[(3, 1, 9)]));
}
