//! The whole-arm oracle: what the stop bench, the `datagram` fuzz target and the stop tests
//! hold every commanded pose to, motion and braking alike (issue 35): no link enters an
//! exclusion box or another link, and the tool's capsules do not leave the bounds.
//!
//! It measures each pose afresh with core's own distances (the body model of [`Envelope`],
//! placed by the chain's link frames, which the kinematics tests hold to the robot file's DH
//! product), against the surfaces themselves: a gap of zero or less is contact, whatever
//! margin the file keeps, and every gap counts, not just those of new hits. Contact present where the watch began or at the pose
//! before (an arm started in a box may leave it) is not an entry; only a new one is.

use heapless::Vec;

use crate::config::{MAX_CAPSULES, ValidRobot};
use crate::geometry::Capsule;
use crate::kinematics::{Chain, Joints};
use crate::motion::Body;
use armgate_protocol::client::Hit;

/// Most contacts remembered from one pose to the next.
const CONTACTS: usize = 32;

/// A link that came into contact: with what, and the gap (m, ≤ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    /// The link and the obstacle.
    pub hit: Hit,
    /// The gap at the pose (m, ≤ 0; the amount is no depth).
    pub gap: f64,
}

/// Watches one arm's commanded poses ([`check`](Self::check) each).
#[derive(Clone, Debug)]
pub struct BodyOracle {
    chain: Chain,
    body: Body,
    /// The last pose checked, and its contacts.
    last: Option<Joints>,
    contacts: Vec<Hit, CONTACTS>,
    /// The least gap seen and to what.
    nearest: Option<(f64, Hit)>,
}

impl BodyOracle {
    /// Watches `config`'s arm from pose `start` (its contacts are not entries).
    pub fn new(config: &ValidRobot, start: &[f64]) -> Self {
        let mut oracle = Self {
            chain: Chain::new(config),
            body: Body::new(config),
            last: None,
            contacts: Vec::new(),
            nearest: None,
        };
        let _ = oracle.check(start);
        oracle.nearest = None;
        oracle
    }

    /// Measures pose `q`: the first contact that was not present at the last pose checked,
    /// if any. Every gap counts towards [`nearest`](Self::nearest). A pose the chain cannot
    /// place (not one value per joint) is not measured: the callers check that commands are
    /// finite and within the joint limits.
    pub fn check(&mut self, q: &[f64]) -> Result<(), Entry> {
        // A held pose: measured already, nothing new.
        if self.nearest.is_some() && self.last.is_some_and(|last| &last[..] == q) {
            return Ok(());
        }
        self.last = Joints::from_slice(q);
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        let Some(q) = self.last.as_ref() else {
            return Ok(());
        };
        if !self.body.place(&self.chain, q, &mut placed) {
            return Ok(());
        }
        let (last, mut now) = (&self.contacts, Vec::<Hit, CONTACTS>::new());
        let (mut entry, mut nearest) = (None, self.nearest);
        self.body
            .envelope()
            .gaps(&placed, None, f64::INFINITY, &mut |hit, gap, _| {
                if nearest.is_none_or(|(least, _)| gap < least) {
                    nearest = Some((gap, hit));
                }
                // Touching is contact (a line, radius 0, meets a box at gap 0 however deep
                // it goes); NaN too.
                if gap.is_nan() || gap <= 0.0 {
                    if !last.contains(&hit) && entry.is_none() {
                        entry = Some(Entry { hit, gap });
                    }
                    if !now.contains(&hit) {
                        let _ = now.push(hit);
                    }
                }
                true
            });
        self.contacts = now;
        self.nearest = nearest;
        entry.map_or(Ok(()), Err)
    }

    /// The least gap of every pose checked since [`new`](Self::new) (m; zero or less: contact),
    /// and to what; none before a check or for an arm without a body.
    pub fn nearest(&self) -> Option<(f64, Hit)> {
        self.nearest
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::parse_toml;

    #[test]
    #[allow(clippy::approx_constant)]
    fn a_link_entering_the_column_is_an_entry_and_one_leaving_it_is_not() {
        let text = include_str!("../../../robots/ranger-mk1.toml");
        let config = parse_toml(text).unwrap();
        let ready = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];
        // Issue 35's pose: the wrist centre inside the base column.
        let through = [0.727, 1.084, 1.506, -2.849, 3.481, -1.322];
        let mut oracle = BodyOracle::new(&config, &ready);
        assert_eq!(oracle.nearest(), None);
        assert_eq!(oracle.check(&ready), Ok(()));
        let (clear, _) = oracle.nearest().unwrap();
        assert!(clear > 0.0, "{clear}");
        let entry = oracle.check(&through).unwrap_err();
        assert!(entry.gap <= 0.0, "{entry:?}");
        assert!(oracle.nearest().unwrap().0 <= entry.gap);
        // Staying in, and leaving: no entry.
        assert_eq!(oracle.check(&through), Ok(()));
        assert_eq!(oracle.check(&ready), Ok(()));
        // Started inside: not an entry either.
        let mut inside = BodyOracle::new(&config, &through);
        assert_eq!(inside.check(&through), Ok(()));
    }
}
