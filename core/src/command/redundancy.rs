//! The controller's side of `KR` (the wire rules are in
//! `armgate_protocol::client::redundancy`): the values of the redundancy parameters one
//! client chose for its next `KG` and its `KS` reads.
//!
//! A choice belongs to the client that made it (the holder: `KR` commands the arm, so it needs
//! the holder as `KG` does) and lasts until that client's next `KG` (whatever its answer), a
//! stop (`ST`, `jR`, the client watchdog) or a change of holder. A `KG` or `KS` that asks for
//! the choice when there is none is refused (`ER24`), so a cleared choice is never a move with
//! other values.

use core::net::SocketAddr;

use crate::kinematics::Joints;

/// The chosen values (rad) of the redundancy parameters, in the order of
/// [`Chain::redundancy_parameters`](crate::kinematics::Chain::redundancy_parameters); `None`:
/// the present value.
pub(super) type Values = [Option<f64>; 2];

/// The last `KR` choice and the client that made it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RedundancyChoice(Option<(SocketAddr, Values)>);

impl RedundancyChoice {
    /// Keeps `values` for `client`, replacing any earlier choice.
    pub(super) fn choose(&mut self, client: SocketAddr, values: Values) {
        self.0 = Some((client, values));
    }

    /// Forgets the choice.
    pub(super) fn clear(&mut self) {
        self.0 = None;
    }

    /// `client`'s choice, if it made the last one.
    pub(super) fn of(&self, client: SocketAddr) -> Option<Values> {
        self.0.filter(|(owner, _)| *owner == client).map(|(_, v)| v)
    }

    /// `client`'s choice, forgotten (its `KG`).
    pub(super) fn take(&mut self, client: SocketAddr) -> Option<Values> {
        let values = self.of(client);
        if values.is_some() {
            self.clear();
        }
        values
    }
}

/// `reference` with the chosen values put in at the redundancy parameters' joints.
pub(super) fn apply(values: Values, parameters: &[usize], reference: &mut Joints) {
    for (joint, value) in parameters.iter().zip(values) {
        if let (Some(v), Some(slot)) = (value, reference.get_mut(*joint)) {
            *slot = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_choice_is_its_clients_until_taken_or_cleared() {
        let (a, b) = (
            SocketAddr::from(([10, 0, 0, 1], 1)),
            SocketAddr::from(([10, 0, 0, 2], 2)),
        );
        let mut choice = RedundancyChoice::default();
        choice.choose(a, [Some(0.5), None]);
        assert_eq!(choice.of(b), None);
        assert_eq!(choice.take(b), None, "another client's KG leaves it");
        assert_eq!(choice.of(a), Some([Some(0.5), None]));
        assert_eq!(choice.take(a), Some([Some(0.5), None]));
        assert_eq!(choice.of(a), None, "taken");
        choice.choose(a, [Some(0.5), Some(-0.25)]);
        choice.clear();
        assert_eq!(choice.of(a), None);

        let mut q = Joints::from_slice(&[0.1; 8]).unwrap();
        apply([Some(0.5), Some(-0.25)], &[2, 4], &mut q);
        assert_eq!(&q[..], &[0.1, 0.1, 0.5, 0.1, -0.25, 0.1, 0.1, 0.1]);
        apply([None, Some(0.7)], &[2, 4], &mut q);
        assert_eq!(q[2], 0.5);
        assert_eq!(q[4], 0.7);
    }
}
