//! `--mcap FILE` and `--foxglove [ADDR]`: the run recorded for Foxglove by armgate-viz's
//! recorder, into an MCAP file and/or served live (docs/visualisation.md).
//!
//! Process-wide like the pcap capture, so that the socket and bus code make one call each; the
//! calls do nothing until [`Recording::start`]. Everything is stamped with the simulation's
//! time: the scheduled time of the tick under way ([`set_time`]), not the wall clock. The
//! recorder's thread does the FK, JSON and file work; here an event is only queued (or dropped
//! and counted when the queue is full).

use std::io;
use std::net::SocketAddr;
use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::math::Frame;
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::MESSAGE_LEN;
use armgate_viz::live::LiveServer;
use armgate_viz::mcap_file::McapFile;
use armgate_viz::recorder::{Recorder, Sink, Tap};
use armgate_viz::translate::{Event, MAX_DATAGRAM};

static TAP: OnceLock<Tap> = OnceLock::new();
/// The tick under way, µs of simulation time.
static NOW_US: AtomicU64 = AtomicU64::new(0);

/// The running recording.
pub struct Recording {
    recorder: Recorder,
}

impl Recording {
    /// Creates the MCAP file and/or listens for live viewers, and starts the recorder; returns
    /// the address the live view listens on. Only one per process.
    pub fn start(
        robot: &ValidRobot,
        mcap: Option<&Path>,
        live: Option<SocketAddr>,
    ) -> io::Result<(Self, Option<SocketAddr>)> {
        let mut sinks: Vec<Box<dyn Sink>> = Vec::new();
        if let Some(path) = mcap {
            let file = McapFile::create(path, robot, "armgate-sim")
                .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
            sinks.push(Box::new(file));
        }
        let mut listening = None;
        if let Some(addr) = live {
            let server = LiveServer::bind(addr, "armgate-sim")
                .map_err(|e| io::Error::new(e.kind(), format!("--foxglove {addr}: {e}")))?;
            listening = Some(server.local_addr());
            sinks.push(Box::new(server));
        }
        let recorder = Recorder::start(robot, 0.0, sinks)?;
        TAP.set(recorder.tap())
            .map_err(|_| io::Error::other("a recording is already running"))?;
        Ok((Self { recorder }, listening))
    }

    /// Writes what is queued, ends the file; returns messages written and events dropped.
    pub fn finish(self) -> io::Result<(u64, u64)> {
        self.recorder.finish()
    }
}

/// True while recording.
pub fn enabled() -> bool {
    TAP.get().is_some()
}

/// The time of the tick about to run (µs on the cycle's schedule).
pub fn set_time(us: u64) {
    NOW_US.store(us, Ordering::Relaxed);
}

fn now() -> f64 {
    NOW_US.load(Ordering::Relaxed) as f64 * 1e-6
}

fn record(event: impl FnOnce(f64) -> Event) {
    if let Some(tap) = TAP.get() {
        tap.record(event(now()));
    }
}

/// A datagram a client sent to the controller.
pub fn request(from: SocketAddr, to: SocketAddr, payload: &[u8]) {
    record(|t| {
        let mut bytes = [0; MAX_DATAGRAM];
        bytes.iter_mut().zip(payload).for_each(|(b, p)| *b = *p);
        Event::Request {
            t,
            from,
            to,
            len: payload.len().min(MAX_DATAGRAM),
            bytes,
        }
    });
}

/// A reply or notice the controller sent.
pub fn answer(from: SocketAddr, to: SocketAddr, payload: &[u8]) {
    record(|t| {
        let mut bytes = [0; MESSAGE_LEN];
        bytes.iter_mut().zip(payload).for_each(|(b, p)| *b = *p);
        Event::Answer { t, from, to, bytes }
    });
}

/// A CAN frame sent or received.
pub fn can(frame: &CanFrame) {
    record(|t| Event::Can { t, frame: *frame });
}

/// The joints of a tick at time `t` (s), with the measured tool pose.
pub fn joints(
    t: f64,
    measured: Joints,
    command: Option<Joints>,
    setpoint: Option<Frame>,
    pose: Frame,
) {
    if let Some(tap) = TAP.get() {
        tap.record(Event::Joints {
            t,
            measured,
            command,
            setpoint,
            pose: Some(pose),
        });
    }
}

/// Events dropped so far (queue full).
pub fn dropped() -> u64 {
    TAP.get().map_or(0, Tap::dropped)
}
