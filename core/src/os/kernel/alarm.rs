//! Counters and alarms (OSEK OS 2.2.3 §13.6; AUTOSAR `IncrementCounter`,
//! `GetCounterValue`, `GetElapsedValue`).

use super::{AlarmBase, Os, NONE};
use crate::os::call::ServiceCall;
use crate::os::callevel::Context;
use crate::os::config::{cycle_ok, AlarmAction, AlarmAutostart, Dialect};
use crate::os::error::ServiceId;
use crate::os::{AlarmId, CounterId, Hooks, OsConfig, OsError, TickType};
use crate::tables::Tables;

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
        K,
        H,
    > Os<T, R, C, A, I, Q, K, H>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Self>,
{
    /// A counter's current value (inspection).
    pub fn counter_value(&self, counter: CounterId) -> Option<TickType> {
        self.counter_value.get(counter.0 as usize).copied()
    }

    /// Whether an alarm is armed (inspection).
    pub fn alarm_armed(&self, alarm: AlarmId) -> bool {
        self.alarm_active
            .get(alarm.0 as usize)
            .copied()
            .unwrap_or(false)
    }

    fn alarm_index(id: AlarmId) -> Result<usize, OsError> {
        let a = id.0 as usize;
        if a < A {
            Ok(a)
        } else {
            Err(OsError::Id)
        }
    }

    fn counter_index(id: CounterId) -> Result<usize, OsError> {
        let c = id.0 as usize;
        if c < C {
            Ok(c)
        } else {
            Err(OsError::Id)
        }
    }

    fn alarm_counter(&self, a: usize) -> usize {
        self.cfg().alarms[a].counter.0 as usize
    }

    /// Ticks from now until the counter of `c` next shows `start` (a full revolution if it
    /// shows it now).
    fn abs_delay(&self, c: usize, start: TickType) -> TickType {
        // (`c` is a configured counter: the configuration's checks tie every alarm to one.)
        let modulus = self
            .cfg()
            .counters
            .get(c)
            .map_or(1, |k| u64::from(k.max_allowed_value) + 1);
        let now = self.counter_value.get(c).map_or(0, |&v| u64::from(v));
        let delay = (u64::from(start) + modulus - now % modulus) % modulus;
        // At most the modulus, `maxallowedvalue + 1`, which fits: the configuration refuses
        // a counter whose `maxallowedvalue` is `u32::MAX`.
        (if delay == 0 { modulus } else { delay }) as TickType
    }

    /// Arms the autostart alarms of application mode `mode` (bit) as `StartOS` does.
    pub(super) fn arm_autostart_alarms(&mut self, mode_bit: u32) {
        let cfg = self.cfg();
        for a in 0..A {
            let alarm = &cfg.alarms[a];
            if alarm.autostart_modes & mode_bit == 0 {
                continue;
            }
            let c = alarm.counter.0 as usize;
            match alarm.autostart {
                AlarmAutostart::Off => {}
                AlarmAutostart::Relative { increment, cycle } => {
                    self.arm(a, c, increment, cycle);
                }
                AlarmAutostart::Absolute { start, cycle } => {
                    let delay = self.abs_delay(c, start);
                    self.arm(a, c, delay, cycle);
                }
            }
        }
    }

    /// Inserts alarm `a` into counter `c`'s delta list, `delay >= 1` ticks from now, after
    /// any alarm due at the same tick.
    fn arm(&mut self, a: usize, c: usize, delay: TickType, cycle: TickType) {
        if a >= A {
            return;
        }
        let mut prev = NONE;
        let mut node = self.counter_head.get(c).copied().unwrap_or(NONE);
        let mut rest = delay;
        // A list holds at most the `A` alarms: the walk is bounded by the configuration.
        for _ in 0..A {
            if node as usize >= A || rest < self.alarm_delta[node as usize] {
                break;
            }
            rest -= self.alarm_delta[node as usize];
            prev = node;
            node = self.alarm_next[node as usize];
        }
        self.alarm_delta[a] = rest;
        self.alarm_next[a] = node;
        if (prev as usize) < A {
            self.alarm_next[prev as usize] = a as u8;
        } else if let Some(head) = self.counter_head.get_mut(c) {
            *head = a as u8;
        }
        if (node as usize) < A {
            self.alarm_delta[node as usize] -= rest;
        }
        self.alarm_active[a] = true;
        self.alarm_cycle[a] = cycle;
    }

    /// Removes armed alarm `a` from its counter's delta list.
    fn disarm(&mut self, a: usize) {
        let c = self.alarm_counter(a);
        let next = self.alarm_next[a];
        if (next as usize) < A {
            self.alarm_delta[next as usize] += self.alarm_delta[a];
        }
        if self.counter_head[c] as usize == a {
            self.counter_head[c] = next;
        } else {
            let mut node = self.counter_head[c];
            for _ in 0..A {
                if node as usize >= A {
                    break;
                }
                if self.alarm_next[node as usize] as usize == a {
                    self.alarm_next[node as usize] = next;
                    break;
                }
                node = self.alarm_next[node as usize];
            }
        }
        self.alarm_active[a] = false;
        self.alarm_delta[a] = 0;
        self.alarm_next[a] = NONE;
        self.alarm_cycle[a] = 0;
    }

    /// Disarms every alarm (the OS shuts down).
    pub(super) fn disarm_all(&mut self) {
        self.counter_head = [NONE; C];
        self.alarm_active = [false; A];
        self.alarm_delta = [0; A];
        self.alarm_next = [NONE; A];
        self.alarm_cycle = [0; A];
    }

    /// `GetAlarmBase`.
    ///
    /// # Errors
    /// `E_OS_ID` invalid alarm; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn get_alarm_base(&mut self, alarm: AlarmId) -> Result<AlarmBase, OsError> {
        self.service(
            ServiceId::GetAlarmBase,
            || ServiceCall::GetAlarmBase(alarm),
            |os| {
                let a = Self::alarm_index(alarm)?;
                let k = &os.cfg().counters[os.alarm_counter(a)];
                Ok(AlarmBase {
                    max_allowed_value: k.max_allowed_value,
                    ticks_per_base: k.ticks_per_base,
                    min_cycle: k.min_cycle,
                })
            },
        )
    }

    /// Ticks before alarm `alarm` expires (inspection behind `GetAlarm`; `None` when it is
    /// not armed or the id is invalid).
    pub fn alarm_remaining(&self, alarm: AlarmId) -> Option<u64> {
        let a = alarm.0 as usize;
        if a >= A || !self.alarm_active[a] {
            return None;
        }
        let mut node = self.counter_head[self.alarm_counter(a)];
        let mut ticks = 0u64;
        for _ in 0..A {
            if node as usize >= A {
                break;
            }
            ticks += u64::from(self.alarm_delta[node as usize]);
            if node as usize == a {
                break;
            }
            node = self.alarm_next[node as usize];
        }
        Some(ticks)
    }

    /// `GetAlarm`: ticks left before the alarm expires.
    ///
    /// # Errors
    /// `E_OS_NOFUNC` the alarm is not armed; `E_OS_ID` invalid alarm; `E_OS_CALLEVEL`,
    /// `E_OS_DISABLEDINT`.
    pub fn get_alarm(&mut self, alarm: AlarmId) -> Result<TickType, OsError> {
        self.service(
            ServiceId::GetAlarm,
            || ServiceCall::GetAlarm(alarm),
            |os| {
                Self::alarm_index(alarm)?;
                let ticks = os.alarm_remaining(alarm).ok_or(OsError::NoFunc)?;
                // At most `maxallowedvalue + 1`, which fits: the counter limits exclude
                // `u32::MAX`, and standard status never arms beyond `u32::MAX` ticks.
                Ok(TickType::try_from(ticks).unwrap_or(TickType::MAX))
            },
        )
    }

    /// The checks `SetRelAlarm` and `SetAbsAlarm` share: `E_OS_ID` for an unknown alarm,
    /// `E_OS_STATE` for an armed one. Returns the alarm and its counter.
    fn unarmed_alarm(&self, alarm: AlarmId) -> Result<(usize, usize), OsError> {
        let a = Self::alarm_index(alarm)?;
        if self.alarm_active[a] {
            return Err(OsError::State);
        }
        Ok((a, self.alarm_counter(a)))
    }

    /// `SetRelAlarm`: arms the alarm `increment` ticks from now, then every `cycle` ticks
    /// (0: once).
    ///
    /// # Errors
    /// `E_OS_STATE` already armed; `E_OS_ID` invalid alarm; `E_OS_VALUE` (extended status)
    /// increment above `maxallowedvalue`, or cycle neither 0 nor in `mincycle ..=
    /// maxallowedvalue`; with the AUTOSAR dialect, increment 0 in both statuses (with the
    /// OSEK dialect the alarm then waits a full revolution); `E_OS_CALLEVEL`,
    /// `E_OS_DISABLEDINT`.
    pub fn set_rel_alarm(
        &mut self,
        alarm: AlarmId,
        increment: TickType,
        cycle: TickType,
    ) -> Result<(), OsError> {
        let call = ServiceCall::SetRelAlarm {
            alarm,
            increment,
            cycle,
        };
        self.service(
            ServiceId::SetRelAlarm,
            || call,
            |os| {
                let (a, c) = os.unarmed_alarm(alarm)?;
                let cfg = os.cfg();
                let k = &cfg.counters[c];
                let autosar = matches!(cfg.dialect, Dialect::Autosar);
                if increment == 0 && autosar {
                    return Err(OsError::Value);
                }
                if os.extended() && (increment > k.max_allowed_value || !cycle_ok(k, cycle)) {
                    return Err(OsError::Value);
                }
                // (A full revolution fits: `maxallowedvalue` is below `u32::MAX`.)
                let delay = if increment == 0 {
                    k.max_allowed_value.saturating_add(1)
                } else {
                    increment
                };
                os.arm(a, c, delay, cycle);
                Ok(())
            },
        )
    }

    /// `SetAbsAlarm`: arms the alarm to expire when the counter next reaches `start`, then
    /// every `cycle` ticks (0: once).
    ///
    /// # Errors
    /// `E_OS_STATE` already armed; `E_OS_ID` invalid alarm; `E_OS_VALUE` (extended status)
    /// start above `maxallowedvalue`, or cycle neither 0 nor in `mincycle ..=
    /// maxallowedvalue`; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn set_abs_alarm(
        &mut self,
        alarm: AlarmId,
        start: TickType,
        cycle: TickType,
    ) -> Result<(), OsError> {
        let call = ServiceCall::SetAbsAlarm {
            alarm,
            start,
            cycle,
        };
        self.service(
            ServiceId::SetAbsAlarm,
            || call,
            |os| {
                let (a, c) = os.unarmed_alarm(alarm)?;
                let k = &os.cfg().counters[c];
                if os.extended() && (start > k.max_allowed_value || !cycle_ok(k, cycle)) {
                    return Err(OsError::Value);
                }
                let delay = os.abs_delay(c, start);
                os.arm(a, c, delay, cycle);
                Ok(())
            },
        )
    }

    /// `CancelAlarm`.
    ///
    /// # Errors
    /// `E_OS_NOFUNC` the alarm is not armed; `E_OS_ID` invalid alarm; `E_OS_CALLEVEL`,
    /// `E_OS_DISABLEDINT`.
    pub fn cancel_alarm(&mut self, alarm: AlarmId) -> Result<(), OsError> {
        self.service(
            ServiceId::CancelAlarm,
            || ServiceCall::CancelAlarm(alarm),
            |os| {
                let a = Self::alarm_index(alarm)?;
                if !os.alarm_active[a] {
                    return Err(OsError::NoFunc);
                }
                os.disarm(a);
                Ok(())
            },
        )
    }

    /// The ticks of `counter` until its next alarm is due (the tick that many ticks from
    /// now expires it), or `u64::MAX` when none is armed; `None` for an unknown counter.
    /// The ticks before that one have nothing to do but count.
    pub fn ticks_to_expiry(&self, counter: CounterId) -> Option<u64> {
        let head = usize::from(*self.counter_head.get(counter.0 as usize)?);
        Some(
            self.alarm_delta
                .get(head)
                .map_or(u64::MAX, |&d| u64::from(d)),
        )
    }

    /// `IncrementCounter`: advances a counter by one tick and runs the actions of the alarms
    /// that expire. At task level this is a rescheduling point. An action that fails is
    /// reported to `ErrorHook` with its own service and parameters; `IncrementCounter`
    /// still returns `E_OK` (AUTOSAR SWS_Os_00321).
    ///
    /// # Errors
    /// `E_OS_ID` invalid counter; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    #[inline]
    pub fn increment_counter(&mut self, counter: CounterId) -> Result<(), OsError> {
        self.service(
            ServiceId::IncrementCounter,
            || ServiceCall::IncrementCounter(counter),
            |os| {
                let c = Self::counter_index(counter)?;
                if os.advance(c) {
                    os.reschedule();
                }
                Ok(())
            },
        )
    }

    /// One tick of counter `c` (an index in range): the value advanced, and every alarm
    /// due at this tick run ([`Os::expire`]). Whether any was due.
    #[inline]
    pub(super) fn advance(&mut self, c: usize) -> bool {
        let max = self.cfg().counters[c].max_allowed_value;
        let value = self.counter_value[c];
        self.counter_value[c] = if value >= max { 0 } else { value + 1 };
        let head = self.counter_head[c] as usize;
        if head >= A {
            return false;
        }
        // The head's delta is at least 1 between ticks; were it 0, the alarm would be
        // due now, which is what happens.
        let delta = self.alarm_delta[head];
        if delta > 1 {
            self.alarm_delta[head] = delta - 1;
            return false;
        }
        self.alarm_delta[head] = 0;
        self.expire(c);
        true
    }

    /// Whether every alarm of counter `c` due at its next tick activates a task that may
    /// be activated once more, each a task of its own (so that none of the activations
    /// fails, nor depends on another): then the tick runs no `ErrorHook`, no callback and
    /// no `SetEvent`. `false` where none is due.
    #[inline(always)]
    pub(super) fn due_alarms_only_activate(&self, c: usize) -> bool {
        let mut a = usize::from(self.counter_head.get(c).copied().unwrap_or(NONE));
        // The head is due at the next tick with a delta of 1, the alarms behind it at the
        // same tick with deltas of 0.
        let mut due: TickType = 1;
        // (32 bits: a 64-bit shift by a task known at run time is a dozen instructions on
        // a 32-bit core; a due alarm of a task above 31 sends the tick to the whole ISR.)
        let mut tasks = 0u32;
        for _ in 0..A {
            if a >= A || self.alarm_delta[a] != due {
                break;
            }
            let AlarmAction::ActivateTask(task) = self.cfg().alarms[a].action else {
                return false;
            };
            let t = usize::from(task.0);
            if t >= T || t >= 32 || tasks & (1 << t) != 0 || self.activation_left(t).is_err() {
                return false;
            }
            tasks |= 1 << t;
            due = 0;
            a = usize::from(self.alarm_next[a]);
        }
        tasks != 0
    }

    /// Pops and runs every alarm of counter `c` that is due now.
    #[inline(never)]
    fn expire(&mut self, c: usize) {
        // At most the `A` alarms are due: one re-armed here, or armed by an action, is
        // at least one tick away (`arm` takes `delay >= 1`), so it is behind them.
        for _ in 0..A {
            // A `ShutdownOS` inside an action (from `ErrorHook` or a callback) disarms
            // every alarm, so the walk ends there too.
            let a = self.counter_head[c] as usize;
            if a >= A || self.alarm_delta[a] != 0 {
                break;
            }
            let cycle = self.alarm_cycle[a];
            self.counter_head[c] = self.alarm_next[a];
            if cycle != 0 {
                // Back in the list `cycle` ticks on: `arm` writes its link, delta, flag
                // and cycle.
                self.arm(a, c, cycle, cycle);
            } else {
                // Disarmed, as `disarm` leaves it (its delta is 0 already, its cycle 0).
                self.alarm_next[a] = NONE;
                self.alarm_active[a] = false;
            }
            match self.cfg().alarms[a].action {
                AlarmAction::ActivateTask(task) => {
                    let result = Self::task_index(task).and_then(|t| self.activate(t).map(|_| ()));
                    if let Err(e) = result {
                        self.report(ServiceCall::ActivateTask(task), e);
                    }
                }
                // Never true where it is tested (an alarm with another action makes the
                // flag false); with constant tables whose alarms all activate tasks, the
                // arms below are folded away.
                _ if self.cfg().task_alarms_only => {}
                AlarmAction::SetEvent(task, mask) => {
                    let result = Self::task_index(task).and_then(|t| self.set_event_inner(t, mask));
                    if let Err(e) = result {
                        self.report(ServiceCall::SetEvent(task, mask), e);
                    }
                }
                AlarmAction::Callback(id) => {
                    self.call_hook(Context::AlarmCallback, |os| H::alarm_callback(os, id));
                }
            }
        }
    }

    /// `GetCounterValue` (AUTOSAR): the counter's current value.
    ///
    /// # Errors
    /// `E_OS_ID` invalid counter; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn get_counter_value(&mut self, counter: CounterId) -> Result<TickType, OsError> {
        self.service(
            ServiceId::GetCounterValue,
            || ServiceCall::GetCounterValue(counter),
            |os| {
                let c = Self::counter_index(counter)?;
                Ok(os.counter_value[c])
            },
        )
    }

    /// `GetElapsedValue` (AUTOSAR): the counter's value now and the ticks elapsed since
    /// `previous` (modulo the counter's range).
    ///
    /// # Errors
    /// `E_OS_ID` invalid counter; `E_OS_VALUE` `previous` above `maxallowedvalue`;
    /// `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn get_elapsed_value(
        &mut self,
        counter: CounterId,
        previous: TickType,
    ) -> Result<(TickType, TickType), OsError> {
        self.service(
            ServiceId::GetElapsedValue,
            || ServiceCall::GetElapsedValue(counter, previous),
            |os| {
                let c = Self::counter_index(counter)?;
                let max = os.cfg().counters[c].max_allowed_value;
                if previous > max {
                    return Err(OsError::Value);
                }
                let now = os.counter_value[c];
                let elapsed = if now >= previous {
                    now - previous
                } else {
                    // Wrapped: (max + 1 - previous) + now, which is at most max.
                    max - previous + now + 1
                };
                Ok((now, elapsed))
            },
        )
    }
}
