//! The PDO mapping the PDO schedule writes at start-up, one SDO transfer per step.
//!
//! PLACEHOLDER until the protocol crate's mapping plan lands (branch pdo-sim).

use armgate_protocol::can::{NodeId, Object, SdoValue};

/// One step of the mapping: a write, or a read whose value must match.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapStep {
    /// Write `value` to `object`.
    Write {
        /// The entry.
        object: Object,
        /// Its value.
        value: SdoValue,
    },
    /// Read `object` back; it must hold `expect`.
    Check {
        /// The entry.
        object: Object,
        /// Its value.
        expect: SdoValue,
    },
}

/// Steps of the plan.
pub const MAP_STEPS: u8 = 2;

/// Step `index` of `node`'s mapping.
pub fn map_step(node: NodeId, index: u8) -> Option<MapStep> {
    let object = Object {
        index: 0x1402,
        subindex: 1,
    };
    let value = SdoValue::U32(0x400 | u32::from(node.get()));
    match index {
        0 => Some(MapStep::Write { object, value }),
        1 => Some(MapStep::Check {
            object,
            expect: value,
        }),
        _ => None,
    }
}
