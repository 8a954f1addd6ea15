//! Joint vectors of any length as the client sends and reads them, by the protocol's bank rule
//! (`armgate_protocol::client::banks`, docs/protocol.md "Arms with more than six joints").

use armgate_protocol::client::VALUES;
pub use armgate_protocol::client::banks::{MAX_JOINTS, READ_JOINTS, WRITE_JOINTS};
use armgate_protocol::client::banks::{bank_2_index, is_bank_2, read_position, write_values};

use crate::ClientError;

/// One datagram of a joint write: its index byte and f0..f6.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BankRequest {
    /// The index byte: the slot, with bit 7 set for bank 2.
    pub index: u8,
    /// f0..f5 the joints of this bank (zero-padded), f6 as given.
    pub values: [f32; VALUES],
}

/// Checks a joint count.
pub fn check_count(n: usize) -> Result<(), ClientError> {
    if (1..=MAX_JOINTS).contains(&n) {
        Ok(())
    } else {
        Err(ClientError::InvalidArgument(format!(
            "{n} joints: an arm has 1 to {MAX_JOINTS} joints"
        )))
    }
}

/// The datagrams of a joint write, in send order: bank 2 first if `q` has more than six joints,
/// then bank 1. `slot` is the via slot (0 for `jG`/`RC`), `f6` the last value (the duration for
/// `jV`, 0 otherwise).
pub fn split(q: &[f64], slot: u8, f6: f32) -> Result<Vec<BankRequest>, ClientError> {
    check_count(q.len())?;
    if is_bank_2(slot) {
        return Err(ClientError::InvalidArgument(format!(
            "via slot {slot}: bit 7 of the index selects the joint bank, slots are 0..=127"
        )));
    }
    let bank = |joints: &[f64], index: u8| BankRequest {
        index,
        values: write_values(joints, f6),
    };
    let (lower, upper) = q.split_at(q.len().min(WRITE_JOINTS));
    let mut out = Vec::with_capacity(2);
    if !upper.is_empty() {
        out.push(bank(upper, bank_2_index(slot)));
    }
    out.push(bank(lower, slot));
    Ok(out)
}

/// Whether reading `n` joints needs the bank-2 read.
pub fn needs_bank2_read(n: usize) -> bool {
    n > READ_JOINTS
}

/// The `n` joint values of a read: joints 1..7 from the bank-1 reply, joints 8.. from the
/// bank-2 reply (which starts at joint 7); a joint whose reply is missing ends the list.
pub fn merge_read(n: usize, bank1: &[f32; VALUES], bank2: Option<&[f32; VALUES]>) -> Vec<f64> {
    (0..n)
        .map_while(|joint| {
            let (in_bank_2, at) = read_position(joint)?;
            let reply = if in_bank_2 { bank2? } else { bank1 };
            reply.get(at).map(|v| f64::from(*v))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn six_joints_is_one_bank() {
        let banks = split(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 0, 0.0).unwrap();
        assert_eq!(banks.len(), 1);
        assert_eq!(banks[0].index, 0);
        assert_eq!(banks[0].values, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0]);
    }

    #[test]
    fn eight_joints_send_bank_two_first() {
        let q = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let banks = split(&q, 5, 2.5).unwrap();
        assert_eq!(banks.len(), 2);
        assert_eq!(banks[0].index, 0x85);
        assert_eq!(banks[0].values, [7.0, 8.0, 0.0, 0.0, 0.0, 0.0, 2.5]);
        assert_eq!(banks[1].index, 0x05);
        assert_eq!(banks[1].values, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 2.5]);
    }

    #[test]
    fn counts_and_slots_are_checked() {
        assert!(split(&[], 0, 0.0).is_err());
        assert!(split(&[0.0; 9], 0, 0.0).is_err());
        assert!(split(&[0.0; 6], 0x80, 0.0).is_err());
        assert!(split(&[0.0; 3], 0, 0.0).is_ok());
    }

    #[test]
    fn reads_merge_at_joint_eight() {
        let b1 = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
        let b2 = [7.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert_eq!(
            merge_read(8, &b1, Some(&b2)),
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]
        );
        assert_eq!(merge_read(6, &b1, None), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert!(!needs_bank2_read(7));
        assert!(needs_bank2_read(8));
    }
}
