//! Settings of the drive manager that the robot description does not hold, and the cycle
//! counts derived from them.

use armgate_protocol::can::NodeId;

use super::streaming::{PDO_LEAD_RAISE, Schedule};
use crate::config::bus_load::{HEARTBEAT_PERIOD, LoadModel, whole_samples};
use crate::config::{MAX_PDO_LEAD, PDO_TARGET_LEAD, RobotConfig, TIME_STAMP_EVERY, ValidRobot};

/// The only unit mode the manager streams to: position (PT motion).
pub const POSITION_MODE: i32 = 5;

/// Settings of the drive manager; [`Default`] gives the documented values (docs/drives.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveSettings {
    /// The controller's own CANopen node id, 1..=127: its heartbeat goes out as `0x700 + id`.
    pub controller_node: u8,
    /// Seconds between the controller's heartbeats.
    pub heartbeat_period: f64,
    /// The drives' consumer heartbeat time (object 0x1016), in seconds: a drive that hears no
    /// heartbeat for this long stops by itself. Longer than `heartbeat_period`.
    pub heartbeat_timeout: f64,
    /// A drive that leaves a request unanswered this long (seconds) is faulted.
    pub reply_timeout: f64,
    /// Pause after the NMT start before talking to the drives (the seed waited 12 ms).
    pub nmt_settle: f64,
    /// Pause after changing a drive's unit mode (the seed waited 100 ms).
    pub unit_mode_settle: f64,
    /// Entries of the drives' PT ring, `QP[1..=ring_len]` (the seed used 6).
    pub ring_len: u16,
    /// Which query each drive sends in each streaming cycle.
    pub schedule: Schedule,
    /// PDO schedule: entries of the drives' PT ring (6..=64): room for the lead, a correction
    /// and a margin that makes a wrong pointer show as an overrun.
    pub pdo_ring_len: u16,
    /// PDO schedule: the PT points kept beyond each drive's read pointer at every SYNC
    /// (1..=pdo_ring_len − 3; docs/drives.md).
    pub pdo_lead: u16,
    /// PDO schedule: the most points the stream may raise the lead above `pdo_lead` while
    /// reports show points lost (0: a fixed lead), at most up to the highest lead
    /// (`MAX_PDO_LEAD`, and `pdo_ring_len` − 3); the robot file's `drives.pdo_lead_raise`
    /// overrides it.
    pub pdo_lead_raise: u16,
    /// PDO schedule: seconds without a lost point after which a raised lead comes down by one
    /// (positive).
    pub pdo_lead_quiet: f64,
    /// PDO schedule: a drive whose transmit PDO is missing for more than this many cycles in a
    /// row is faulted (at least 1).
    pub pdo_missing_cycles: u16,
    /// PDO schedule: the group id (object 0x2040) the drives also answer to, 1..=127, neither
    /// a drive's nor the controller's: one `BG` to it begins every drive at once.
    pub group_node: u8,
}

impl Default for DriveSettings {
    fn default() -> Self {
        Self {
            // The highest node id: the drives use 101 and up (spec §6.1).
            controller_node: 127,
            heartbeat_period: HEARTBEAT_PERIOD,
            heartbeat_timeout: 0.3,
            reply_timeout: 0.05,
            nmt_settle: 0.012,
            unit_mode_settle: 0.1,
            ring_len: 6,
            schedule: Schedule::default(),
            pdo_ring_len: 16,
            pdo_lead: PDO_TARGET_LEAD,
            pdo_lead_raise: PDO_LEAD_RAISE,
            pdo_lead_quiet: 2.0,
            pdo_missing_cycles: 4,
            group_node: 126,
        }
    }
}

impl DriveSettings {
    /// The worst-case streaming traffic of `config`'s drives with these settings.
    pub fn load_model(&self, config: &RobotConfig) -> LoadModel {
        LoadModel::new(
            config,
            self.heartbeat_period,
            self.schedule.temperature_every,
        )
    }
}

/// Why the drive manager cannot run a robot with these settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupError {
    /// Only position mode (unit mode 5) is streamed; the robot asks for another.
    UnsupportedUnitMode(u8),
    /// The control period is not a whole number of 360 µs drive samples (the PT segment time
    /// `MP[4]` × 360 µs must equal it), or is out of range.
    PeriodNotWholeSamples,
    /// The PT ring must have 6 to 64 entries: the drive holds three points and the flow
    /// control keeps up to five ahead.
    RingSize,
    /// The heartbeat times must be positive, the timeout longer than the period, and the
    /// timeout at most 65.535 s (a 16-bit number of milliseconds).
    Heartbeat,
    /// The controller's or the group's node id is not in 1..=127, or is also a drive's, or
    /// they are the same.
    ControllerNode,
    /// A timeout or settle time is negative or not finite, a schedule interval is zero, or the
    /// PDO lead or missing-feedback count is out of range.
    BadTiming,
    /// A joint's drive has a node id above 127 or no counts per revolution.
    BadDrive,
    /// With this heartbeat period the drives' worst-case traffic exceeds the robot's
    /// `drives.max_bus_load` (validation checked it with the default heartbeat).
    BusOverloaded,
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::UnsupportedUnitMode(mode) => {
                write!(f, "unit mode {mode}: only position mode (5) is supported")
            }
            Self::PeriodNotWholeSamples => {
                f.write_str("control period is not a whole number of 360 µs drive samples")
            }
            Self::RingSize => f.write_str("PT ring length must be 6..=64"),
            Self::Heartbeat => f.write_str("bad heartbeat period or timeout"),
            Self::ControllerNode => f.write_str("controller node id invalid or a drive's"),
            Self::BadTiming => f.write_str("bad timeout, settle time or schedule"),
            Self::BadDrive => f.write_str("bad drive node id or counts per revolution"),
            Self::BusOverloaded => f.write_str("worst-case bus load exceeds drives.max_bus_load"),
        }
    }
}

/// The settings turned into cycle counts for one control period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Timing {
    /// The control period (s).
    pub period: f64,
    /// Drive samples per PT point (`MP[4]`).
    pub samples_per_point: u16,
    /// Cycles a request may stay unanswered.
    pub reply_timeout: u32,
    /// Cycles to wait after the NMT start.
    pub nmt_settle: u32,
    /// Cycles to wait after a unit-mode change.
    pub unit_mode_settle: u32,
    /// Seconds between the controller's heartbeats.
    pub heartbeat_period: f64,
    /// The consumer heartbeat time for object 0x1016 (ms).
    pub heartbeat_timeout_ms: u16,
    /// The controller's node id.
    pub controller: NodeId,
    /// The drives' group id (PDO schedule).
    pub group: NodeId,
    /// Cycles without a lost point before a raised PDO lead comes down by one.
    pub pdo_lead_quiet: u32,
    /// The most the PDO lead may be raised.
    pub pdo_lead_raise: u16,
    /// PDO schedule: cycles between two Time Stamps (0: none).
    pub time_stamp_every: u16,
}

impl Timing {
    /// Checks `settings` against `config` and derives the counts.
    pub fn new(config: &ValidRobot, settings: &DriveSettings) -> Result<Self, SetupError> {
        if config.drives.unit_mode != POSITION_MODE as u8 {
            return Err(SetupError::UnsupportedUnitMode(config.drives.unit_mode));
        }
        let period = config.control_period;
        // Validation refuses any other period; kept as the manager's own precondition.
        let samples = whole_samples(period).ok_or(SetupError::PeriodNotWholeSamples)?;
        let load = settings
            .load_model(config)
            .load(period, config.drives.can_bitrate);
        let fits = load <= config.drives.max_bus_load; // false for NaN too
        if !fits {
            return Err(SetupError::BusOverloaded);
        }
        if !(6..=64).contains(&settings.ring_len) || !(6..=64).contains(&settings.pdo_ring_len) {
            return Err(SetupError::RingSize);
        }
        let (beat, timeout) = (settings.heartbeat_period, settings.heartbeat_timeout);
        let timeout_ms = libm::round(timeout * 1000.0);
        if !(beat > 0.0 && timeout > beat && (1.0..=65535.0).contains(&timeout_ms)) {
            return Err(SetupError::Heartbeat);
        }
        let free = |id: u8| {
            NodeId::new(id).filter(|id| config.joints.iter().all(|j| j.drive.node_id != id.get()))
        };
        let controller = free(settings.controller_node).ok_or(SetupError::ControllerNode)?;
        let group = free(settings.group_node)
            .filter(|&group| group != controller)
            .ok_or(SetupError::ControllerNode)?;
        let schedule = settings.schedule;
        if schedule.read_index_every == 0 || schedule.temperature_every == 0 {
            return Err(SetupError::BadTiming);
        }
        let lead = config.drives.pdo_lead.unwrap_or(settings.pdo_lead);
        let highest = settings.pdo_ring_len.saturating_sub(3).min(MAX_PDO_LEAD);
        let lead_fits = (1..=highest).contains(&lead);
        // A raise the robot file does not ask for stops at the highest lead.
        let pdo_lead_raise = match config.drives.pdo_lead_raise {
            Some(raise) if lead.saturating_add(raise) > highest => {
                return Err(SetupError::BadTiming);
            }
            Some(raise) => raise,
            None => settings.pdo_lead_raise.min(highest.saturating_sub(lead)),
        };
        let quiet_fits = settings.pdo_lead_quiet > 0.0;
        if !lead_fits || !quiet_fits || settings.pdo_missing_cycles == 0 {
            return Err(SetupError::BadTiming);
        }
        let cycles = |seconds: f64| {
            let n = libm::ceil(seconds / period - 1e-9);
            (seconds.is_finite() && seconds >= 0.0 && n <= f64::from(u32::MAX))
                .then_some(n.max(0.0) as u32)
                .ok_or(SetupError::BadTiming)
        };
        Ok(Self {
            period,
            samples_per_point: samples,
            // At least two cycles: a reply to a request sent in one cycle is read in the next.
            reply_timeout: cycles(settings.reply_timeout)?.max(2),
            nmt_settle: cycles(settings.nmt_settle)?,
            unit_mode_settle: cycles(settings.unit_mode_settle)?,
            heartbeat_period: beat,
            heartbeat_timeout_ms: timeout_ms as u16,
            controller,
            group,
            pdo_lead_quiet: cycles(settings.pdo_lead_quiet)?.max(1),
            pdo_lead_raise,
            time_stamp_every: config.drives.time_stamp_every.unwrap_or(TIME_STAMP_EVERY),
        })
    }
}
