//! Time. Nothing in the framework reads the system time except through a
//! [`Clock`], so a simulated run is exactly repeatable.

use std::time::{Duration, Instant};

/// The controller's sense of time.
pub trait Clock: Send {
    /// Seconds since the clock started.
    fn now(&self) -> f64;
    /// Seconds between ticks.
    fn period(&self) -> f64;
    /// Returns when the next tick is due (a simulated clock just advances).
    fn wait_for_next_tick(&mut self);
}

/// Simulated time: advances exactly one period per tick and never sleeps.
#[derive(Clone, Debug)]
pub struct SimClock {
    period: f64,
    ticks: u64,
}

impl SimClock {
    /// A clock ticking every `period` seconds of simulated time.
    pub fn new(period: f64) -> Self {
        SimClock { period, ticks: 0 }
    }
}

impl Clock for SimClock {
    fn now(&self) -> f64 {
        // Multiplying rather than accumulating keeps time free of drift.
        self.ticks as f64 * self.period
    }
    fn period(&self) -> f64 {
        self.period
    }
    fn wait_for_next_tick(&mut self) {
        self.ticks += 1;
    }
}

/// Wall-clock time for a real robot: sleeps until the next tick is due. A
/// tick that overruns does not cause a burst of catch-up ticks.
#[derive(Clone, Debug)]
pub struct WallClock {
    start: Instant,
    pacer: Pacer,
}

impl WallClock {
    /// A clock ticking every `period` seconds of real time.
    pub fn new(period: f64) -> Self {
        WallClock { start: Instant::now(), pacer: Pacer::new(Duration::from_secs_f64(period.max(0.0))) }
    }
}

impl Clock for WallClock {
    fn now(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
    fn period(&self) -> f64 {
        self.pacer.period.as_secs_f64()
    }
    fn wait_for_next_tick(&mut self) {
        self.pacer.wait();
    }
}

/// Sleeps until the next tick of a real-time period is due; after an
/// overrun the next tick is one period on, not a burst of catch-up ticks.
/// Ticks that end more than a period late are said on stderr, at most
/// every [`SAY_LATE_EVERY`]: on a robot they mean acting on old readings,
/// and nothing else would tell.
#[derive(Clone, Debug)]
struct Pacer {
    period: Duration,
    next: Instant,
    late: LateTicks,
}

/// How often late ticks are said at most.
const SAY_LATE_EVERY: Duration = Duration::from_secs(10);

/// The ticks that ended more than a period after the next was due, since
/// they were last said.
#[derive(Clone, Debug, Default)]
struct LateTicks {
    count: u32,
    latest: Duration,
    said_at: Option<Instant>,
}

impl LateTicks {
    /// Counts a tick that ended `late` after the next was due (`period`
    /// apart), at `now`; what to say, if it is time to say it.
    fn count(&mut self, late: Duration, period: Duration, now: Instant) -> Option<String> {
        if late <= period {
            return None;
        }
        self.count += 1;
        self.latest = late;
        if self.said_at.is_some_and(|at| now - at < SAY_LATE_EVERY) {
            return None;
        }
        let count = std::mem::take(&mut self.count);
        let latest = self.latest.as_secs_f64();
        let since = match self.said_at.replace(now) {
            Some(_) => format!(" ({count} since this was last said)"),
            None => String::new(),
        };
        Some(format!(
            "the control loop is behind: a tick ended {latest:.2} s after the next was due, with ticks every {:.2} s{since}; \
             the robot acts on older readings",
            period.as_secs_f64()
        ))
    }
}

impl Pacer {
    fn new(period: Duration) -> Self {
        Pacer { period, next: Instant::now() + period, late: LateTicks::default() }
    }

    fn wait(&mut self) {
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
            self.next += self.period;
        } else {
            if let Some(said) = self.late.count(now - self.next, self.period, now) {
                tracing::warn!("{said}");
            }
            self.next = now + self.period;
        }
    }
}

/// Simulated time kept in step with the wall clock, `speed` times as
/// fast: a simulation someone watches live. Its time is the simulated
/// clock's, so a paced run computes exactly what an unpaced one does; it
/// only waits. A tick that overruns is not caught up with a burst.
#[derive(Clone, Debug)]
pub struct PacedClock {
    sim: SimClock,
    pacer: Pacer,
}

impl PacedClock {
    /// A clock ticking every `period` simulated seconds, `speed` times
    /// faster than real time (clamped to 0.01–1000).
    pub fn new(period: f64, speed: f64) -> Self {
        let real_period = Duration::from_secs_f64((period / speed.clamp(0.01, 1000.0)).max(0.0));
        PacedClock { sim: SimClock::new(period), pacer: Pacer::new(real_period) }
    }
}

impl Clock for PacedClock {
    fn now(&self) -> f64 {
        self.sim.now()
    }
    fn period(&self) -> f64 {
        self.sim.period()
    }
    fn wait_for_next_tick(&mut self) {
        self.sim.wait_for_next_tick();
        self.pacer.wait();
    }
}

/// Measures how long some work took in real time, for reports. Not a clock:
/// nothing that affects a run's outcome may read it.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch(Instant);

impl Stopwatch {
    /// Starts measuring.
    pub fn start() -> Self {
        Stopwatch(Instant::now())
    }
    /// Seconds since the start.
    pub fn elapsed_s(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_ticks_are_said_at_once_then_at_most_every_ten_seconds() {
        let (mut late, period, start) = (LateTicks::default(), Duration::from_millis(100), Instant::now());
        let at = |s: f64| start + Duration::from_secs_f64(s);
        // Within a period of the due time: not late.
        assert_eq!(late.count(Duration::from_millis(90), period, at(0.0)), None);
        let first = late.count(Duration::from_millis(700), period, at(1.0)).unwrap();
        assert!(first.starts_with("the control loop is behind: a tick ended 0.70 s after"), "{first}");
        assert_eq!(late.count(Duration::from_millis(300), period, at(2.0)), None);
        assert_eq!(late.count(Duration::from_millis(400), period, at(5.0)), None);
        let next = late.count(Duration::from_millis(500), period, at(11.0)).unwrap();
        assert!(next.contains("0.50 s after") && next.contains("(3 since this was last said)"), "{next}");
    }

    #[test]
    fn sim_clock_advances_by_whole_periods() {
        let mut clock = SimClock::new(0.1);
        for _ in 0..1000 {
            clock.wait_for_next_tick();
        }
        assert_eq!(clock.now(), 1000.0 * 0.1);
    }

    #[test]
    fn a_paced_clock_keeps_simulated_time() {
        let mut clock = PacedClock::new(0.1, 1000.0);
        for _ in 0..10 {
            clock.wait_for_next_tick();
        }
        assert_eq!(clock.now(), 10.0 * 0.1);
    }
}
