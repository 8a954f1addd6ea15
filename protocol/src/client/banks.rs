//! Joint banks: how requests of seven floats carry the joints of arms with up to eight joints
//! (docs/protocol.md, "Arms with more than six joints").
//!
//! * Writes (`jG`, `jV`, `RC`) carry six joints in f0..f5. For more than six, a bank-2 request
//!   (index bit 7 set, joints 7.. in f0..) goes first, then the bank-1 request (joints 1..6)
//!   completes the vector. For `jV` the via slot stays in bits 0–6 of both.
//! * Reads (`jP`, `TM`) answer joints 1..7 in f0..f6. For more than seven joints, a second read
//!   with bit 7 set answers joints 7.. in f0.. (so joint 8 is its f1).

use super::VALUES;

/// The most joints an arm may have: what two banks address (the seed's Ranger Mark II has 8).
pub const MAX_JOINTS: usize = 8;

/// Index-byte flag of bank 2.
pub const BANK_2: u8 = 0x80;

/// Joints per write request (f0..f5; f6 is the duration of `jV`).
pub const WRITE_JOINTS: usize = 6;

/// Joints per read reply (f0..f6).
pub const READ_JOINTS: usize = 7;

/// The index byte of a bank-2 request or reply with `slot` in bits 0–6.
pub const fn bank_2_index(slot: u8) -> u8 {
    slot | BANK_2
}

/// Whether `index` selects bank 2.
pub const fn is_bank_2(index: u8) -> bool {
    index & BANK_2 != 0
}

/// The via slot (bits 0–6) of `index`.
pub const fn slot(index: u8) -> u8 {
    index & !BANK_2
}

/// Where joint `joint` (0-based) of a read answer is: in the bank-2 reply (`true`) or not,
/// and at which value. Joints past [`MAX_JOINTS`] have no place.
pub const fn read_position(joint: usize) -> Option<(bool, usize)> {
    if joint < READ_JOINTS {
        Some((false, joint))
    } else if joint < MAX_JOINTS {
        // The bank-2 reply starts at joint 7.
        Some((true, joint - WRITE_JOINTS))
    } else {
        None
    }
}

/// The values of one write bank: `joints` (at most [`WRITE_JOINTS`] taken) in f0.., zero
/// padded, and `f6` last.
pub fn write_values(joints: &[f64], f6: f32) -> [f32; VALUES] {
    let mut values = [0.0; VALUES];
    for (v, q) in values.iter_mut().zip(joints.iter().take(WRITE_JOINTS)) {
        *v = *q as f32;
    }
    if let Some(last) = values.last_mut() {
        *last = f6;
    }
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_bits() {
        assert_eq!(bank_2_index(5), 0x85);
        assert!(is_bank_2(0x85) && !is_bank_2(0x05));
        assert_eq!(slot(0x85), 5);
    }

    #[test]
    fn reads_place_joint_eight_at_f1_of_bank_2() {
        assert_eq!(read_position(0), Some((false, 0)));
        assert_eq!(read_position(6), Some((false, 6)));
        assert_eq!(read_position(7), Some((true, 1)));
        assert_eq!(read_position(8), None);
    }

    #[test]
    fn write_values_pad_and_end_with_f6() {
        assert_eq!(
            write_values(&[1.0, 2.0], 2.5),
            [1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 2.5]
        );
        assert_eq!(
            write_values(&[1.0; 8], 0.0),
            [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0]
        );
    }
}
