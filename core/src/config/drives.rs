//! The robot file's `[drives]` section: its keys, their bounds and defaults. The drive
//! manager (`crate::drives`) runs by these numbers; they live here, below it, because the robot
//! file is checked against them.

use serde::{Deserialize, Serialize};

use super::bus_load::DEFAULT_CEILING;
use super::error::ConfigReason;

/// The lead (points beyond the read pointer) the stream keeps at every SYNC by default, for a
/// drive whose segment boundary follows the SYNC; one less for a drive whose boundary precedes
/// it.
pub const PDO_TARGET_LEAD: u16 = 2;

/// Cycles between two Time Stamps by default (`drives.time_stamp_every`): one after every
/// second SYNC locks the drives' clocks within about 400 cycles (200 pairs, Elmo's figure)
/// and keeps six drives at 231.5 Hz under 70 % of a 500 kbit/s bus (one after every SYNC
/// would take them to 71.6 %).
pub const TIME_STAMP_EVERY: u16 = 2;

/// The largest lead a robot file may ask for (`drives.pdo_lead`): the default 16-entry ring
/// then still holds a correction and a margin that makes a wrong pointer show as an overrun.
pub const MAX_PDO_LEAD: u16 = 8;

/// Settings shared by all drives on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DrivesConfig {
    /// CAN bit rate in bit/s: 125 000, 250 000, 500 000 or 1 000 000.
    pub can_bitrate: u32,
    /// Elmo unit mode: 5 = position (the only mode the seed used), 2 = speed, 1 = torque.
    pub unit_mode: u8,
    /// The largest fraction of the bus the drives' worst-case streaming traffic may take
    /// (0 < x ≤ 1; default 0.7, [`DEFAULT_CEILING`]).
    #[serde(default = "default_ceiling")]
    pub max_bus_load: f64,
    /// How set-points reach the drives (default [`Streaming::Interpreter`]).
    #[serde(default)]
    pub streaming: Streaming,
    /// With `streaming = "pdo"`: a drive that refuses the PDO mapping makes the manager fall
    /// back to the interpreter schedule (reported as a warning) instead of a start-up fault.
    /// The period must then fit the interpreter schedule's load too.
    #[serde(default)]
    pub pdo_fallback: bool,
    /// With `streaming = "pdo"`: the PT points kept beyond each drive's read pointer at every
    /// SYNC, 1..=[`MAX_PDO_LEAD`]; none: [`PDO_TARGET_LEAD`] (2). More tolerates lost
    /// frames, less is less latency (docs/drives.md, "The lead").
    #[serde(default)]
    pub pdo_lead: Option<u16>,
    /// With `streaming = "pdo"`: the most points the stream may raise the lead above
    /// `pdo_lead` while the drives' reports show points lost on the bus, lowering it again
    /// after a quiet interval; 0 keeps the lead fixed. The sum must stay at most
    /// [`MAX_PDO_LEAD`]; none: `DriveSettings::pdo_lead_raise` (3), up to [`MAX_PDO_LEAD`]
    /// (docs/drives.md, "The lead").
    #[serde(default)]
    pub pdo_lead_raise: Option<u16>,
    /// With `streaming = "pdo"`: a Time Stamp after every n-th SYNC, which locks the drives'
    /// motion clocks to the controller's (Elmo MAN-CAN301IG ch. 8), so that their PT segments
    /// stop drifting against the control cycle; 0 sends none. None:
    /// [`TIME_STAMP_EVERY`] (2)
    /// (docs/drives.md, "SYNC locking").
    #[serde(default)]
    pub time_stamp_every: Option<u16>,
}

/// The streaming schedule: which frames carry the set-points and the feedback (docs/drives.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Streaming {
    /// Binary-interpreter frames: per drive and cycle a `QP` write and one query, both
    /// answered (the seed's way, 500 bits per drive worst case).
    #[default]
    Interpreter,
    /// Process data: one SYNC per cycle, per drive one receive PDO carrying the next PT point
    /// and one synchronous transmit PDO with the position and the PT pointers (230 bits per
    /// drive worst case).
    Pdo,
}

fn default_ceiling() -> f64 {
    DEFAULT_CEILING
}

impl DrivesConfig {
    pub(super) fn validate(&self) -> Result<(), (&'static str, ConfigReason)> {
        if !matches!(self.can_bitrate, 125_000 | 250_000 | 500_000 | 1_000_000) {
            return Err(("drives.can_bitrate", ConfigReason::UnsupportedBitRate));
        }
        if !matches!(self.unit_mode, 1 | 2 | 5) {
            return Err(("drives.unit_mode", ConfigReason::UnsupportedUnitMode));
        }
        if !(self.max_bus_load > 0.0 && self.max_bus_load <= 1.0) {
            return Err(("drives.max_bus_load", ConfigReason::NotAFraction));
        }
        if self
            .pdo_lead
            .is_some_and(|lead| !(1..=MAX_PDO_LEAD).contains(&lead))
        {
            return Err(("drives.pdo_lead", ConfigReason::PdoLead));
        }
        let lead = self.pdo_lead.unwrap_or(PDO_TARGET_LEAD);
        // Without the key the default raise stops at the highest lead.
        let raise = self.pdo_lead_raise.unwrap_or(0);
        if lead.saturating_add(raise) > MAX_PDO_LEAD {
            return Err(("drives.pdo_lead_raise", ConfigReason::PdoLeadRaise));
        }
        Ok(())
    }
}
