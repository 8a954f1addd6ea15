//! The sentinel values of a `TM` reply (°C).

/// A drive that has not reported a temperature yet (spec §6.9).
pub const UNKNOWN_TEMPERATURE: f32 = -100.0;

/// The padding of value slots past the arm's last joint (spec §2.5).
pub const NO_JOINT_TEMPERATURE: f32 = -1000.0;
