//! CSV logs written by a background thread, so that file I/O never blocks the control loop.
//!
//! Like the seed's FileLogger (spec §7.1), but with a time column in every file, full-precision
//! values, and a bounded queue whose overflow is counted rather than silent. Every field goes
//! through the `csv` crate, so a datagram whose bytes hold `"`, `,` or a newline cannot break a
//! line; the raw bytes are kept in a hex column as well. The headers are written when the
//! files are created, and the files are flushed at least once a second (a crash loses at most
//! the last second).

use std::fs::File;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use armgate_core::kinematics::Joints;
use armgate_core::math::{Frame, Quaternion};
use armgate_protocol::client::{MESSAGE_LEN, Message};

/// Records waiting to be written; more are dropped and counted.
const QUEUE: usize = 4096;

/// The longest time a written record stays in the writer's buffers.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);

/// One line of one log.
#[derive(Debug)]
pub enum Record {
    /// A datagram received from the client (as raw bytes).
    Command { t: f64, datagram: Vec<u8> },
    /// A reply sent.
    Reply { t: f64, datagram: [u8; MESSAGE_LEN] },
    /// An unsolicited warning sent.
    Warning { t: f64, text: String },
    /// One control tick (boxed: it is much larger than the other records).
    Tick(Box<Tick>),
}

/// The state of one control tick.
#[derive(Debug)]
pub struct Tick {
    /// Time (s).
    pub t: f64,
    /// Control mode.
    pub mode: &'static str,
    /// Measured tool pose.
    pub pose: Frame,
    /// Measured joints.
    pub joints: Joints,
    /// Joint command sent (none while off).
    pub command: Option<Joints>,
    /// Cartesian set-point (Cartesian mode).
    pub setpoint: Option<Frame>,
}

/// The sending side; cheap to use from the control loop.
pub struct Logger {
    sender: Option<SyncSender<Record>>,
    dropped: Arc<AtomicU64>,
    writer: Option<JoinHandle<csv::Result<()>>>,
}

impl Logger {
    /// A logger that writes nothing.
    pub fn disabled() -> Self {
        Self {
            sender: None,
            dropped: Arc::new(AtomicU64::new(0)),
            writer: None,
        }
    }

    /// Creates `commands.csv`, `replies.csv`, `warnings.csv` and `state.csv` in `dir` for an
    /// arm of `n` joints, writes their headers and starts the writer thread.
    pub fn start(dir: &Path, n: usize) -> csv::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut files = Files {
            commands: create(dir, "commands.csv", &message_header("cmd", true))?,
            replies: create(dir, "replies.csv", &message_header("reply", false))?,
            warnings: create(dir, "warnings.csv", &["t".into(), "text".into()])?,
            state: create(dir, "state.csv", &state_header(n))?,
        };
        files.flush()?;
        let (sender, receiver) = sync_channel(QUEUE);
        let writer = std::thread::Builder::new()
            .name("armgate-log".into())
            .spawn(move || files.write_all(&receiver))?;
        Ok(Self {
            sender: Some(sender),
            dropped: Arc::new(AtomicU64::new(0)),
            writer: Some(writer),
        })
    }

    /// Queues a record without blocking; a full queue drops it and counts it.
    pub fn log(&self, record: Record) {
        if let Some(sender) = &self.sender
            && let Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) =
                sender.try_send(record)
        {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// True if records are being written.
    pub fn enabled(&self) -> bool {
        self.sender.is_some()
    }

    /// Records dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Writes what is queued, flushes and closes the files.
    pub fn finish(mut self) -> csv::Result<()> {
        self.sender = None;
        match self.writer.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(std::io::Error::other("log writer thread panicked").into()),
            None => Ok(()),
        }
    }
}

type Writer = csv::Writer<File>;

struct Files {
    commands: Writer,
    replies: Writer,
    warnings: Writer,
    state: Writer,
}

impl Files {
    /// Writes records until the logger is finished, flushing at least every
    /// [`FLUSH_INTERVAL`] while there is something to flush.
    fn write_all(&mut self, receiver: &Receiver<Record>) -> csv::Result<()> {
        let mut next_flush: Option<Instant> = None;
        loop {
            let wait = next_flush.map_or(FLUSH_INTERVAL, |t| {
                t.saturating_duration_since(Instant::now())
            });
            match receiver.recv_timeout(wait) {
                Ok(record) => {
                    self.write(record)?;
                    next_flush.get_or_insert_with(|| Instant::now() + FLUSH_INTERVAL);
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return self.flush(),
            }
            if next_flush.is_some_and(|t| Instant::now() >= t) {
                self.flush()?;
                next_flush = None;
            }
        }
    }

    fn flush(&mut self) -> csv::Result<()> {
        for f in [
            &mut self.commands,
            &mut self.replies,
            &mut self.warnings,
            &mut self.state,
        ] {
            f.flush()?;
        }
        Ok(())
    }

    fn write(&mut self, record: Record) -> csv::Result<()> {
        match record {
            Record::Command { t, datagram } => {
                let mut row = vec![time(t)];
                row.extend(message_fields(&datagram));
                row.push(datagram.len().to_string());
                row.push(hex(&datagram));
                self.commands.write_record(&row)
            }
            Record::Reply { t, datagram } => {
                let mut row = vec![time(t)];
                row.extend(message_fields(&datagram));
                self.replies.write_record(&row)
            }
            Record::Warning { t, text } => self.warnings.write_record([time(t), text]),
            Record::Tick(tick) => self.state.write_record(state_fields(&tick)),
        }
    }
}

fn create(dir: &Path, name: &str, header: &[String]) -> csv::Result<Writer> {
    let mut writer = csv::Writer::from_path(dir.join(name))?;
    writer.write_record(header)?;
    Ok(writer)
}

fn time(t: f64) -> String {
    format!("{t:.6}")
}

/// `t,<chars>,f0..f6,index` and, for received datagrams, `len,hex`.
fn message_header(chars: &str, raw: bool) -> Vec<String> {
    let mut h = vec!["t".to_owned(), chars.to_owned()];
    h.extend((0..7).map(|k| format!("f{k}")));
    h.push("index".into());
    if raw {
        h.extend(["len".into(), "hex".into()]);
    }
    h
}

fn state_header(n: usize) -> Vec<String> {
    let mut h: Vec<String> = ["t", "mode", "x", "y", "z", "qx", "qy", "qz", "qw"]
        .map(String::from)
        .into();
    for prefix in ["q", "cmd"] {
        h.extend((1..=n).map(|k| format!("{prefix}{k}")));
    }
    h.extend(["sp_x", "sp_y", "sp_z", "sp_qx", "sp_qy", "sp_qz", "sp_qw"].map(String::from));
    h
}

fn state_fields(tick: &Tick) -> Vec<String> {
    let mut row = vec![time(tick.t), tick.mode.to_owned()];
    row.extend(pose_fields(Some(&tick.pose)));
    row.extend(tick.joints.iter().map(|q| format!("{q:.9}")));
    row.extend((0..tick.joints.len()).map(|k| {
        tick.command
            .as_ref()
            .and_then(|c| c.get(k))
            .map_or_else(String::new, |c| format!("{c:.9}"))
    }));
    row.extend(pose_fields(tick.setpoint.as_ref()));
    row
}

/// Position and quaternion, or seven empty fields.
fn pose_fields(pose: Option<&Frame>) -> Vec<String> {
    match pose {
        Some(p) => {
            let [x, y, z]: [f64; 3] = p.translation.vector.into();
            let [a, b, c, d] = Quaternion::from_rotation(&p.rotation).to_array();
            [x, y, z, a, b, c, d].map(|v| format!("{v:.9}")).into()
        }
        None => vec![String::new(); 7],
    }
}

/// `chars,f0..f6,index` of a datagram, zero-padded to 31 bytes (an undersized one is logged as
/// well); an ER/WN text is the whole `chars` field and the others are empty. Bytes that are not
/// printable ASCII show as `?` (the hex column has them all).
fn message_fields(datagram: &[u8]) -> Vec<String> {
    let mut padded = [0u8; MESSAGE_LEN];
    for (p, b) in padded.iter_mut().zip(datagram) {
        *p = *b;
    }
    let Ok(message) = Message::new_checked(&padded[..]) else {
        return vec![String::new(); 9]; // not reached: the buffer is a whole message
    };
    let chars = message.command();
    let mut fields = Vec::with_capacity(9);
    if matches!(&chars, b"ER" | b"WN") {
        fields.push(
            padded
                .iter()
                .take_while(|b| **b != 0)
                .map(|b| printable(*b))
                .collect(),
        );
        fields.resize(9, String::new());
        return fields;
    }
    fields.push(chars.iter().map(|b| printable(*b)).collect());
    fields.extend(message.values().iter().map(ToString::to_string));
    fields.push(message.index().to_string());
    fields
}

fn printable(b: u8) -> char {
    if b.is_ascii_graphic() || b == b' ' {
        char::from(b)
    } else {
        '?'
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("armgate-log-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn rows(path: &Path) -> Vec<csv::StringRecord> {
        csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_path(path)
            .unwrap()
            .records()
            .map(Result::unwrap)
            .collect()
    }

    #[test]
    fn quotes_commas_and_newlines_stay_inside_their_fields() {
        let dir = temp_dir("escape");
        let logger = Logger::start(&dir, 6).unwrap();
        let mut nasty = b"\",".to_vec();
        nasty.extend_from_slice(&[b'\n'; 10]);
        nasty.extend_from_slice(b"\r\n\",,\"");
        logger.log(Record::Command {
            t: 1.0,
            datagram: nasty.clone(),
        });
        let mut text = [0u8; MESSAGE_LEN];
        text[..22].copy_from_slice(b"ER00 Cmd \",not, \"\nhere");
        logger.log(Record::Reply {
            t: 1.0,
            datagram: text,
        });
        logger.log(Record::Command {
            t: 2.0,
            datagram: b"PS".to_vec(),
        });
        logger.finish().unwrap();
        let commands = rows(&dir.join("commands.csv"));
        assert_eq!(commands.len(), 3, "{commands:?}");
        assert_eq!(&commands[0][1], "cmd");
        assert_eq!(commands[1].len(), 12);
        assert_eq!(&commands[1][1], "\",");
        assert_eq!(&commands[1][11], hex(&nasty));
        assert_eq!(&commands[2][1], "PS");
        assert_eq!(&commands[2][10], "2");
        let replies = rows(&dir.join("replies.csv"));
        assert_eq!(replies.len(), 2);
        assert_eq!(&replies[1][1], "ER00 Cmd \",not, \"?here");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn headers_are_there_at_once_and_records_within_a_second() {
        let dir = temp_dir("flush");
        let logger = Logger::start(&dir, 2).unwrap();
        let header = std::fs::read_to_string(dir.join("state.csv")).unwrap();
        assert_eq!(
            header,
            "t,mode,x,y,z,qx,qy,qz,qw,q1,q2,cmd1,cmd2,sp_x,sp_y,sp_z,sp_qx,sp_qy,sp_qz,sp_qw\n"
        );
        logger.log(Record::Warning {
            t: 0.5,
            text: "WN12 Joint limit.".into(),
        });
        // Not finished: only the periodic flush can have written it.
        let deadline = Instant::now() + FLUSH_INTERVAL * 3;
        let path = dir.join("warnings.csv");
        while rows(&path).len() < 2 {
            assert!(Instant::now() < deadline, "not flushed");
            std::thread::sleep(Duration::from_millis(20));
        }
        assert_eq!(&rows(&path)[1][1], "WN12 Joint limit.");
        logger.finish().unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
