//! The live view: a run's or a drive's JSON topics ([`crate::json_topics`],
//! the same as its MCAP log's) served on the Foxglove WebSocket protocol as
//! they happen, for Foxglove, or any client of the protocol, to watch.
//!
//! The server only advertises and sends: it takes no messages, parameters
//! or service calls from its clients, so a viewer cannot move the robot.
//! It still shows the robot's surroundings to anyone who can reach its
//! address: it binds only where it is told, the docs give loopback, and
//! [`LiveServer::announce`] warns when it is anything else.
//!
//! A slow viewer never slows a tick: the view runs on a thread of its own,
//! which takes the latest tick to show from a one-record mailbox every
//! 20 ms (the tick never wakes it and never waits for it; a tick it has
//! not taken yet is replaced only by one that adds a collision, and a tick
//! that finds the view holding the mailbox is not shown, the next offered
//! in its place), and the server keeps a bounded queue per
//! client, dropping that client's oldest messages when it cannot keep up.
//! While nobody watches, no record is handed over; messages of a topic
//! nobody has subscribed to are not made. A viewer is shown at most 20
//! ticks a second ([`SHOW_EVERY`]), and every tick that adds a collision;
//! a run's log keeps every tick.

use crate::json_topics::{nanos, JsonChannels, JsonTopics, RunMessage, WorldMessage};
use foxglove::WebSocketServerHandle;
use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};
use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, TryLockError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use ubf_core::{TickRecord, TickSink, TreeLayout};

/// Why the live view could not be served.
#[derive(Debug, thiserror::Error)]
#[error("serving the live view on {address}: {message}")]
pub struct LiveError {
    address: SocketAddr,
    message: String,
}

/// A live view's server: its channels, once for all the sessions of a
/// drive, which may reconnect to its robot many times.
pub struct LiveServer {
    channels: LiveChannels,
    server: Option<WebSocketServerHandle>,
    address: SocketAddr,
}

/// The server's channels, one per topic.
#[derive(Clone)]
struct LiveChannels {
    channels: BTreeMap<&'static str, Arc<RawChannel>>,
    context: Arc<Context>,
    /// Unix time of the session's time 0, ns: Foxglove's timeline shows
    /// the time of day.
    epoch_ns: u64,
}

impl JsonChannels for LiveChannels {
    type Error = foxglove::FoxgloveError;

    fn declare(&mut self, topic: &'static str, schema_name: &str, schema: &[u8]) -> Result<(), Self::Error> {
        let channel = ChannelBuilder::new(topic)
            .context(&self.context)
            .message_encoding("json")
            .schema(Schema::new(schema_name, "jsonschema", schema.to_vec()))
            .build_raw()?;
        self.channels.insert(topic, channel);
        Ok(())
    }

    fn wanted(&self, topic: &'static str) -> bool {
        self.channels[topic].has_sinks()
    }

    fn write(&mut self, topic: &'static str, time: f64, data: &[u8]) -> Result<(), Self::Error> {
        let log_time = self.epoch_ns + nanos(time);
        self.channels[topic].log_with_meta(data, PartialMetadata { log_time: Some(log_time) });
        Ok(())
    }
}

/// Messages held for a viewer that falls behind, after which its oldest
/// are dropped (a viewer that stops reading its control messages is cut
/// off). The library's 1024 held about 24 MB a stalled viewer with
/// rendered images, and viewers are anyone who can reach the port; 256 is
/// over a second of every topic at the view's 20 Hz.
const VIEWER_BACKLOG: usize = 256;

impl LiveServer {
    /// Serves the live view on `address` (port 0: a free port, which
    /// [`LiveServer::address`] tells), with `/report`'s schema named and
    /// given by `report`.
    pub fn serve(address: SocketAddr, report: (&str, Vec<u8>)) -> Result<LiveServer, LiveError> {
        let fail = |e: &dyn std::fmt::Display| LiveError { address, message: e.to_string() };
        let context = Context::new();
        let mut channels = LiveChannels { channels: BTreeMap::new(), context: context.clone(), epoch_ns: 0 };
        JsonTopics::declare(&mut channels, report).map_err(|e| fail(&e))?;
        let server = WebSocketServer::new()
            .name(concat!("ubf ", env!("CARGO_PKG_VERSION")))
            .bind(address.ip().to_string(), address.port())
            .message_backlog_size(VIEWER_BACKLOG)
            .context(&context)
            .start_blocking()
            .map_err(|e| fail(&e))?;
        let bound = SocketAddr::new(address.ip(), server.port());
        Ok(LiveServer { channels, server: Some(server), address: bound })
    }

    /// Where the server listens.
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Says on stderr where the view is served, and, off loopback, who can
    /// watch it.
    pub fn announce(&self) {
        eprintln!("live view on ws://{} (Foxglove: Open connection, Foxglove WebSocket)", self.address);
        if !self.address.ip().is_loopback() {
            eprintln!(
                "warning: the live view is served beyond this machine: anyone who can reach {} sees the robot, \
                 where it is and what its sensors see, without a password or encryption",
                self.address
            );
        }
    }

    /// A sink showing one session, `run` in `world`, whose time 0 is now,
    /// on its own thread ([`LiveSink`]): a viewer that falls behind costs
    /// dropped records, never a tick.
    pub fn view(&self, run: RunMessage, world: WorldMessage) -> Result<LiveSink, LiveError> {
        self.view_napping(run, world, TAKE_EVERY)
    }

    /// [`LiveServer::view`] with the view's thread looking for a tick every
    /// `nap` rather than every [`TAKE_EVERY`]. Not public: only the tests
    /// need another nap, a long one, so that the thread takes nothing
    /// unless woken, and what they check cannot pass by the thread's
    /// timing.
    fn view_napping(&self, run: RunMessage, world: WorldMessage, nap: Duration) -> Result<LiveSink, LiveError> {
        let now = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64);
        let channels = LiveChannels { epoch_ns: now, ..self.channels.clone() };
        let watchable: Vec<Arc<RawChannel>> = channels.channels.values().cloned().collect();
        let view = LiveView {
            channels,
            topics: JsonTopics::default(),
            run,
            world,
            described_at: None,
            last_tick: None,
            started: false,
            nap,
        };
        let mailbox = Arc::new(Mutex::new(Mailbox::default()));
        let thread = {
            let mailbox = mailbox.clone();
            std::thread::Builder::new()
                .name("live view".into())
                .spawn(move || view.serve(&mailbox))
                .map_err(|e| LiveError { address: self.address, message: format!("starting its thread: {e}") })?
        };
        let now = Instant::now();
        Ok(LiveSink {
            mailbox,
            thread: Some(thread),
            new_layout: None,
            dropped: 0,
            unshown_collision: false,
            channels: watchable,
            watched: false,
            ask_at: now,
            show_at: now,
            collisions: 0,
            watched_from: 0,
        })
    }
}

impl Drop for LiveServer {
    /// Closes the listening socket and every client's connection, waiting
    /// `CLOSE_WAIT` (a second) at most: a viewer that has stopped reading
    /// never answers its close, and must not hold the end of a run or a
    /// drive.
    fn drop(&mut self) {
        if let Some(server) = self.server.take() {
            let shutdown = server.stop();
            let (closed, wait) = crossbeam_channel::bounded(1);
            let waiting = std::thread::Builder::new().name("live view close".into()).spawn(move || {
                shutdown.wait_blocking();
                let _ = closed.send(());
            });
            if waiting.is_ok() {
                let _ = wait.recv_timeout(CLOSE_WAIT);
            }
        }
    }
}

/// How long the end of a session waits for its viewers' connections to
/// close.
const CLOSE_WAIT: Duration = Duration::from_secs(1);

/// How often a live view asks whether anyone watches: a new viewer's
/// first messages come this much later at most.
const ASK_EVERY: Duration = Duration::from_millis(100);

/// How often the live view's thread looks for a tick to show: a viewer
/// sees the robot 20 ms late at most, and the tick never wakes a thread
/// (waking it every tick cost a viewer's tick 46 %).
const TAKE_EVERY: Duration = Duration::from_millis(20);

/// The least wall time between two ticks the view shows: a viewer gets at
/// most 20 ticks a second, about as often as a screen can show a change
/// worth seeing, while the log gets every one. A robot ticking at 10 Hz in
/// real time is shown whole; a run at `--speed 10` (100 ticks a second) is
/// shown every fifth tick. Handing a record to the view's thread is most
/// of what a viewer costs a tick, so the ticks not shown cost no more than
/// an unwatched view.
pub const SHOW_EVERY: Duration = Duration::from_millis(50);

/// Seconds of controller time between repeats of what the session is (its
/// run, world, goal and scene): the protocol keeps no message for a viewer
/// that connects later, so they are said again.
const DESCRIBE_EVERY_S: f64 = 1.0;

/// The live view of one session, as the controller holds it: records go
/// to the view's own thread only while someone watches, so an unwatched
/// view costs a tick next to nothing.
///
/// A shown tick is copied into a one-record mailbox that only this side
/// writes, and that the view's thread copies out of. Timed on the
/// `live_view` bench (docs/performance.md): the copy into a buffer of a
/// pool that had been to the view's thread and back cost the tick 4.5 µs
/// (memory the other core last held), and the channel operations and the
/// check on the thread around it 2.2 µs more; the copy into the mailbox
/// costs 1.3 µs and its lock 0.4 µs. The controller's record itself is not
/// handed over instead: the robot senses into it and keeps in it what it
/// does not renew (the last stereo frame), so a record swapped for a spare
/// would have to be copied back into the spare, the same copy into the
/// same distant memory.
pub struct LiveSink {
    /// The latest tick to show, shared with the view's thread.
    mailbox: Arc<Mutex<Mailbox>>,
    /// The view's thread; it ends when the mailbox is closed, or early
    /// when showing fails.
    thread: Option<JoinHandle<std::io::Result<()>>>,
    /// A new tree's layout, put in the mailbox with the next tick shown.
    new_layout: Option<TreeLayout>,
    /// Ticks not shown because the view's thread held the mailbox or had
    /// not taken the last one yet.
    dropped: u64,
    /// Whether a tick that added a collision found the view holding the
    /// mailbox: the next tick is then shown in its place, at once.
    unshown_collision: bool,
    /// The channels, to ask whether anyone subscribes.
    channels: Vec<Arc<RawChannel>>,
    /// Whether anyone subscribed when last asked, and when to ask again:
    /// asking costs more than a tick can spare (the `live_view` bench).
    watched: bool,
    ask_at: Instant,
    /// When the next tick may be shown ([`SHOW_EVERY`]).
    show_at: Instant,
    /// The collisions so far, as of the last tick: a tick that adds one is
    /// shown whatever the time, so that the viewer sees where it happened.
    collisions: u32,
    /// The tick from which the current viewers have watched, for the view
    /// to tell a gap nobody watched from ticks left out by [`SHOW_EVERY`].
    watched_from: u64,
}

/// What the tick leaves for the view's thread, which takes it every
/// [`TAKE_EVERY`]. Each side holds the lock only to copy a record in or
/// out; the tick never waits for it: when the view holds it, that tick is
/// not shown.
#[derive(Default)]
struct Mailbox {
    /// The latest tick to show: written only by the tick's side, so that
    /// the copy lands in memory that side keeps (the view copies out).
    record: TickRecord,
    /// `record` is new since the view last took it. While it is, the tick
    /// puts only a tick that added a collision in its place (whose count
    /// includes the collisions of the one it replaces: two collisions
    /// within 20 ms are shown as one, at the later).
    fresh: bool,
    /// [`LiveSink::watched_from`] as of `record`.
    watched_from: u64,
    /// The layout of `record` and the records after it, when it changed.
    layout: Option<TreeLayout>,
    /// The session is over: the view shows what is left and ends.
    closed: bool,
    /// The view's thread has ended early (showing failed, or it
    /// panicked): the tick reports it.
    ended: bool,
}

/// Locks the mailbox, whatever happened to the other side: neither side
/// can leave it half written (a copy does not panic), so a poisoned lock
/// is still a good one.
fn lock(mailbox: &Mutex<Mailbox>) -> MutexGuard<'_, Mailbox> {
    mailbox.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Marks the mailbox when the view's thread ends, however it ends (a
/// panic included), so that the tick finds out.
struct Ended<'a>(&'a Mutex<Mailbox>);

impl Drop for Ended<'_> {
    fn drop(&mut self) {
        lock(self.0).ended = true;
    }
}

impl LiveSink {
    /// The view's thread has ended early: why, named.
    fn stopped(&mut self) -> std::io::Error {
        match self.finish() {
            Err(e) => e,
            Ok(()) => std::io::Error::other("live view: its thread stopped"),
        }
    }
}

impl TickSink for LiveSink {
    /// Gives the view the tree's layout: once, before the first tick, so
    /// waiting for the lock here costs no tick.
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        lock(&self.mailbox).layout = Some(layout.clone());
        Ok(())
    }

    /// Keeps the new layout to put in the mailbox with the next tick shown,
    /// so that the view never names one tree's nodes by another's layout
    /// and the tick never waits.
    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.new_layout = Some(layout.clone());
        Ok(())
    }

    /// Puts the record in the mailbox if anyone watches and [`SHOW_EVERY`]
    /// has passed since the last one, or if the tick added a collision. A
    /// first viewer is told what the session is with the first record it
    /// gets: the view says it again when a second has passed since it last
    /// did.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let now = Instant::now();
        if now >= self.ask_at {
            self.ask_at = now + ASK_EVERY;
            let watched = self.channels.iter().any(|c| c.has_sinks());
            if watched && !self.watched {
                self.watched_from = record.tick;
            }
            self.watched = watched;
        }
        let collisions = record.truth.map_or(0, |t| t.collisions);
        let collided = collisions > self.collisions || self.unshown_collision;
        self.collisions = collisions;
        if !self.watched || (now < self.show_at && !collided) {
            return Ok(());
        }
        let mut mailbox = match self.mailbox.try_lock() {
            Ok(mailbox) => mailbox,
            Err(TryLockError::Poisoned(poisoned)) => poisoned.into_inner(),
            Err(TryLockError::WouldBlock) => {
                // The view is copying the last tick out: this one is not
                // shown, and the schedule stays where it is, so the next
                // tick is offered at once (with a collision this one added).
                if self.dropped == 0 {
                    tracing::debug!("live view: a tick was not shown: the view's thread was taking the last");
                }
                self.unshown_collision |= collided;
                self.dropped += 1;
                return Ok(());
            }
        };
        if mailbox.ended {
            drop(mailbox);
            return Err(self.stopped());
        }
        // On the schedule while ticks keep up with it, so that 100 ticks a
        // second are shown every fifth rather than every sixth; after a
        // pause, from now.
        let next = self.show_at + SHOW_EVERY;
        self.show_at = if next > now { next } else { now + SHOW_EVERY };
        if mailbox.fresh && !collided {
            // The view has not taken the last tick yet (it is 50 ms
            // behind): that one stays, so that a tick that added a
            // collision is only ever replaced by another that did.
            self.dropped += 1;
            return Ok(());
        }
        mailbox.record.copy_from(record);
        mailbox.fresh = true;
        self.unshown_collision = false;
        mailbox.watched_from = self.watched_from;
        if let Some(layout) = self.new_layout.take() {
            mailbox.layout = Some(layout);
        }
        Ok(())
    }

    /// Closes the mailbox and waits for the view's thread to show what is
    /// left; its own failure, if it failed.
    fn finish(&mut self) -> std::io::Result<()> {
        let Some(thread) = self.thread.take() else { return Ok(()) };
        lock(&self.mailbox).closed = true;
        thread.thread().unpark();
        if self.dropped > 0 {
            tracing::debug!("live view: {} ticks not shown while the view's thread was behind", self.dropped);
        }
        thread.join().unwrap_or_else(|_| Err(std::io::Error::other("live view: its thread panicked")))
    }
}

impl Drop for LiveSink {
    /// Ends the view's thread with the sink, however the session ended.
    fn drop(&mut self) {
        if let Err(e) = self.finish() {
            tracing::warn!("{e}");
        }
    }
}

/// One session shown live.
struct LiveView {
    channels: LiveChannels,
    topics: JsonTopics,
    run: RunMessage,
    world: WorldMessage,
    /// Controller time at which the session was last described.
    described_at: Option<f64>,
    /// The last tick shown.
    last_tick: Option<u64>,
    /// Whether the view has been given its first layout.
    started: bool,
    /// How long the thread sleeps between looks at the mailbox
    /// ([`TAKE_EVERY`] but in tests).
    nap: Duration,
}

impl LiveView {
    /// The view's thread: every nap ([`TAKE_EVERY`]), or when woken to end, it
    /// copies what the mailbox holds out of it and shows it, until the
    /// mailbox is closed or showing fails.
    fn serve(mut self, mailbox: &Mutex<Mailbox>) -> std::io::Result<()> {
        let _ended = Ended(mailbox);
        let mut record = TickRecord::default();
        loop {
            std::thread::park_timeout(self.nap);
            let (layout, fresh, watched_from, closed) = {
                let mut mailbox = lock(mailbox);
                let fresh = std::mem::take(&mut mailbox.fresh);
                if fresh {
                    // A copy rather than a swap: the mailbox's buffer stays
                    // memory the tick's side writes, and the cost of moving
                    // the record between cores falls on this thread.
                    record.copy_from(&mailbox.record);
                }
                (mailbox.layout.take(), fresh, mailbox.watched_from, mailbox.closed)
            };
            if let Some(layout) = layout {
                if std::mem::replace(&mut self.started, true) {
                    self.topics.start(&layout);
                } else {
                    self.start(&layout);
                }
            }
            if fresh {
                self.show(&record, watched_from)
                    .map_err(|e| std::io::Error::new(e.kind(), format!("live view: {e}")))?;
            }
            if closed {
                return Ok(());
            }
        }
    }

    /// The tree of the ticks to come, the first time.
    fn start(&mut self, layout: &TreeLayout) {
        self.topics.start(layout);
        // The camera's pairs cost nothing until a viewer subscribes.
        self.topics.images(true);
    }

    /// Shows the tick to viewers who have watched from tick `from`.
    /// Sending cannot fail: a client that cannot keep up loses messages,
    /// and the tick goes on.
    fn show(&mut self, record: &TickRecord, from: u64) -> std::io::Result<()> {
        let time = record.time();
        // Ticks left out between two shown are no gap: a tick that added a
        // collision is shown (or, overwritten in the mailbox before the
        // view took it, its collision comes with the next). Ticks nobody
        // watched are: what they did is not news to a viewer who has just
        // come.
        if self.last_tick.is_none_or(|last| from > last) {
            self.topics.catch_up(record);
        }
        self.last_tick = Some(record.tick);
        if self.described_at.is_none_or(|at| time - at >= DESCRIBE_EVERY_S) {
            self.described_at = Some(time);
            JsonTopics::describe(&mut self.channels, time, &self.run, &self.world).map_err(std::io::Error::other)?;
        }
        self.topics.tick(&mut self.channels, record).map_err(std::io::Error::other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::{self, RecvTimeoutError};
    use ubf_core::GroundTruth;

    /// The tests' views nap far longer than any test, so that their
    /// threads take nothing from the mailbox unless the sink wakes them to
    /// end: what a test finds in the mailbox is what the sink left there,
    /// however slow the machine (a park can in principle wake early, but
    /// nothing here leaves the thread a wake-up token to do so).
    const NAP: Duration = Duration::from_secs(3600);

    /// How long ending a view may take once its thread is woken: generous
    /// on a loaded machine, and still far below [`NAP`], so that a thread
    /// left to sleep out its nap fails the test rather than passes it late.
    const WAKE_ALLOWANCE: Duration = Duration::from_secs(30);

    fn server() -> LiveServer {
        LiveServer::serve("127.0.0.1:0".parse().unwrap(), ("ubf.Report", b"{}".to_vec())).unwrap()
    }

    fn watched_sink(server: &LiveServer) -> LiveSink {
        let run = RunMessage { scenario: "test".into(), seed: 1, start: [0.0; 3], outline: [[0.0; 2]; 4], goal: None };
        let mut sink = server.view_napping(run, WorldMessage::default(), NAP).unwrap();
        sink.start(&TreeLayout::default()).unwrap();
        // As if a viewer had subscribed, for the next hour.
        sink.watched = true;
        sink.ask_at = Instant::now() + Duration::from_secs(3600);
        sink
    }

    fn tick(tick: u64, collisions: u32) -> TickRecord {
        TickRecord { tick, truth: Some(GroundTruth { collisions, ..GroundTruth::default() }), ..TickRecord::default() }
    }

    /// The tick waiting in the mailbox for the view to take, if any.
    fn waiting(sink: &LiveSink) -> Option<u64> {
        let mailbox = lock(&sink.mailbox);
        mailbox.fresh.then_some(mailbox.record.tick)
    }

    /// Runs `end`, which ends a view, on a thread of its own, and fails if
    /// it has not returned within [`WAKE_ALLOWANCE`]: a view whose thread
    /// is not woken holds it for [`NAP`], and the test then fails at the
    /// allowance instead of hanging for the nap.
    fn ends_promptly(what: &str, end: impl FnOnce() + Send + 'static) {
        let (done, ended) = mpsc::channel();
        let ending = std::thread::spawn(move || {
            end();
            let _ = done.send(());
        });
        match ended.recv_timeout(WAKE_ALLOWANCE) {
            Ok(()) => {}
            Err(RecvTimeoutError::Timeout) => {
                panic!("{what}: still waiting after {WAKE_ALLOWANCE:?}, the view's thread was not woken")
            }
            Err(RecvTimeoutError::Disconnected) => std::panic::resume_unwind(ending.join().unwrap_err()),
        }
    }

    #[test]
    fn the_view_ends_with_its_session_without_waiting_out_its_nap() {
        let server = server();
        let mut sink = watched_sink(&server);
        for i in 0..50 {
            sink.record(&tick(i, 0)).unwrap();
        }
        // Still waiting: the view's thread is asleep for the hour.
        assert_eq!(waiting(&sink), Some(0));
        ends_promptly("finishing", move || {
            sink.finish().unwrap();
            // Woken, it showed what was left before it ended.
            assert_eq!(waiting(&sink), None);
            // Dropped after its end: no thread left to wait for.
            drop(sink);
        });
        // Dropped without an end: the drop ends it, and wakes it too.
        let sink = watched_sink(&server);
        ends_promptly("dropping", move || drop(sink));
    }

    #[test]
    fn a_tick_that_added_a_collision_is_replaced_only_by_another() {
        let server = server();
        let mut sink = watched_sink(&server);
        sink.record(&tick(0, 1)).unwrap();
        // Due at once, whatever the schedule.
        sink.show_at = Instant::now();
        sink.record(&tick(1, 1)).unwrap();
        assert_eq!(waiting(&sink), Some(0), "a tick that added no collision replaced one that did");
        sink.record(&tick(2, 2)).unwrap();
        assert_eq!(waiting(&sink), Some(2), "a tick that added a collision did not replace the last");
        ends_promptly("dropping", move || drop(sink));
    }

    #[test]
    fn a_collision_whose_tick_found_the_view_busy_goes_with_the_next_tick() {
        let server = server();
        let mut sink = watched_sink(&server);
        sink.record(&tick(0, 0)).unwrap();
        assert_eq!(waiting(&sink), Some(0));
        // No tick due for an hour: only a collision can show one.
        sink.show_at = Instant::now() + Duration::from_secs(3600);
        let mailbox = sink.mailbox.clone();
        {
            // The view holding the mailbox, as if copying a tick out, for
            // the tick that adds the collision and the one after.
            let _busy = lock(&mailbox);
            sink.record(&tick(1, 1)).unwrap();
            sink.record(&tick(2, 1)).unwrap();
        }
        assert_eq!(waiting(&sink), Some(0), "a tick was shown while the view held the mailbox");
        // The first tick to find the mailbox free carries the collision,
        // though it adds none and the schedule shows nothing.
        sink.record(&tick(3, 1)).unwrap();
        assert_eq!(waiting(&sink), Some(3), "the collision was not shown with the next tick");
        // Once shown, it is not shown again.
        sink.record(&tick(4, 1)).unwrap();
        assert_eq!(waiting(&sink), Some(3), "the collision was shown twice");
        ends_promptly("dropping", move || drop(sink));
    }
}
