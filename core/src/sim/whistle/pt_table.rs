//! The simulated drive's PT table and motion (SimplIQ software manual, "PT motion").
//!
//! Model (the simulation's reading of the manual, documented in docs/drives.md):
//!
//! * `QP[1..=64]` hold positions (a real drive has 1024); `MP[1]`/`MP[2]` bound the ring, `MP[3]`
//!   bit 0 makes it cyclic, `MP[4]` is the samples per segment, `MP[5]` the queue-low threshold.
//! * While the read index is `r` the drive moves from `QP[r]` to `QP[r+1]` on a cubic (Hermite,
//!   Catmull-Rom slopes: the slope at `QP[k]` is (`QP[k+1]` − `QP[k−1]`) / 2 per segment). When
//!   segment `r` starts it fetches `QP[r+2]` for the end slope; `BG` fetches the first three.
//! * A point must have been written since it was last fetched (or since the table was last
//!   configured through MP, or the last motion ended): fetching a stale point is a
//!   buffer underflow — the motion ends where it is and the drive sends the "motion
//!   terminated, read pointer reached write pointer" emergency. Writing over a point not yet
//!   fetched is refused with the "queue full" emergency.
//! * A point received by PDO ([`PtTable::push`]) goes to the write pointer `MP[6]`, which then
//!   moves to the next index of the ring (MAN-CAN301IG: the PT-type object is written "at
//!   the write pointer"); `QP[k]` writes by index leave the pointer alone.

use heapless::Vec;

use crate::drives::{DriveEmergency, REASON_UNDERFLOW};

/// Entries of the simulated QP table.
pub const TABLE_LEN: u16 = 64;

/// End of a non-cyclic table (a motion-terminated reason).
const REASON_END_OF_TABLE: u16 = 1;

/// One entry of QP.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Entry {
    value: i32,
    /// Written since it was last fetched.
    fresh: bool,
    /// When it was written (ns).
    written_at: u64,
}

/// The segment being run.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Segment {
    /// The read index.
    read: u16,
    /// Samples done in this segment.
    sample: u32,
    from: f64,
    to: f64,
    /// `QP[read + 2]`, fetched for the end slope; the next segment's end.
    ahead: f64,
    /// Slopes at both ends, counts per segment.
    slope_from: f64,
    slope_to: f64,
}

impl Segment {
    /// The position at fraction `u` of the segment.
    fn at(&self, u: f64) -> f64 {
        let (u2, u3) = (u * u, u * u * u);
        (2.0 * u3 - 3.0 * u2 + 1.0) * self.from
            + (u3 - 2.0 * u2 + u) * self.slope_from
            + (-2.0 * u3 + 3.0 * u2) * self.to
            + (u3 - u2) * self.slope_to
    }
}

/// What one sample of the motion produced.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    /// The profile position (counts), if the motion ran during this sample.
    pub reference: Option<f64>,
    /// An emergency the drive sends.
    pub emergency: Option<DriveEmergency>,
}

/// Why `BG` cannot start PT motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeginError {
    /// No `PT=k`, bad MP values, or `QP[k..k+2]` not all written.
    BadSetup,
}

/// Why a QP write was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WriteError {
    /// The index is outside the table.
    BadIndex,
    /// The entry holds a point not yet fetched.
    QueueFull,
}

/// Why a point received by PDO was not written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PushError {
    /// The write pointer `MP[6]` is outside the ring `MP[1]..=MP[2]` (or there is no ring).
    OutOfRange {
        /// The write pointer.
        write: u16,
    },
    /// The entry at the write pointer holds a point not yet fetched; the pointer stays.
    QueueFull {
        /// The write pointer.
        write: u16,
    },
}

/// Points reached since the last reset: how long after being written (ns).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Latency {
    /// Points reached that were written while the motion ran.
    pub points: u64,
    /// The longest time from writing a point to reaching it (ns).
    pub max_ns: u64,
    /// The sum over all points (ns).
    pub total_ns: u64,
}

/// The PT table and the motion through it.
#[derive(Clone, Debug, PartialEq)]
pub struct PtTable {
    /// `MP[1..=6]` (index 0 unused).
    mp: [i32; 7],
    entries: Vec<Entry, { TABLE_LEN as usize }>,
    /// `PT=k` given: the next `BG` starts at k.
    armed: Option<u16>,
    segment: Option<Segment>,
    /// The read index of the last motion.
    last_read: u16,
    /// When the motion began (ns).
    begun_at: Option<u64>,
    /// The first sample of the motion (ns): when the profile started to move.
    started_at: Option<u64>,
    /// When QP was last written (ns).
    last_write: Option<u64>,
    /// A queue-low warning was sent and the queue has not recovered since.
    warned_low: bool,
    latency: Latency,
}

impl Default for PtTable {
    fn default() -> Self {
        let mut entries = Vec::new();
        entries
            .resize(usize::from(TABLE_LEN), Entry::default())
            .ok();
        Self {
            mp: [0; 7],
            entries,
            armed: None,
            segment: None,
            last_read: 0,
            begun_at: None,
            started_at: None,
            last_write: None,
            warned_low: false,
            latency: Latency::default(),
        }
    }
}

impl PtTable {
    fn entry(&self, index: u16) -> Option<&Entry> {
        self.entries.get(usize::from(index).checked_sub(1)?)
    }

    fn entry_mut(&mut self, index: u16) -> Option<&mut Entry> {
        self.entries.get_mut(usize::from(index).checked_sub(1)?)
    }

    fn mp_at(&self, i: usize) -> i32 {
        self.mp.get(i).copied().unwrap_or(0)
    }

    /// The ring bounds `MP[1]..=MP[2]`, if valid.
    fn ring(&self) -> Option<(u16, u16)> {
        let first = u16::try_from(self.mp_at(1)).ok()?;
        let last = u16::try_from(self.mp_at(2)).ok()?;
        (1 <= first && first < last && last <= TABLE_LEN).then_some((first, last))
    }

    /// The index after `index` in the ring (`None` past the end of a non-cyclic table).
    fn next(&self, index: u16) -> Option<u16> {
        let (first, last) = self.ring()?;
        match index {
            i if i < last => Some(i + 1),
            _ if self.mp_at(3) & 1 == 1 => Some(first),
            _ => None,
        }
    }

    /// `MP[i]`, 1..=6.
    pub fn mp(&self, i: u16) -> Option<i32> {
        (1..=6).contains(&i).then(|| self.mp_at(usize::from(i)))
    }

    /// Sets `MP[i]`; false if `i` is not 1..=6. Redefining the table forgets which points were
    /// not yet executed.
    pub fn set_mp(&mut self, i: u16, value: i32) -> bool {
        match self.mp.get_mut(usize::from(i)).filter(|_| i >= 1) {
            Some(slot) => {
                *slot = value;
                self.entries.iter_mut().for_each(|e| e.fresh = false);
                true
            }
            None => false,
        }
    }

    /// `QP[i]`.
    pub fn qp(&self, i: u16) -> Option<i32> {
        self.entry(i).map(|e| e.value)
    }

    /// Writes `QP[i]` at time `now` (ns).
    pub fn write(&mut self, i: u16, value: i32, now: u64) -> Result<(), WriteError> {
        let running = self.segment.is_some();
        let entry = self.entry_mut(i).ok_or(WriteError::BadIndex)?;
        if running && entry.fresh {
            return Err(WriteError::QueueFull);
        }
        *entry = Entry {
            value,
            fresh: true,
            written_at: now,
        };
        self.last_write = Some(now);
        Ok(())
    }

    /// The write pointer `MP[6]`, as the PVT head pointer (0x2F11) reports it.
    pub fn write_pointer(&self) -> u16 {
        u16::try_from(self.mp_at(6)).unwrap_or(0)
    }

    /// A point received by PDO at `now` (ns): written at the write pointer, which advances
    /// (wrapping in a cyclic ring; past `MP[2]` otherwise, where the next point is refused).
    pub fn push(&mut self, value: i32, now: u64) -> Result<(), PushError> {
        let write = self.write_pointer();
        let in_ring = self
            .ring()
            .is_some_and(|(first, last)| (first..=last).contains(&write));
        if !in_ring {
            return Err(PushError::OutOfRange { write });
        }
        self.write(write, value, now).map_err(|error| match error {
            WriteError::QueueFull => PushError::QueueFull { write },
            WriteError::BadIndex => PushError::OutOfRange { write },
        })?;
        let next = self.next(write).unwrap_or(write.saturating_add(1));
        if let Some(slot) = self.mp.get_mut(6) {
            *slot = i32::from(next);
        }
        Ok(())
    }

    /// `PT=k`: the next `BG` starts PT motion at `QP[k]`; false if `k` is outside the table.
    pub fn arm(&mut self, k: i32) -> bool {
        let k = u16::try_from(k)
            .ok()
            .filter(|k| (1..=TABLE_LEN).contains(k));
        self.armed = k;
        k.is_some()
    }

    /// The read index (the last one after the motion ended).
    pub fn read_index(&self) -> u16 {
        self.segment.map_or(self.last_read, |s| s.read)
    }

    /// True while PT motion runs.
    pub fn running(&self) -> bool {
        self.segment.is_some()
    }

    /// Takes `QP[i]` for the motion: its value, if it was fresh.
    fn fetch(&mut self, i: u16) -> Option<f64> {
        let entry = self.entry_mut(i).filter(|e| e.fresh)?;
        entry.fresh = false;
        Some(f64::from(entry.value))
    }

    /// `BG` at `now` (ns): starts PT motion from the armed index.
    pub fn begin(&mut self, now: u64) -> Result<(), BeginError> {
        let start = self.armed.take().ok_or(BeginError::BadSetup)?;
        if self.mp_at(4) < 1 {
            return Err(BeginError::BadSetup);
        }
        let second = self.next(start).ok_or(BeginError::BadSetup)?;
        let third = self.next(second).ok_or(BeginError::BadSetup)?;
        let (Some(from), Some(to), Some(after)) =
            (self.fetch(start), self.fetch(second), self.fetch(third))
        else {
            return Err(BeginError::BadSetup);
        };
        self.segment = Some(Segment {
            read: start,
            sample: 0,
            from,
            to,
            ahead: after,
            slope_from: 0.0,
            slope_to: (after - from) / 2.0,
        });
        self.begun_at = Some(now);
        self.started_at = None;
        self.warned_low = false;
        Ok(())
    }

    /// Ends the motion (`ST`, motor off, a fault); the profile stays where it is. Points not
    /// yet executed are dropped: the online feed ends with the motion.
    pub fn stop(&mut self) {
        if let Some(segment) = self.segment.take() {
            self.last_read = segment.read;
            self.entries.iter_mut().for_each(|e| e.fresh = false);
        }
        self.armed = None;
    }

    /// Advances the motion by one sample at `now` (ns). `stalled` freezes the read index (an
    /// injected fault).
    pub fn sample(&mut self, now: u64, stalled: bool) -> Sample {
        let Some(mut segment) = self.segment else {
            return Sample::default();
        };
        let per_segment = u32::try_from(self.mp_at(4)).unwrap_or(1).max(1);
        self.started_at.get_or_insert(now);
        if !stalled {
            segment.sample += 1;
        }
        if segment.sample < per_segment {
            self.segment = Some(segment);
            let u = f64::from(segment.sample) / f64::from(per_segment);
            return Sample {
                reference: Some(segment.at(u)),
                emergency: None,
            };
        }
        // Segment boundary: QP[read + 1] is reached and becomes the start; QP[read + 3] is
        // fetched for the new end slope.
        let reached = self.next(segment.read);
        let fetch = reached
            .and_then(|r| self.next(r))
            .and_then(|r| self.next(r));
        let emergency = match (reached, fetch) {
            (Some(reached), Some(fetch)) => {
                self.record_latency(reached, now);
                match self.fetch(fetch) {
                    Some(ahead) => {
                        self.segment = Some(Segment {
                            read: reached,
                            sample: 0,
                            from: segment.to,
                            to: segment.ahead,
                            ahead,
                            slope_from: segment.slope_to,
                            slope_to: (ahead - segment.to) / 2.0,
                        });
                        self.queue_low()
                    }
                    None => Some(self.terminate(reached, REASON_UNDERFLOW)),
                }
            }
            _ => Some(self.terminate(segment.read, REASON_END_OF_TABLE)),
        };
        Sample {
            reference: Some(segment.to),
            emergency,
        }
    }

    /// Ends the motion at read index `read` for `reason`.
    fn terminate(&mut self, read: u16, reason: u16) -> DriveEmergency {
        self.stop();
        self.last_read = read;
        DriveEmergency::MotionTerminated {
            write: u16::try_from(self.mp_at(6)).unwrap_or(0),
            reason,
        }
    }

    fn record_latency(&mut self, index: u16, now: u64) {
        let begun = self.begun_at.unwrap_or(u64::MAX);
        if let Some(entry) = self.entry(index).filter(|e| e.written_at >= begun) {
            let latency = now.saturating_sub(entry.written_at);
            self.latency.points += 1;
            self.latency.max_ns = self.latency.max_ns.max(latency);
            self.latency.total_ns = self.latency.total_ns.saturating_add(latency);
        }
    }

    /// The queue-low warning: fewer fresh points in the ring than `MP[5]` (once per dip).
    fn queue_low(&mut self) -> Option<DriveEmergency> {
        let threshold = self.mp_at(5);
        let (first, last) = self.ring()?;
        let fresh = (first..=last)
            .filter(|&i| self.entry(i).is_some_and(|e| e.fresh))
            .count();
        let low = threshold > 0 && (fresh as i32) < threshold;
        let warn = low && !self.warned_low;
        self.warned_low = low;
        let read = self.read_index();
        warn.then_some(DriveEmergency::QueueLow {
            write: u16::try_from(self.mp_at(6)).unwrap_or(0),
            read,
        })
    }

    /// Latency of the points reached so far.
    pub fn latency(&self) -> Latency {
        self.latency
    }

    /// Forgets the latency so far.
    pub fn reset_latency(&mut self) {
        self.latency = Latency::default();
    }

    /// When the last motion began (ns).
    pub fn begun_at(&self) -> Option<u64> {
        self.begun_at
    }

    /// The first sample of the last motion (ns): when its profile started to move.
    pub fn started_at(&self) -> Option<u64> {
        self.started_at
    }

    /// When QP was last written (ns).
    pub fn last_write(&self) -> Option<u64> {
        self.last_write
    }
}
