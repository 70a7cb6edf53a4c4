//! Where tick records go: a trajectory file, a log, a live view.

use crate::{TickRecord, TreeLayout};
use crossbeam_channel::{Receiver, Sender};
use std::io;
use std::thread::JoinHandle;

/// Receives every tick's record: a trajectory writer, a log file, a live plot.
pub trait TickSink: Send {
    /// Called once before the first tick with the tree's shape.
    fn start(&mut self, _layout: &TreeLayout) -> std::io::Result<()> {
        Ok(())
    }
    /// Called after every tick.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()>;
    /// Called between ticks when the tree was replaced while running
    /// ([`crate::Controller::replace_root`]): the records that follow have
    /// `layout`'s nodes. A sink that names nodes by the layout it was
    /// started with takes this one instead.
    fn tree_changed(&mut self, _layout: &TreeLayout) -> std::io::Result<()> {
        Ok(())
    }
    /// Called once when the controller shuts down: flush here.
    fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// A sink shared with whoever made it: the controller records into it, and
/// its maker reads it (or finishes it off) once the run is over.
impl<T: TickSink> TickSink for std::sync::Arc<std::sync::Mutex<T>> {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.lock().unwrap_or_else(std::sync::PoisonError::into_inner).start(layout)
    }
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        self.lock().unwrap_or_else(std::sync::PoisonError::into_inner).record(record)
    }
    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.lock().unwrap_or_else(std::sync::PoisonError::into_inner).tree_changed(layout)
    }
    fn finish(&mut self) -> std::io::Result<()> {
        self.lock().unwrap_or_else(std::sync::PoisonError::into_inner).finish()
    }
}

/// Logs every tick at `trace` level through `tracing`.
#[derive(Clone, Copy, Debug, Default)]
pub struct TracingSink;

impl TickSink for TracingSink {
    fn record(&mut self, r: &TickRecord) -> std::io::Result<()> {
        tracing::trace!(tick = r.tick, time = r.time(), x = r.state.pose.x, y = r.state.pose.y, command = ?r.command, "tick");
        Ok(())
    }
}

/// Runs a sink on a thread of its own, so that a slow disk never delays a
/// tick: a real robot's control loop must not wait for a log.
///
/// Records are copied into a fixed pool of `capacity` buffers that go to
/// the writer thread and come back, so ticks allocate nothing once each
/// buffer has been used. When the writer has every buffer (it has fallen
/// `capacity` records behind), further records are dropped and counted
/// rather than the tick waiting. If the sink fails or its thread dies, the
/// writer flushes what it can and the next [`TickSink::record`] returns the
/// failure, named: the session then ends (its robot stopped) rather than
/// running on unrecorded.
pub struct BackgroundSink {
    name: String,
    to_writer: Option<Sender<Message>>,
    spare: Receiver<Box<TickRecord>>,
    writer: Option<JoinHandle<io::Result<()>>>,
    dropped: u64,
    /// A new tree's layout, sent with the next record that is not dropped.
    new_layout: Option<TreeLayout>,
}

enum Message {
    Start(TreeLayout),
    TreeChanged(TreeLayout),
    Record(Box<TickRecord>),
}

impl BackgroundSink {
    /// Starts `sink` on a thread named after `name` (which also names it in
    /// warnings), with a pool of `capacity` record buffers.
    pub fn spawn(name: impl Into<String>, sink: impl TickSink + 'static, capacity: usize) -> io::Result<Self> {
        BackgroundSink::start(name.into(), sink, capacity)
    }

    fn start(name: String, mut sink: impl TickSink + 'static, capacity: usize) -> io::Result<Self> {
        let capacity = capacity.max(1);
        // A slot for each buffer, one for each new tree's layout (which
        // goes only with a record) and one for the start message: the
        // channel is never full.
        let (to_writer, messages) = crossbeam_channel::bounded::<Message>(2 * capacity + 1);
        let (give_back, spare) = crossbeam_channel::bounded::<Box<TickRecord>>(capacity);
        for _ in 0..capacity {
            let _ = give_back.send(Box::default());
        }
        let label = name.clone();
        let writer = std::thread::Builder::new().name(format!("sink {name}")).spawn(move || {
            let mut result = Ok(());
            while let Ok(message) = messages.recv() {
                let written = match message {
                    Message::Start(layout) => sink.start(&layout),
                    Message::TreeChanged(layout) => sink.tree_changed(&layout),
                    Message::Record(record) => {
                        let written = sink.record(&record);
                        let _ = give_back.send(record);
                        written
                    }
                };
                if let Err(e) = written {
                    result = Err(io::Error::new(e.kind(), format!("{label}: {e}")));
                    break;
                }
            }
            // Flush what was written, even after a failure.
            let finished = sink.finish().map_err(|e| io::Error::new(e.kind(), format!("{label}: {e}")));
            result.and(finished)
        })?;
        Ok(BackgroundSink {
            name,
            to_writer: Some(to_writer),
            spare,
            writer: Some(writer),
            dropped: 0,
            new_layout: None,
        })
    }

    /// Records dropped because the writer had fallen behind.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

impl TickSink for BackgroundSink {
    fn start(&mut self, layout: &TreeLayout) -> io::Result<()> {
        if let Some(to_writer) = &self.to_writer {
            // Once, before the first tick: waiting here is harmless.
            let _ = to_writer.send(Message::Start(layout.clone()));
        }
        Ok(())
    }

    fn record(&mut self, record: &TickRecord) -> io::Result<()> {
        // The writer only ends early when it failed or panicked.
        if self.writer.as_ref().is_some_and(JoinHandle::is_finished) {
            return match self.finish() {
                Err(e) => Err(e),
                Ok(()) => Err(io::Error::other(format!("{}: the writer stopped", self.name))),
            };
        }
        let Some(to_writer) = &self.to_writer else { return Ok(()) };
        let Ok(mut copy) = self.spare.try_recv() else {
            if self.dropped == 0 {
                tracing::warn!("{}: the writer has fallen behind; records are being dropped", self.name);
            }
            self.dropped += 1;
            return Ok(());
        };
        copy.copy_from(record);
        // Never full: there are no more buffers than slots.
        if let Some(layout) = self.new_layout.take() {
            let _ = to_writer.try_send(Message::TreeChanged(layout));
        }
        let _ = to_writer.try_send(Message::Record(copy));
        Ok(())
    }

    /// Passes the new layout on with the next record the writer gets, so
    /// that the tick never waits for the writer.
    fn tree_changed(&mut self, layout: &TreeLayout) -> io::Result<()> {
        self.new_layout = Some(layout.clone());
        Ok(())
    }

    /// Waits for the writer to write what it was given and flush.
    fn finish(&mut self) -> io::Result<()> {
        self.to_writer = None;
        let Some(writer) = self.writer.take() else { return Ok(()) };
        if self.dropped > 0 {
            tracing::warn!("{}: {} records dropped while the writer was behind", self.name, self.dropped);
        }
        writer.join().unwrap_or_else(|_| Err(io::Error::other(format!("{}: the writer panicked", self.name))))
    }
}

impl Drop for BackgroundSink {
    fn drop(&mut self) {
        if let Err(e) = self.finish() {
            tracing::warn!("{}: {e}", self.name);
        }
    }
}
