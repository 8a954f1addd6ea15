//! Why a robot description was refused, naming the field.

use core::fmt;

use armgate_protocol::client::Hit;

/// A refused robot description: which field, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConfigError {
    /// The joint the field belongs to (0-based), if it is a per-joint field.
    pub joint: Option<u8>,
    /// The field's path in the robot file, e.g. `max_velocity` or `workspace.bounds`.
    pub field: &'static str,
    /// What is wrong with it.
    pub reason: ConfigReason,
}

/// What is wrong with a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigReason {
    /// The text is empty.
    Empty,
    /// There are no joints.
    NoJoints,
    /// A number is NaN or infinite.
    NotFinite,
    /// A number must be greater than zero.
    NotPositive,
    /// A lower limit exceeds its upper limit.
    MinAboveMax,
    /// A CANopen node id must be 0 (no drive) or 1..=127.
    NodeIdOutOfRange,
    /// Two joints use the same CANopen node id.
    DuplicateNodeId,
    /// A joint with a drive needs nonzero encoder counts per revolution.
    ZeroCounts,
    /// The CAN bit rate is not one of 125, 250, 500 or 1000 kbit/s.
    UnsupportedBitRate,
    /// The unit mode is not 1 (torque), 2 (speed) or 5 (position).
    UnsupportedUnitMode,
    /// The control period is not a whole number of 360 µs drive samples from 3 to 2777
    /// (1.08 ms to 0.99972 s).
    ControlPeriod,
    /// A joint's home (its position at zero encoder counts, and the start pose) lies outside
    /// its limits.
    HomeOutsideLimits,
    /// The drives' worst-case streaming traffic would take this much of the bus (per cent,
    /// rounded up), more than `drives.max_bus_load`.
    BusOverloaded {
        /// The worst-case load, per cent.
        percent: u16,
    },
    /// A fraction must be greater than 0 and at most 1.
    NotAFraction,
    /// A number must be zero or more.
    Negative,
    /// `[motion] profile = "jerk-limited"` needs this jerk limit.
    MissingJerkLimit,
    /// The PDO schedule's lead must be 1 to 8 points (`config::MAX_PDO_LEAD`).
    PdoLead,
    /// The PDO lead raised by `drives.pdo_lead_raise` must stay at most 8 points.
    PdoLeadRaise,
    /// The joint's limits, in encoder counts, do not fit the drive's 32-bit positions.
    CountsOverflow,
    /// One tracking solve may take 1 to 100 iterations (`config::MAX_TRACKING_ITERATIONS`).
    TrackingIterations,
    /// A line may be slowed down 1 to 1000 times (`config::MAX_LINE_SLOWDOWN`).
    LineSlowdown,
    /// An exclusion box is flat: its minimum equals its maximum on some axis.
    NoVolume,
    /// A joint's limit exceeds what its drive is configured for: the limit and the drive's
    /// value (thousandths, rounded up) and the drive's field.
    ExceedsDrive {
        /// The joint's limit, thousandths.
        value_milli: u32,
        /// The drive's value, thousandths.
        drive_milli: u32,
        /// The drive's field, e.g. `drive.max_speed`.
        drive_field: &'static str,
    },
    /// A link number beyond the last link (the number of joints).
    NoSuchLink,
    /// At home a link of the body already hits something (`L3 hits B1`: link 3 within
    /// `collision.margin` of exclusion box 1; `L5 hits L2`; `L3 out`: the bounds).
    HomeInCollision(Hit),
}

impl ConfigError {
    pub(super) fn top(field: &'static str, reason: ConfigReason) -> Self {
        Self {
            joint: None,
            field,
            reason,
        }
    }

    pub(super) fn joint(index: usize, field: &'static str, reason: ConfigReason) -> Self {
        Self {
            joint: u8::try_from(index).ok(),
            field,
            reason,
        }
    }
}

impl fmt::Display for ConfigReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Empty => "must not be empty",
            Self::NoJoints => "a robot needs at least one joint",
            Self::NotFinite => "must be a finite number (not NaN or infinite)",
            Self::NotPositive => "must be greater than zero",
            Self::Negative => "must be zero or more",
            Self::MinAboveMax => "minimum is greater than maximum",
            Self::NodeIdOutOfRange => "node id must be 0 (no drive) or 1..=127",
            Self::DuplicateNodeId => "node id is used by an earlier joint",
            Self::ZeroCounts => "counts per revolution must be nonzero for a joint with a drive",
            Self::UnsupportedBitRate => "bit rate must be 125000, 250000, 500000 or 1000000",
            Self::UnsupportedUnitMode => "unit mode must be 1 (torque), 2 (speed) or 5 (position)",
            Self::ControlPeriod => {
                "must be a whole number of 360 µs drive samples from 3 to 2777 \
                 (1.08 ms to 0.99972 s)"
            }
            Self::HomeOutsideLimits => "home must lie within the joint's min and max",
            Self::ExceedsDrive {
                value_milli,
                drive_milli,
                drive_field,
            } => {
                let (v, d) = (value_milli, drive_milli);
                return write!(
                    f,
                    "{}.{:03} exceeds the {drive_field} {}.{:03} the drive is configured for \
                     (it would fall behind its commands)",
                    v / 1000,
                    v % 1000,
                    d / 1000,
                    d % 1000
                );
            }
            Self::BusOverloaded { percent } => {
                return write!(
                    f,
                    "worst-case CAN bus load {percent} % exceeds drives.max_bus_load; \
                     lengthen the period or raise the bit rate"
                );
            }
            Self::NotAFraction => "must be greater than 0 and at most 1",
            Self::MissingJerkLimit => "is required by [motion] profile = \"jerk-limited\"",
            Self::PdoLead => "must be 1 to 8 points",
            Self::PdoLeadRaise => "plus drives.pdo_lead must be at most 8 points",
            Self::TrackingIterations => "must be 1 to 100",
            Self::LineSlowdown => "must be 1 to 1000",
            Self::NoVolume => "a box must be thicker than zero on every axis",
            Self::NoSuchLink => "names a link the arm does not have (0 to the number of joints)",
            Self::HomeInCollision(hit) => {
                return write!(
                    f,
                    "the home pose is already in collision: {hit} (link L within the margin \
                     of box B, of another link, or out of the bounds)"
                );
            }
            Self::CountsOverflow => {
                "times the joint's min and max (from home) exceeds the drive's 32-bit counts"
            }
        })
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.joint {
            // Joints counted from 1, as everywhere else (the file's n-th [[joints]] table).
            Some(j) => write!(
                f,
                "joint {}, {}: {}",
                usize::from(j).saturating_add(1),
                self.field,
                self.reason
            ),
            None => write!(f, "{}: {}", self.field, self.reason),
        }
    }
}

impl core::error::Error for ConfigError {}
