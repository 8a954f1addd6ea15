//! The nearest gap of the arm's body: the reply to `SQ` index 7 (issue 35).
//!
//! `QS` index 7: f0 the smallest gap (m) between the arm's capsules and what they are checked
//! against at the measured pose (boxes, the bounds, links not excluded from each other;
//! negative: overlap), f1 the link (0 = base), f2 the kind of obstacle ([`OBSTACLE_KINDS`]),
//! f3 its number (box n from 1, link m; 0 for the bounds), f4 the robot file's margin (m).
//! f1 = −1 when there is nothing to measure (no body, no measurement): then f0 is 0.

use super::{Command, DecodeError, Hit, Obstacle, Reply};

/// `SQ` index of the nearest-gap report.
pub const NEAREST_INDEX: u8 = 7;
/// The kinds of obstacle by their number in f2, with their names and the short form the
/// texts use (`L3 hits B1`, `L5 hits L2`, `L6 out`); `protocol/grammar.json` lists them for
/// the clients in other languages.
pub const OBSTACLE_KINDS: [(u8, &str, &str); 3] =
    [(0, "box", "B"), (1, "link", "L"), (2, "bounds", "out")];

/// The nearest gap and the pair it is between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearestReport {
    /// The gap (m) and the link and obstacle it is between; none when there is nothing to
    /// measure.
    pub nearest: Option<(f32, Hit)>,
    /// The margin the body keeps (m).
    pub margin: f32,
}

impl NearestReport {
    /// The reply, index 7.
    pub fn to_reply(&self) -> Reply {
        let values = match self.nearest {
            Some((gap, hit)) => {
                let (kind, number) = match hit.obstacle {
                    Obstacle::Box(b) => (0u8, b),
                    Obstacle::Link(l) => (1, l),
                    Obstacle::Bounds => (2, 0),
                };
                [
                    gap,
                    f32::from(hit.link),
                    f32::from(kind),
                    f32::from(number),
                    self.margin,
                    0.0,
                    0.0,
                ]
            }
            None => [0.0, -1.0, 0.0, 0.0, self.margin, 0.0, 0.0],
        };
        Reply {
            command: Command::Status,
            values,
            index: NEAREST_INDEX,
        }
    }

    /// Decodes a `QS` index-7 reply (on the client side).
    pub fn from_reply(reply: &Reply) -> Result<Self, DecodeError> {
        if reply.command != Command::Status || reply.index != NEAREST_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let [gap, link, kind, number, margin, _, _] = reply.values;
        let small = |v: f32| {
            (v.is_finite() && (0.0..=255.0).contains(&v) && v == libm::roundf(v)).then_some(v as u8)
        };
        let nearest = if link < 0.0 {
            None
        } else {
            let (link, number) = (small(link), small(number));
            let obstacle = match (small(kind), number) {
                (Some(0), Some(b)) => Obstacle::Box(b),
                (Some(1), Some(l)) => Obstacle::Link(l),
                (Some(2), _) => Obstacle::Bounds,
                _ => return Err(DecodeError::BadField),
            };
            let link = link.ok_or(DecodeError::BadField)?;
            Some((gap, Hit { link, obstacle }))
        };
        Ok(Self { nearest, margin })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_round_trip_with_known_values() {
        let report = NearestReport {
            nearest: Some((
                0.125,
                Hit {
                    link: 3,
                    obstacle: Obstacle::Box(1),
                },
            )),
            margin: 0.01,
        };
        let reply = report.to_reply();
        assert_eq!(reply.values, [0.125, 3.0, 0.0, 1.0, 0.01, 0.0, 0.0]);
        assert_eq!(reply.to_bytes()[30], NEAREST_INDEX);
        assert_eq!(NearestReport::from_reply(&reply), Ok(report));
        for (obstacle, kind, number) in
            [(Obstacle::Link(2), 1.0, 2.0), (Obstacle::Bounds, 2.0, 0.0)]
        {
            let report = NearestReport {
                nearest: Some((-0.5, Hit { link: 6, obstacle })),
                margin: 0.0,
            };
            let reply = report.to_reply();
            assert_eq!(reply.values[..4], [-0.5, 6.0, kind, number]);
            assert_eq!(NearestReport::from_reply(&reply), Ok(report));
        }
        let none = NearestReport {
            nearest: None,
            margin: 0.02,
        };
        assert_eq!(none.to_reply().values[1], -1.0);
        assert_eq!(NearestReport::from_reply(&none.to_reply()), Ok(none));
        let mut bad = reply;
        bad.values[2] = 3.0;
        assert_eq!(NearestReport::from_reply(&bad), Err(DecodeError::BadField));
        bad.values[2] = 0.5;
        assert_eq!(NearestReport::from_reply(&bad), Err(DecodeError::BadField));
        bad.index = 6;
        assert_eq!(
            NearestReport::from_reply(&bad),
            Err(DecodeError::WrongCommand)
        );
    }
}
