//! The controller's side of the joint banks (the wire rules are in
//! `armgate_protocol::client::banks`): a bank-2 request stages the upper joints; the next
//! bank-1 request of the same kind (and slot) completes the vector with them. See
//! docs/protocol.md.

pub(super) use armgate_protocol::client::banks::{BANK_2, WRITE_JOINTS as BANK_LEN};

use crate::MAX_JOINTS;
use crate::kinematics::Joints;
use crate::motion::VIA_SLOTS;

/// Joints 7 and 8.
const UPPER: usize = MAX_JOINTS - BANK_LEN;

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

/// Staged upper joints, per request kind and via slot.
#[derive(Clone, Debug, Default)]
pub(super) struct Banks {
    goal: Option<[f64; UPPER]>,
    recalibrate: Option<[f64; UPPER]>,
    rates: Option<[f64; UPPER]>,
    via: [Option<[f64; UPPER]>; VIA_SLOTS],
}

impl Banks {
    fn slot(&mut self, key: BankKey) -> Result<&mut Option<[f64; UPPER]>, BankError> {
        match key {
            BankKey::Goal => Ok(&mut self.goal),
            BankKey::Recalibrate => Ok(&mut self.recalibrate),
            BankKey::Rates => Ok(&mut self.rates),
            BankKey::Via(i) => self.via.get_mut(i).ok_or(BankError::BadIndex),
        }
    }

    /// Stages bank 2 (`values` = joints 7..) for an arm of `n` joints.
    pub(super) fn stage(
        &mut self,
        key: BankKey,
        values: &[f64],
        n: usize,
    ) -> Result<(), BankError> {
        if n <= BANK_LEN {
            return Err(BankError::BadIndex);
        }
        let mut upper = [0.0; UPPER];
        for (u, v) in upper.iter_mut().zip(values) {
            *u = *v;
        }
        *self.slot(key)? = Some(upper);
        Ok(())
    }

    /// The full joint vector of a bank-1 request (`values` = joints 1..6) for an arm of `n`
    /// joints, consuming the staged bank 2 if the arm has more than six joints.
    pub(super) fn complete(
        &mut self,
        key: BankKey,
        values: &[f64],
        n: usize,
    ) -> Result<Joints, BankError> {
        let mut q = Joints::zeros(n);
        for (dst, v) in q.iter_mut().zip(values) {
            *dst = *v;
        }
        if n > BANK_LEN {
            let upper = self.slot(key)?.take().ok_or(BankError::BadIndex)?;
            for (dst, v) in q.iter_mut().skip(BANK_LEN).zip(upper) {
                *dst = v;
            }
        }
        Ok(q)
    }
}
