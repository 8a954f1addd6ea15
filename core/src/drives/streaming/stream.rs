//! One drive's PT writer, of the schedule its start chose: a one-of, so that a drive never
//! holds a writer of the other schedule.

use super::{PdoStream, PtStream};

/// The PT writer of one drive, from `BG` until the motion stops.
#[derive(Clone, Debug, PartialEq)]
pub enum Stream {
    /// Interpreter schedule: `QP` writes paced by the drive's read index.
    Interpreter(PtStream),
    /// PDO schedule: receive PDOs paced by the PT pointers of the drive's transmit PDO.
    Pdo(PdoStream),
}

impl Stream {
    /// The points the drive had queued ahead of its read pointer when it last said.
    #[inline]
    pub fn lead(&self) -> Option<u32> {
        match self {
            Self::Interpreter(stream) => stream.lead(),
            Self::Pdo(stream) => stream.lead(),
        }
    }

    /// The interpreter schedule's writer, if this is one.
    #[inline]
    pub fn interpreter(&mut self) -> Option<&mut PtStream> {
        match self {
            Self::Interpreter(stream) => Some(stream),
            Self::Pdo(_) => None,
        }
    }

    /// The PDO schedule's writer, if this is one.
    #[inline]
    pub fn pdo(&mut self) -> Option<&mut PdoStream> {
        match self {
            Self::Pdo(stream) => Some(stream),
            Self::Interpreter(_) => None,
        }
    }
}
