//! What a link of the arm would hit: the words of `ER25 … L3 hits B1 at 40%` (a refused move)
//! and `ER21 L5 hits L2` (a motion stopped), written and read back here.
//!
//! Compact because a text holds 30 characters and `ER25 Cmd jB ` and ` at 40%` take 19:
//! `L3` is link 3 (0 is the base, the last link carries the tool), `B1` the robot file's first
//! exclusion box, `out` the workspace bounds.

use core::fmt;

use super::words::decimal;

/// What a link comes too close to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Obstacle {
    /// `B1`: exclusion box 1 (numbered from 1 in the robot file's order).
    Box(u8),
    /// `L2`: another link of the arm.
    Link(u8),
    /// `out`: the link would leave the workspace bounds.
    Bounds,
}

/// A link of the arm too close to an obstacle (within the robot file's margin).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hit {
    /// The link (0 = base).
    pub link: u8,
    /// What it hits.
    pub obstacle: Obstacle,
}

impl Hit {
    const HITS: &'static str = " hits ";
    const OUT: &'static str = " out";

    /// Reads `L3 hits B1`, `L5 hits L2` or `L3 out` back.
    pub(super) fn parse(s: &str) -> Option<Self> {
        let rest = s.strip_prefix('L')?;
        if let Some(link) = rest.strip_suffix(Self::OUT) {
            return Some(Self {
                link: decimal(link)?,
                obstacle: Obstacle::Bounds,
            });
        }
        let (link, what) = rest.split_once(Self::HITS)?;
        let obstacle = if let Some(b) = what.strip_prefix('B') {
            Obstacle::Box(decimal(b)?)
        } else {
            Obstacle::Link(decimal(what.strip_prefix('L')?)?)
        };
        Some(Self {
            link: decimal(link)?,
            obstacle,
        })
    }
}

impl fmt::Display for Hit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.obstacle {
            Obstacle::Box(b) => write!(f, "L{}{}B{b}", self.link, Self::HITS),
            Obstacle::Link(l) => write!(f, "L{}{}L{l}", self.link, Self::HITS),
            Obstacle::Bounds => write!(f, "L{}{}", self.link, Self::OUT),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_read_back_what_they_print() {
        let cases = [
            (Obstacle::Box(1), "L3 hits B1"),
            (Obstacle::Box(16), "L8 hits B16"),
            (Obstacle::Link(2), "L5 hits L2"),
            (Obstacle::Bounds, "L3 out"),
        ];
        for (obstacle, text) in cases {
            let link = text[1..2].parse().unwrap();
            let hit = Hit { link, obstacle };
            assert_eq!(hit.to_string(), text);
            assert_eq!(Hit::parse(text), Some(hit));
        }
        for bad in [
            "L3 hits",
            "L hits B1",
            "3 hits B1",
            "L3 hits X1",
            "L3 hits B-1",
        ] {
            assert_eq!(Hit::parse(bad), None, "{bad}");
        }
    }
}
