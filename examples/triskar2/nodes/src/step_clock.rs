//! Step interval from successive `now_ns` values, shared by every node with a period.

use crate::Nanos;

/// Turns the absolute times a node is stepped at into a step length in seconds.
///
/// The first step has no predecessor and uses the nominal period. A late step (a task
/// preempted, a frame lost) is clamped to `max_ns` so an integrator does not take one
/// huge stride; a clock that goes backwards gives a zero step (nothing to integrate).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct StepClock {
    last_ns: Option<Nanos>,
    nominal_ns: Nanos,
    max_ns: Nanos,
}

impl StepClock {
    pub(crate) const fn new(nominal_ns: Nanos, max_ns: Nanos) -> Self {
        Self {
            last_ns: None,
            nominal_ns,
            max_ns,
        }
    }

    /// Step length in seconds since the previous call.
    pub(crate) fn dt_s(&mut self, now_ns: Nanos) -> f32 {
        let dt_ns = match self.last_ns {
            None => self.nominal_ns,
            Some(last) => now_ns.saturating_sub(last).min(self.max_ns),
        };
        // Never move the reference backwards: a stale timestamp must not make the
        // next step count the same interval twice.
        self.last_ns = Some(self.last_ns.map_or(now_ns, |last| last.max(now_ns)));
        dt_ns as f32 * 1e-9
    }

    pub(crate) fn reset(&mut self) {
        self.last_ns = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_is_nominal_then_measured_and_clamped() {
        let mut c = StepClock::new(5_000_000, 20_000_000);
        assert_eq!(c.dt_s(1_000_000_000), 0.005);
        assert_eq!(c.dt_s(1_010_000_000), 0.01);
        assert_eq!(c.dt_s(2_000_000_000), 0.02);
        // Backwards: zero step, and the reference stays at the latest time.
        assert_eq!(c.dt_s(1_500_000_000), 0.0);
        assert_eq!(c.dt_s(2_005_000_000), 0.005);
        c.reset();
        assert_eq!(c.dt_s(9), 0.005);
    }
}
