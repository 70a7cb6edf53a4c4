//! A control loop that stops ticking (a behaviour stuck in a loop, a
//! device read that never returns) leaves the robot on its last command,
//! which nothing in the loop can take back. A thread of its own watches
//! the ticks, and once they have stopped for as long as a lost link is
//! given, stops the robot from outside the loop, as Ctrl-C does, and holds
//! it still.

use super::ON_INTERRUPT;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use ubf_core::{TickRecord, TickSink};

/// How often the watch looks at the ticks.
const LOOK_EVERY: Duration = Duration::from_millis(50);

/// What the watch and the loop's sink share.
struct Shared {
    /// When the loop last ticked, ms since `started`; 0 before the first.
    last_tick_ms: AtomicU64,
    started: Instant,
    /// Set when the session's run ends: the stop sequence that follows
    /// brakes without ticking, on purpose.
    disarmed: AtomicBool,
}

/// The watch over one session's ticks: [`LoopWatch::sink`] goes to the
/// controller; [`LoopWatch::disarm`] when its run ends.
pub(super) struct LoopWatch {
    shared: Arc<Shared>,
}

impl LoopWatch {
    /// Starts watching: after the first tick, ticks silent for `limit`
    /// halt the robot armed for interrupts.
    pub(super) fn start(limit: Duration) -> std::io::Result<LoopWatch> {
        let shared = Arc::new(Shared {
            last_tick_ms: AtomicU64::new(0),
            started: Instant::now(),
            disarmed: AtomicBool::new(false),
        });
        let watched = Arc::clone(&shared);
        std::thread::Builder::new().name("loop watch".into()).spawn(move || watch(&watched, limit))?;
        Ok(LoopWatch { shared })
    }

    /// What the controller pets on every tick.
    pub(super) fn sink(&self) -> Box<dyn TickSink> {
        Box::new(Pet(Arc::clone(&self.shared)))
    }

    /// Stops watching: the session's run is over.
    pub(super) fn disarm(&self) {
        self.shared.disarmed.store(true, Ordering::SeqCst);
    }
}

impl Drop for LoopWatch {
    fn drop(&mut self) {
        self.disarm();
    }
}

/// Until disarmed: halts the robot once the ticks have been silent for
/// `limit`, and says so.
fn watch(shared: &Shared, limit: Duration) {
    while !shared.disarmed.load(Ordering::SeqCst) {
        std::thread::sleep(LOOK_EVERY);
        let last = shared.last_tick_ms.load(Ordering::SeqCst);
        let silent = shared.started.elapsed().saturating_sub(Duration::from_millis(last));
        if last == 0 || silent < limit || shared.disarmed.load(Ordering::SeqCst) {
            continue;
        }
        let halted = match ON_INTERRUPT.lock() {
            Ok(guard) => guard.as_ref().map(|emergency| emergency.halt()),
            Err(_) => None,
        };
        let what = match halted {
            Some(Ok(())) => "robot stopped and held still",
            Some(Err(_)) => "stopping the robot failed",
            None => "no robot to stop",
        };
        crate::say!(
            "error: the control loop has not ticked for {:.1} s: {what}; the drive goes on only once it ticks again, \
             holding the robot, until it is restarted",
            silent.as_secs_f64()
        );
        return;
    }
}

/// The sink that tells the watch the loop ticked.
struct Pet(Arc<Shared>);

impl TickSink for Pet {
    fn record(&mut self, _: &TickRecord) -> std::io::Result<()> {
        let ms = u64::try_from(self.0.started.elapsed().as_millis()).unwrap_or(u64::MAX).max(1);
        self.0.last_tick_ms.store(ms, Ordering::SeqCst);
        Ok(())
    }
}
