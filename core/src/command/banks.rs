//! The controller's side of the joint banks (the wire rules are in
//! `armgate_protocol::client::banks`): a bank-2 request stages the upper joints; the next
//! bank-1 request of the same kind (and slot) completes the vector with them. See
//! docs/protocol.md.
//!
//! Staged values belong to the client that sent them and expire: a bank 1 completes only a bank
//! 2 of the same client staged within [`STAGED_FOR`]; another client's staging replaces them,
//! and `ST`, `CM`, `ON`, `OF` clear them. So a lost bank-2 datagram is a refusal (`ER24`), never
//! a vector completed with another client's (or an old) joints 7–8.

pub(super) use armgate_protocol::client::banks::{BANK_2, WRITE_JOINTS as BANK_LEN};

use core::net::SocketAddr;

use crate::MAX_JOINTS;
use crate::kinematics::Joints;
use crate::motion::VIA_SLOTS;

/// Joints 7 and 8.
const UPPER: usize = MAX_JOINTS - BANK_LEN;

/// How long staged values wait for their bank 1 (s).
pub(super) const STAGED_FOR: f64 = 1.0;

/// Staged upper joints and when they were staged (s).
type Staged = Option<([f64; UPPER], f64)>;

/// Which request a staged bank 2 belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum BankKey {
    /// jG.
    Goal,
    /// RC.
    Recalibrate,
    /// jV for one slot.
    Via(usize),
    /// jW.
    Rates,
}

/// Why a bank request was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum BankError {
    /// Bank 2 on an arm with six joints or fewer, a slot out of range, or bank 1 of a 7–8 joint
    /// arm without a staged bank 2.
    BadIndex,
}

/// Staged upper joints, per request kind and via slot, of one client.
#[derive(Clone, Debug, Default)]
pub(super) struct Banks {
    /// The client whose values these are.
    owner: Option<SocketAddr>,
    goal: Staged,
    recalibrate: Staged,
    rates: Staged,
    via: [Staged; VIA_SLOTS],
}

impl Banks {
    /// Forgets everything staged.
    pub(super) fn clear(&mut self) {
        *self = Self::default();
    }

    /// Makes `client` the owner, forgetting another client's values.
    fn own(&mut self, client: SocketAddr) {
        if self.owner != Some(client) {
            self.clear();
            self.owner = Some(client);
        }
    }

    fn slot(&mut self, key: BankKey) -> Result<&mut Staged, BankError> {
        match key {
            BankKey::Goal => Ok(&mut self.goal),
            BankKey::Recalibrate => Ok(&mut self.recalibrate),
            BankKey::Rates => Ok(&mut self.rates),
            BankKey::Via(i) => self.via.get_mut(i).ok_or(BankError::BadIndex),
        }
    }

    /// Stages bank 2 (`values` = joints 7..) from `client` at `now` for an arm of `n` joints.
    pub(super) fn stage(
        &mut self,
        key: BankKey,
        values: &[f64],
        n: usize,
        client: SocketAddr,
        now: f64,
    ) -> Result<(), BankError> {
        if n <= BANK_LEN {
            return Err(BankError::BadIndex);
        }
        let mut upper = [0.0; UPPER];
        for (u, v) in upper.iter_mut().zip(values) {
            *u = *v;
        }
        self.own(client);
        *self.slot(key)? = Some((upper, now));
        Ok(())
    }

    /// The full joint vector of a bank-1 request (`values` = joints 1..6) from `client` at
    /// `now` for an arm of `n` joints, consuming the bank 2 it staged (within [`STAGED_FOR`])
    /// if the arm has more than six joints.
    pub(super) fn complete(
        &mut self,
        key: BankKey,
        values: &[f64],
        n: usize,
        client: SocketAddr,
        now: f64,
    ) -> Result<Joints, BankError> {
        let mut q = Joints::zeros(n);
        for (dst, v) in q.iter_mut().zip(values) {
            *dst = *v;
        }
        if n > BANK_LEN {
            self.own(client);
            let (upper, at) = self.slot(key)?.take().ok_or(BankError::BadIndex)?;
            if now - at > STAGED_FOR {
                return Err(BankError::BadIndex);
            }
            for (dst, v) in q.iter_mut().skip(BANK_LEN).zip(upper) {
                *dst = v;
            }
        }
        Ok(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bank_completes_only_its_clients_fresh_values() {
        let (a, b) = (
            SocketAddr::from(([10, 0, 0, 1], 1)),
            SocketAddr::from(([10, 0, 0, 2], 2)),
        );
        let mut banks = Banks::default();
        let lower = [0.1; BANK_LEN];
        banks.stage(BankKey::Goal, &[0.7, 0.8], 8, a, 0.0).unwrap();
        let q = banks.complete(BankKey::Goal, &lower, 8, a, 0.5).unwrap();
        assert_eq!((q[6], q[7]), (0.7, 0.8));
        // Consumed: a second bank 1 has nothing to complete.
        assert!(banks.complete(BankKey::Goal, &lower, 8, a, 0.5).is_err());
        // Another client's bank 1 does not take A's values.
        banks.stage(BankKey::Goal, &[0.7, 0.8], 8, a, 1.0).unwrap();
        assert!(banks.complete(BankKey::Goal, &lower, 8, b, 1.1).is_err());
        assert!(banks.complete(BankKey::Goal, &lower, 8, a, 1.1).is_err());
        // Stale after a second; cleared by a stop or mode change.
        banks
            .stage(BankKey::Via(3), &[0.7, 0.8], 8, a, 2.0)
            .unwrap();
        assert!(banks.complete(BankKey::Via(3), &lower, 8, a, 3.5).is_err());
        banks.stage(BankKey::Rates, &[0.7, 0.8], 8, a, 4.0).unwrap();
        banks.clear();
        assert!(banks.complete(BankKey::Rates, &lower, 8, a, 4.1).is_err());
        // Six joints: nothing to stage, bank 1 is the whole vector.
        assert!(banks.stage(BankKey::Goal, &[0.7, 0.8], 6, a, 0.0).is_err());
        assert_eq!(
            banks
                .complete(BankKey::Goal, &lower, 6, b, 0.0)
                .unwrap()
                .len(),
            6
        );
    }
}
