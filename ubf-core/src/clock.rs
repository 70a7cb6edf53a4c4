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
    period: Duration,
    start: Instant,
    next: Instant,
}

impl WallClock {
    /// A clock ticking every `period` seconds of real time.
    pub fn new(period: f64) -> Self {
        let start = Instant::now();
        let period = Duration::from_secs_f64(period.max(0.0));
        WallClock { period, start, next: start + period }
    }
}

impl Clock for WallClock {
    fn now(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
    fn period(&self) -> f64 {
        self.period.as_secs_f64()
    }
    fn wait_for_next_tick(&mut self) {
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
            self.next += self.period;
        } else {
            self.next = now + self.period;
        }
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
    fn sim_clock_advances_by_whole_periods() {
        let mut clock = SimClock::new(0.1);
        for _ in 0..1000 {
            clock.wait_for_next_tick();
        }
        assert_eq!(clock.now(), 1000.0 * 0.1);
    }
}
