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
//! A slow viewer never slows a tick: the view runs on a thread of its own
//! behind a [`BackgroundSink`], which drops records when it falls behind
//! and which the tick never has to wake (it takes what has come every
//! 20 ms), and the server keeps a bounded queue per client, dropping that
//! client's oldest messages when it cannot keep up. While nobody watches,
//! no record is handed over; messages of a topic nobody has subscribed to
//! are not made. A viewer is shown at most 20 ticks a second
//! ([`SHOW_EVERY`]), and every tick that adds a collision; a run's log
//! keeps every tick.

use crate::json_topics::{nanos, JsonChannels, JsonTopics, RunMessage, WorldMessage};
use foxglove::WebSocketServerHandle;
use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};
use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use ubf_core::{BackgroundSink, TickRecord, TickSink, TreeLayout};

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
        let now = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64);
        let channels = LiveChannels { epoch_ns: now, ..self.channels.clone() };
        let watchable: Vec<Arc<RawChannel>> = channels.channels.values().cloned().collect();
        let watched_from = Arc::new(AtomicU64::new(0));
        let view = LiveView {
            channels,
            topics: JsonTopics::default(),
            run,
            world,
            described_at: None,
            last_tick: None,
            watched_from: watched_from.clone(),
        };
        let background = BackgroundSink::spawn_batched("live view", view, QUEUE, BATCH_EVERY)
            .map_err(|e| LiveError { address: self.address, message: format!("starting its thread: {e}") })?;
        let now = Instant::now();
        Ok(LiveSink {
            background,
            channels: watchable,
            watched: false,
            ask_at: now,
            show_at: now,
            collisions: 0,
            watched_from,
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

/// Ticks the live view may fall behind by before records are dropped.
const QUEUE: usize = 64;

/// How often a live view asks whether anyone watches: a new viewer's
/// first messages come this much later at most.
const ASK_EVERY: Duration = Duration::from_millis(100);

/// How often the live view takes the records that have come: a viewer
/// sees the robot 20 ms late at most, and the tick never wakes a thread.
const BATCH_EVERY: Duration = Duration::from_millis(20);

/// The least wall time between two ticks the view shows: a viewer gets at
/// most 20 ticks a second, about as often as a screen can show a change
/// worth seeing, while the log gets every one. A robot ticking at 10 Hz in
/// real time is shown whole; a run at `--speed 10` (100 ticks a second) is
/// shown every fifth tick. Handing a record to the view's thread is most
/// of what a viewer costs a tick (its copy lands in memory the other core
/// last held), so the ticks not shown cost no more than an unwatched view.
pub const SHOW_EVERY: Duration = Duration::from_millis(50);

/// Seconds of controller time between repeats of what the session is (its
/// run, world, goal and scene): the protocol keeps no message for a viewer
/// that connects later, so they are said again.
const DESCRIBE_EVERY_S: f64 = 1.0;

/// The live view of one session, as the controller holds it: records go
/// to the view's own thread ([`BackgroundSink`]) only while someone
/// watches, so an unwatched view costs a tick next to nothing.
pub struct LiveSink {
    background: BackgroundSink,
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
    watched_from: Arc<AtomicU64>,
}

impl TickSink for LiveSink {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.background.start(layout)
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.background.tree_changed(layout)
    }

    /// Hands the record over if anyone watches and [`SHOW_EVERY`] has
    /// passed since the last one, or if the tick added a collision. A first
    /// viewer is told what the session is with the first record it gets:
    /// the view says it again when a second has passed since it last did.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let now = Instant::now();
        if now >= self.ask_at {
            self.ask_at = now + ASK_EVERY;
            let watched = self.channels.iter().any(|c| c.has_sinks());
            if watched && !self.watched {
                self.watched_from.store(record.tick, Ordering::Relaxed);
            }
            self.watched = watched;
        }
        let collisions = record.truth.map_or(0, |t| t.collisions);
        let collided = collisions > self.collisions;
        self.collisions = collisions;
        if !self.watched || (now < self.show_at && !collided) {
            return Ok(());
        }
        // On the schedule while ticks keep up with it, so that 100 ticks a
        // second are shown every fifth rather than every sixth; after a
        // pause, from now.
        let next = self.show_at + SHOW_EVERY;
        self.show_at = if next > now { next } else { now + SHOW_EVERY };
        self.background.record(record)
    }

    fn finish(&mut self) -> std::io::Result<()> {
        self.background.finish()
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
    /// The tick from which the current viewers have watched
    /// ([`LiveSink`] sets it).
    watched_from: Arc<AtomicU64>,
}

impl TickSink for LiveView {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.topics.start(layout);
        // The camera's pairs cost nothing until a viewer subscribes.
        self.topics.images(true);
        Ok(())
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.topics.start(layout);
        Ok(())
    }

    /// Shows the tick. Sending cannot fail: a client that cannot keep up
    /// loses messages, and the tick goes on.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let time = record.time();
        // Ticks left out between two shown are no gap: a tick that added a
        // collision is shown (or, dropped by a view far behind, its
        // collision comes with the next). Ticks nobody watched are: what
        // they did is not news to a viewer who has just come.
        let from = self.watched_from.load(Ordering::Relaxed);
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
