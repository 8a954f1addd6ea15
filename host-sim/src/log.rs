//! CSV logs written by a background thread, so that file I/O never blocks the control loop.
//!
//! Like the seed's FileLogger (spec §7.1), but with a time column in every file, full-precision
//! values, and a bounded queue whose overflow is counted rather than silent.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;

use armgate_core::kinematics::Joints;
use armgate_core::math::{Frame, Quaternion};
use armgate_protocol::client::{MESSAGE_LEN, Message};

/// Records waiting to be written; more are dropped and counted.
const QUEUE: usize = 4096;

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
    writer: Option<JoinHandle<std::io::Result<()>>>,
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
    /// arm of `n` joints and starts the writer thread.
    pub fn start(dir: &Path, n: usize) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut files = Files {
            commands: csv(
                dir,
                "commands.csv",
                "t,cmd,f0,f1,f2,f3,f4,f5,f6,index,bytes",
            )?,
            replies: csv(dir, "replies.csv", "t,reply,f0,f1,f2,f3,f4,f5,f6,index")?,
            warnings: csv(dir, "warnings.csv", "t,text")?,
            state: csv(dir, "state.csv", &state_header(n))?,
        };
        let (sender, receiver) = sync_channel(QUEUE);
        let writer = std::thread::Builder::new()
            .name("armgate-log".into())
            .spawn(move || files.write_all(receiver))?;
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

    /// Flushes and closes the files.
    pub fn finish(mut self) -> std::io::Result<()> {
        self.sender = None;
        match self.writer.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(std::io::Error::other("log writer thread panicked")),
            None => Ok(()),
        }
    }
}

struct Files {
    commands: BufWriter<File>,
    replies: BufWriter<File>,
    warnings: BufWriter<File>,
    state: BufWriter<File>,
}

impl Files {
    fn write_all(&mut self, receiver: Receiver<Record>) -> std::io::Result<()> {
        for record in receiver {
            self.write(record)?;
        }
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

    fn write(&mut self, record: Record) -> std::io::Result<()> {
        match record {
            Record::Command { t, datagram } => {
                write!(self.commands, "{t:.6},{}", message_fields(&datagram))?;
                writeln!(self.commands, ",{}", datagram.len())
            }
            Record::Reply { t, datagram } => {
                writeln!(self.replies, "{t:.6},{}", message_fields(&datagram[..]))
            }
            Record::Warning { t, text } => writeln!(self.warnings, "{t:.6},{text}"),
            Record::Tick(tick) => {
                let Tick {
                    t,
                    mode,
                    pose,
                    joints,
                    command,
                    setpoint,
                } = *tick;
                let f = &mut self.state;
                write!(f, "{t:.6},{mode}")?;
                write_pose(f, Some(&pose))?;
                for q in joints.iter() {
                    write!(f, ",{q:.9}")?;
                }
                for k in 0..joints.len() {
                    match command.as_ref().and_then(|c| c.get(k)) {
                        Some(c) => write!(f, ",{c:.9}")?,
                        None => write!(f, ",")?,
                    }
                }
                write_pose(f, setpoint.as_ref())?;
                writeln!(f)
            }
        }
    }
}

fn csv(dir: &Path, name: &str, header: &str) -> std::io::Result<BufWriter<File>> {
    let mut f = BufWriter::new(File::create(dir.join(name))?);
    writeln!(f, "{header}")?;
    Ok(f)
}

fn state_header(n: usize) -> String {
    let mut h = String::from("t,mode,x,y,z,qx,qy,qz,qw");
    for prefix in ["q", "cmd"] {
        for k in 1..=n {
            h.push_str(&format!(",{prefix}{k}"));
        }
    }
    h.push_str(",sp_x,sp_y,sp_z,sp_qx,sp_qy,sp_qz,sp_qw");
    h
}

/// Position and quaternion, or empty fields.
fn write_pose(f: &mut impl Write, pose: Option<&Frame>) -> std::io::Result<()> {
    match pose {
        Some(p) => {
            let [x, y, z]: [f64; 3] = p.translation.vector.into();
            let [a, b, c, d] = Quaternion::from_rotation(&p.rotation).to_array();
            write!(f, ",{x:.9},{y:.9},{z:.9},{a:.9},{b:.9},{c:.9},{d:.9}")
        }
        None => write!(f, ",,,,,,,"),
    }
}

/// `cmd,f0..f6,index` of a datagram, zero-padded to 31 bytes (an undersized one is logged as
/// well); ER/WN texts go in the `cmd` column, quoted.
fn message_fields(datagram: &[u8]) -> String {
    let mut padded = [0u8; MESSAGE_LEN];
    for (p, b) in padded.iter_mut().zip(datagram) {
        *p = *b;
    }
    let Ok(message) = Message::new_checked(&padded[..]) else {
        return ",,,,,,,,".to_string(); // not reached: the buffer is a whole message
    };
    let [c0, c1] = message.command();
    if matches!(&[c0, c1], b"ER" | b"WN") {
        let text: String = padded
            .iter()
            .take_while(|b| **b != 0)
            .map(|b| char::from(*b))
            .collect();
        return format!("\"{text}\",,,,,,,,");
    }
    let mut s = format!("{}{}", printable(c0), printable(c1));
    for v in message.values() {
        s.push_str(&format!(",{v}"));
    }
    s.push_str(&format!(",{}", message.index()));
    s
}

fn printable(b: u8) -> char {
    if b.is_ascii_graphic() {
        char::from(b)
    } else {
        '?'
    }
}
