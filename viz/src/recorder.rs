//! The recorder: events go through a bounded queue to a thread that translates them and hands
//! the messages to its sinks (an MCAP file, the live view). The control loop never waits: an
//! event that finds the queue full is dropped and counted, as the CSV logs and the pcap
//! capture of `armgate-sim` do. The sinks are flushed at least once a second and at the end.

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use armgate_core::config::ValidRobot;

use crate::translate::{Event, Message, Translator};

/// Events waiting for the recorder thread at most (about 400 bytes each, so about 3 MiB; a
/// 200 Hz arm with six drives makes about 3,000 a second).
pub const QUEUE: usize = 8192;

/// The longest time a message stays in a sink's buffers.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);

/// Where messages go.
pub trait Sink: Send {
    /// Takes one message.
    fn write(&mut self, message: &Message) -> io::Result<()>;
    /// Makes what was written durable (or visible).
    fn flush(&mut self) -> io::Result<()>;
    /// Ends the output (an MCAP file writes its summary).
    fn finish(&mut self) -> io::Result<()>;
}

// By value (see `Event`): the bounded channel's slots are allocated once.
#[allow(clippy::large_enum_variant)]
enum Item {
    Event(Event),
    Finish,
}

/// The sending side: cheap and non-blocking; clone it to record from several places.
#[derive(Clone)]
pub struct Tap {
    sender: SyncSender<Item>,
    dropped: Arc<AtomicU64>,
}

impl Tap {
    /// Queues an event without blocking; a full queue drops it and counts it.
    pub fn record(&self, event: Event) {
        if let Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) =
            self.sender.try_send(Item::Event(event))
        {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Events dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
}

/// The running recorder; [`finish`](Self::finish) it to write the end of its outputs.
pub struct Recorder {
    tap: Tap,
    writer: Option<JoinHandle<io::Result<u64>>>,
}

impl Recorder {
    /// Starts the thread: the preamble (URDF, workspace) at time `t0` first, then every event.
    pub fn start(robot: &ValidRobot, t0: f64, sinks: Vec<Box<dyn Sink>>) -> io::Result<Self> {
        let (sender, receiver) = sync_channel(QUEUE);
        let translator = Translator::new(robot);
        let writer = std::thread::Builder::new()
            .name("armgate-record".into())
            .spawn(move || run(translator, t0, sinks, &receiver))?;
        Ok(Self {
            tap: Tap {
                sender,
                dropped: Arc::new(AtomicU64::new(0)),
            },
            writer: Some(writer),
        })
    }

    /// A handle to record with.
    pub fn tap(&self) -> Tap {
        self.tap.clone()
    }

    /// Writes what is queued, ends the outputs, and returns the messages written and the
    /// events dropped because the queue was full.
    pub fn finish(mut self) -> io::Result<(u64, u64)> {
        self.stop()
    }

    fn stop(&mut self) -> io::Result<(u64, u64)> {
        let Some(writer) = self.writer.take() else {
            return Ok((0, 0));
        };
        // A blocking send: the end must not be dropped.
        let _ = self.tap.sender.send(Item::Finish);
        let written = writer
            .join()
            .map_err(|_| io::Error::other("the recorder thread panicked"))??;
        Ok((written, self.tap.dropped()))
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        // Nobody is left to report an error to.
        let _ = self.stop();
    }
}

fn run(
    mut translator: Translator,
    t0: f64,
    mut sinks: Vec<Box<dyn Sink>>,
    receiver: &Receiver<Item>,
) -> io::Result<u64> {
    let mut written = 0;
    let mut write = |sinks: &mut Vec<Box<dyn Sink>>, messages: Vec<Message>| {
        for message in &messages {
            for sink in sinks.iter_mut() {
                sink.write(message)?;
            }
            written += 1;
        }
        io::Result::Ok(())
    };
    write(&mut sinks, translator.preamble(t0))?;
    let mut next_flush = Some(Instant::now());
    loop {
        let wait = next_flush.map_or(FLUSH_INTERVAL, |t| {
            t.saturating_duration_since(Instant::now())
        });
        match receiver.recv_timeout(wait) {
            Ok(Item::Event(event)) => {
                write(&mut sinks, translator.translate(&event))?;
                next_flush.get_or_insert_with(|| Instant::now() + FLUSH_INTERVAL);
            }
            Err(RecvTimeoutError::Timeout) => {}
            Ok(Item::Finish) | Err(RecvTimeoutError::Disconnected) => break,
        }
        if next_flush.is_some_and(|t| Instant::now() >= t) {
            for sink in &mut sinks {
                sink.flush()?;
            }
            next_flush = None;
        }
    }
    for sink in &mut sinks {
        sink.finish()?;
    }
    Ok(written)
}
