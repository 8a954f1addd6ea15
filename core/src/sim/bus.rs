//! A simulated CAN bus with simulated drives on it.
//!
//! Frames from every node compete by arbitration: when the bus falls idle, the ready frame
//! with the lowest identifier goes next (equal identifiers in the order queued). The
//! controller sends its own frames in the order it queued them: only the oldest competes, as
//! with the firmware's FDCAN transmit FIFO (`TxBufferMode::Fifo`) and a SocketCAN socket. A frame
//! occupies the bus for its exact length — stuff bits of its actual content and the
//! interframe space included — at the configured bit rate, and is delivered to every other
//! node when it ends. The bus owns the drives and advances them in time with itself; its
//! controller side is a [`CanBus`] for the drive manager.
//!
//! Knobs for the streaming tests: random frame loss with a fixed-seed generator (a lost frame
//! takes its time on the wire and reaches no one, as a frame every receiver dropped), and the
//! drives' clock errors ([`VirtualBus::spread_clock_errors`]). A late SYNC is the caller's to
//! send late.

use armgate_protocol::can::{CanFrame, bits_on_wire, exact_bits_on_wire};
use heapless::{Deque, Vec};

use super::whistle::{SimWhistle, WhistleConfig};
use crate::MAX_JOINTS;
use crate::config::RobotConfig;
use crate::drives::{BusState, CanBus, TxError};
use crate::rng::SplitMix64;

/// Frames the controller may have queued (a CAN controller's transmit FIFO).
const CONTROLLER_QUEUE: usize = 32;
/// Frames waiting on the bus from all nodes.
const PENDING: usize = CONTROLLER_QUEUE + MAX_JOINTS * 16;
/// The controller's receive FIFO.
const INBOX: usize = 64;
/// Events handled per `advance` call at most.
const MAX_EVENTS: u32 = 10_000_000;

/// Who sent a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sender {
    Controller,
    /// The drive at this position in the bus's list.
    Drive(usize),
}

#[derive(Clone, Copy, Debug)]
struct Pending {
    frame: CanFrame,
    from: Sender,
    /// When it may first be sent (ns).
    ready: u64,
    /// Queue order, for equal identifiers.
    order: u64,
}

/// Bus traffic since the last reset.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BusStats {
    /// Frames sent.
    pub frames: u64,
    /// Their exact length on the bus (bits).
    pub bits: u64,
    /// Their length with worst-case stuffing (bits).
    pub worst_case_bits: u64,
    /// The time covered (ns).
    pub elapsed_ns: u64,
    /// Frames lost because the controller's receive FIFO was full.
    pub inbox_overruns: u64,
    /// Frames lost on the wire ([`VirtualBus::set_frame_loss`]).
    pub frames_lost: u64,
    /// The spread of the drives' PT start instants (ns; the first sample of each drive's last
    /// PT motion), once every drive has started.
    pub start_skew_ns: Option<u64>,
    /// A hash (FNV-1a) of every frame on the wire, in order: identifier and data. Two runs
    /// that put the same frames on the bus have the same digest (the differential test).
    pub digest: u64,
}

impl BusStats {
    /// The fraction of the time the bus was busy, at `bitrate`.
    pub fn load(&self, bitrate: u32) -> f64 {
        fraction(self.bits, self.elapsed_ns, bitrate)
    }

    /// The load the same frames would make with worst-case stuffing.
    pub fn worst_case_load(&self, bitrate: u32) -> f64 {
        fraction(self.worst_case_bits, self.elapsed_ns, bitrate)
    }
}

fn fraction(bits: u64, elapsed_ns: u64, bitrate: u32) -> f64 {
    if elapsed_ns == 0 || bitrate == 0 {
        return 0.0;
    }
    bits as f64 / (elapsed_ns as f64 * 1e-9 * f64::from(bitrate))
}

/// `hash` extended by `frame`'s identifier and data (FNV-1a).
fn digest(hash: u64, frame: &CanFrame) -> u64 {
    frame
        .id()
        .to_le_bytes()
        .iter()
        .chain(frame.data())
        .fold(hash, |h, b| {
            (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
        })
}

/// `advance` gave up: more events than any sensible interval holds (a drive producing frames
/// without end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stalled;

/// A CAN bus with simulated drives; the controller's side implements [`CanBus`].
#[derive(Clone, Debug)]
pub struct VirtualBus {
    /// Nanoseconds per bit.
    bit_ns: u64,
    now: u64,
    drives: Vec<SimWhistle, MAX_JOINTS>,
    pending: Vec<Pending, PENDING>,
    order: u64,
    /// The frame on the bus and when it ends.
    wire: Option<(Pending, u64)>,
    inbox: Deque<CanFrame, INBOX>,
    bus_off: bool,
    stats: BusStats,
    /// When the statistics were last reset (ns).
    stats_since: u64,
    /// The probability that a frame is lost, and the generator that decides.
    loss: Option<(f64, SplitMix64)>,
}

impl VirtualBus {
    /// A bus at `bitrate` with `drives` on it, at time 0.
    pub fn new(bitrate: u32, drives: impl IntoIterator<Item = SimWhistle>) -> Self {
        Self {
            bit_ns: 1_000_000_000 / u64::from(bitrate.max(1)),
            now: 0,
            drives: drives.into_iter().take(MAX_JOINTS).collect(),
            pending: Vec::new(),
            order: 0,
            wire: None,
            inbox: Deque::new(),
            bus_off: false,
            stats: BusStats::default(),
            stats_since: 0,
            loss: None,
        }
    }

    /// The bus of `config`: its bit rate, and a default simulated drive for every joint that
    /// has one, at its home position.
    pub fn for_robot(config: &RobotConfig) -> Self {
        Self::for_robot_at(config, &config.home())
    }

    /// The same, with every drive's encoder at joint position `q` (rad or m; a drive whose
    /// position does not fit the encoder's counts starts at home).
    pub fn for_robot_at(config: &RobotConfig, q: &[f64]) -> Self {
        let drives = config.joints.iter().zip(q).filter_map(|(joint, q)| {
            let mut whistle = WhistleConfig::for_joint(joint)?;
            whistle.counts = whistle.units.counts(*q).unwrap_or(0);
            Some(SimWhistle::new(whistle))
        });
        Self::new(config.drives.can_bitrate, drives)
    }

    /// The bus time (s).
    pub fn now(&self) -> f64 {
        self.now as f64 * 1e-9
    }

    /// The drives, in the order given.
    pub fn drives(&self) -> impl Iterator<Item = &SimWhistle> {
        self.drives.iter()
    }

    /// The drive with node id `node`.
    pub fn drive(&self, node: u8) -> Option<&SimWhistle> {
        self.drives.iter().find(|d| d.node().get() == node)
    }

    /// The drive with node id `node`, to inject faults.
    pub fn drive_mut(&mut self, node: u8) -> Option<&mut SimWhistle> {
        self.drives.iter_mut().find(|d| d.node().get() == node)
    }

    /// Puts the controller bus-off (`true`), dropping its queued frames, or back on.
    pub fn set_bus_off(&mut self, off: bool) {
        self.bus_off = off;
        if off {
            self.pending.retain(|p| p.from != Sender::Controller);
        }
    }

    /// Makes every frame lost with `probability` (0 for none), drawn from a generator seeded
    /// with `seed`: the same seed loses the same frames.
    pub fn set_frame_loss(&mut self, probability: f64, seed: u64) {
        self.loss = (probability > 0.0).then(|| (probability, SplitMix64::new(seed)));
    }

    /// Gives every drive a clock error drawn uniformly in ±`max_ppm` from a generator seeded
    /// with `seed`, from now on.
    pub fn spread_clock_errors(&mut self, max_ppm: f64, seed: u64) {
        let mut rng = SplitMix64::new(seed);
        for drive in &mut self.drives {
            drive.set_clock_error_ppm(rng.uniform(-max_ppm, max_ppm));
        }
    }

    /// The spread of the drives' PT start instants (ns), once every drive has started one.
    pub fn start_skew_ns(&self) -> Option<u64> {
        let mut starts = self.drives.iter().map(|d| d.stats().started_at);
        let first = starts.next()??;
        let (min, max) = starts.try_fold((first, first), |(lo, hi), t| {
            t.map(|t| (lo.min(t), hi.max(t)))
        })?;
        Some(max - min)
    }

    /// Traffic since the last reset.
    pub fn stats(&self) -> BusStats {
        BusStats {
            elapsed_ns: self.now - self.stats_since,
            start_skew_ns: self.start_skew_ns(),
            ..self.stats
        }
    }

    /// Starts the bus and drive statistics afresh.
    pub fn reset_stats(&mut self) {
        self.stats = BusStats::default();
        self.stats_since = self.now;
        self.drives.iter_mut().for_each(SimWhistle::reset_stats);
    }

    /// Runs the bus and the drives up to time `to` (s).
    pub fn advance(&mut self, to: f64) -> Result<(), Stalled> {
        let to = (libm::round(to * 1e9).max(0.0) as u64).max(self.now);
        for _ in 0..MAX_EVENTS {
            self.collect();
            if self.wire.is_none() {
                self.arbitrate();
            }
            let bus_event = match self.wire {
                Some((_, end)) => Some(end),
                None => self.pending.iter().map(|p| p.ready).min(),
            };
            let drive_event = self.drives.iter().map(SimWhistle::next_event).min();
            let Some(next) = bus_event
                .into_iter()
                .chain(drive_event)
                .min()
                .filter(|&t| t <= to)
            else {
                self.run_drives_to(to);
                self.now = to;
                self.collect();
                return Ok(());
            };
            self.run_drives_to(next);
            self.now = next;
            if let Some((frame, end)) = self.wire
                && end == next
            {
                self.wire = None;
                if self.lose() {
                    self.stats.frames_lost += 1;
                } else {
                    self.deliver(&frame);
                }
            }
        }
        Err(Stalled)
    }

    fn run_drives_to(&mut self, t: u64) {
        self.drives.iter_mut().for_each(|d| d.advance_to(t));
    }

    /// Moves the drives' outgoing frames onto the bus queue.
    fn collect(&mut self) {
        for (index, drive) in self.drives.iter_mut().enumerate() {
            while let Some((frame, ready)) = drive.pop_transmit() {
                self.order += 1;
                let pending = Pending {
                    frame,
                    from: Sender::Drive(index),
                    ready,
                    order: self.order,
                };
                // The drive queue is bounded, and so is this one; a full bus queue drops.
                let _ = self.pending.push(pending);
            }
        }
    }

    /// Starts the ready frame that wins arbitration, if any.
    fn arbitrate(&mut self) {
        let now = self.now;
        let controller_head = self
            .pending
            .iter()
            .filter(|p| p.from == Sender::Controller)
            .map(|p| p.order)
            .min();
        let winner = self
            .pending
            .iter()
            .enumerate()
            .filter(|(_, p)| p.ready <= now)
            .filter(|(_, p)| p.from != Sender::Controller || Some(p.order) == controller_head)
            .min_by_key(|(_, p)| (p.frame.id(), p.order))
            .map(|(i, _)| i);
        if let Some(index) = winner {
            let pending = self.pending.swap_remove(index);
            let bits = exact_bits_on_wire(&pending.frame);
            self.stats.frames += 1;
            self.stats.bits += u64::from(bits);
            self.stats.digest = digest(self.stats.digest, &pending.frame);
            self.stats.worst_case_bits += u64::from(bits_on_wire(&pending.frame));
            self.wire = Some((pending, now + u64::from(bits) * self.bit_ns));
        }
    }

    /// True if the frame just ended is lost (a draw only when loss is on).
    fn lose(&mut self) -> bool {
        self.loss
            .as_mut()
            .is_some_and(|(probability, rng)| rng.next_f64() < *probability)
    }

    /// A frame has ended: every other node receives it.
    fn deliver(&mut self, sent: &Pending) {
        if sent.from != Sender::Controller
            && !self.bus_off
            && self.inbox.push_back(sent.frame).is_err()
        {
            self.stats.inbox_overruns += 1;
        }
        for (index, drive) in self.drives.iter_mut().enumerate() {
            if sent.from != Sender::Drive(index) {
                drive.receive(&sent.frame);
            }
        }
    }
}

impl CanBus for VirtualBus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        if self.bus_off {
            return Err(TxError::BusOff);
        }
        let queued = self
            .pending
            .iter()
            .filter(|p| p.from == Sender::Controller)
            .count();
        if queued >= CONTROLLER_QUEUE {
            return Err(TxError::QueueFull);
        }
        self.order += 1;
        let pending = Pending {
            frame: *frame,
            from: Sender::Controller,
            ready: self.now,
            order: self.order,
        };
        self.pending.push(pending).map_err(|_| TxError::QueueFull)
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.inbox.pop_front()
    }

    /// Runs the simulated drives and the bus up to `now`.
    fn advance_to(&mut self, now: f64) -> bool {
        self.advance(now).is_ok()
    }

    fn state(&self) -> BusState {
        BusState::from_bus_off(self.bus_off)
    }
}
