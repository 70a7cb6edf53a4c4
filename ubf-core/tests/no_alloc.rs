//! After warm-up, a controller tick allocates nothing: not for a 4-behaviour
//! tree under any arbiter, not for a 3-level tree, not with its records
//! handed to a writer thread.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use ubf_core::{
    from_fn, Action, ArbiterSpec, BackgroundSink, Behavior, Composite, Condition, Controller, Goal, NullRobot,
    RangeReading, SimClock, State, TickRecord, TickSink, TracingSink,
};

struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set on the thread whose ticks are measured: the test harness's own
    /// threads allocate when they please (more so on a loaded machine), and
    /// those allocations are not the tick's.
    static MEASURED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Counts an allocation if it happens on the measured thread.
fn count() {
    if MEASURED.with(std::cell::Cell::get) {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    }
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn leaves() -> [Box<dyn Behavior>; 4] {
    [
        Box::new(from_fn("go", |s: &State| Action::with_vote(0.5).velocity(0.5).rot_velocity(-s.pose.theta))),
        Box::new(from_fn("avoid", |s: &State| match s.nearest_range() {
            Some(r) if r < 1.0 => Action::with_vote(0.9).rot_velocity(0.4).max_velocity(r * 0.5),
            _ => Action::none(),
        })),
        Box::new(from_fn("stop", |s: &State| if s.bumpers.any() { Action::stop(1.0) } else { Action::none() })),
        Box::new(from_fn("aim", |_: &State| Action::with_vote(0.3).heading(0.2))),
    ]
}

fn robot() -> NullRobot {
    let mut robot = NullRobot::default();
    robot.reported.ranges = (0..32)
        .map(|i| RangeReading { range: Some(0.5 + i as f64 * 0.1), max_range: 5.0, ..Default::default() })
        .collect();
    robot
}

/// A sink that only counts, on the writer thread of a `BackgroundSink`.
struct Counter(Arc<AtomicU64>);

impl TickSink for Counter {
    fn record(&mut self, _: &TickRecord) -> std::io::Result<()> {
        self.0.fetch_add(1, Ordering::SeqCst);
        Ok(())
    }
}

fn allocations_in_ticks(root: Box<dyn Behavior>) -> usize {
    let mut controller = Controller::new(robot(), root, Box::new(SimClock::new(0.1)));
    controller.add_sink(Box::new(TracingSink));
    let written = Arc::new(AtomicU64::new(0));
    controller.add_sink(Box::new(BackgroundSink::spawn("counter", Counter(written.clone()), 4).unwrap()));
    controller.set_goal(Some(Goal { x: 10.0, y: 0.0, tolerance: 0.2 }));
    // Warm-up: each tick waits for the writer, so that every one of the
    // background sink's buffers has been filled once.
    for tick in 1..=10 {
        controller.tick().unwrap();
        while written.load(Ordering::SeqCst) < tick {
            std::thread::yield_now();
        }
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    MEASURED.with(|m| m.set(true));
    for _ in 0..1000 {
        controller.tick().unwrap();
    }
    MEASURED.with(|m| m.set(false));
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn a_warm_tick_allocates_nothing() {
    let specs = [
        ArbiterSpec::HighestPriority,
        ArbiterSpec::SimplePriority,
        ArbiterSpec::HighestActivation,
        ArbiterSpec::MonteCarlo { hold_ticks: 3 },
        ArbiterSpec::ActivationFusion,
        ArbiterSpec::PriorityFusion,
        ArbiterSpec::UtilityFusion,
        ArbiterSpec::CommandFusion,
        ArbiterSpec::PriorityResolver { priorities: vec![3, 2, 2, 1] },
        ArbiterSpec::Conditional {
            when: Condition::Any(vec![Condition::Bumped, Condition::ObstacleWithin { range: 0.3 }]),
        },
    ];
    // The count can fail: a behaviour that formats a string every tick is
    // seen.
    let allocating = from_fn("chatty", |s: &State| {
        std::hint::black_box(format!("{}", s.time));
        Action::none()
    });
    assert!(allocations_in_ticks(Box::new(allocating)) >= 1000);

    for spec in specs {
        let mut tree = Composite::with_arbiter("root", spec.build(ChaCha8Rng::seed_from_u64(1)));
        let take = if matches!(spec, ArbiterSpec::Conditional { .. }) { 2 } else { 4 };
        for (i, leaf) in leaves().into_iter().take(take).enumerate() {
            tree.push_child(format!("leaf{i}"), leaf, 1.0 + i as f64);
        }
        assert_eq!(allocations_in_ticks(Box::new(tree)), 0, "{spec:?}");
    }

    // Three levels: root → (safety, drive → (go, aim)).
    let [go, avoid, stop, aim] = leaves();
    let mut drive = Composite::new("drive", ubf_core::arbiter::CommandFusion).vote(0.6);
    drive.push_child("go".into(), go, 1.0);
    drive.push_child("aim".into(), aim, 1.0);
    let mut safety = Composite::new("safety", ubf_core::arbiter::HighestPriority);
    safety.push_child("stop".into(), stop, 2.0);
    safety.push_child("avoid".into(), avoid, 1.0);
    let root = Composite::new("root", ubf_core::arbiter::HighestActivation).child(safety, 2.0).child(drive, 1.0);
    assert_eq!(allocations_in_ticks(Box::new(root)), 0, "3-level tree");
}
