//! The simulated drive's PT table and motion (Elmo HARmonica software manual HARSFEN0602
//! §12.1.7.4, "Motion Management", which SimplIQ drives share).
//!
//! Model (the simulation's reading of the manual, documented in docs/drives.md):
//!
//! * `QP[1..=64]` hold positions (a real drive has 1024); `MP[1]`/`MP[2]` bound the ring, `MP[3]`
//!   bit 0 makes it cyclic, `MP[4]` is the samples per segment, `MP[5]` the queue-low threshold.
//! * Which point is read when, as the manual says: "When the read pointer is N, the present
//!   motion segment starts at the position of `QP[N]`, and ends at `QP(N+1)`. After `MP[4]`
//!   control sampling times, the Amplifier increments the read pointer to N+1, and reads the
//!   `QP[N+2]` to calculate the parameters of the next motion segment." So when segment `r`
//!   starts the drive fetches `QP[r+1]`, the segment's own end, and nothing beyond it; `BG`
//!   fetches `QP[k]` and `QP[k+1]`. (The previous model fetched `QP[r+2]` for a Catmull-Rom
//!   end slope: one point further than the manual. [`PtTable::new`] keeps it as an option,
//!   for a test that a drive doing so streams with a lead one higher.)
//! * **ASSUMED** (the manual gives no formula; "third order" is the seed's thesis): segment `r`
//!   is a cubic Hermite from `QP[r]` to `QP[r+1]` computed only from points up to `r+1`: the
//!   slope at knot `k` is the second-order backward difference (3·`QP[k]` − 4·`QP[k−1]` +
//!   `QP[k−2]`) / 2 per segment — exact for constant acceleration, causal, and continuous
//!   (each segment starts with the slope the last one ended with). `BG` starts from rest.
//! * A point must have been written since it was last fetched (or since the table was last
//!   configured through MP, or the last motion ended): a segment start fetching a stale
//!   `QP[r+1]` is a buffer underflow — the motion ends where it is and the drive sends the "motion
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
    /// `QP[read + 2]`, already fetched by a drive reading one point ahead.
    ahead: Option<f64>,
    /// Slopes at both ends, counts per segment.
    slope_from: f64,
    slope_to: f64,
}

impl Segment {
    /// The segment after this one, at read index `read` and ending at `to`: it starts where and with the slope this one
    /// ends, and its end slope is the backward difference at `to` (**ASSUMED**, see the module
    /// comment).
    fn next(&self, read: u16, to: f64, ahead: Option<f64>) -> Self {
        Self {
            read,
            sample: 0,
            from: self.to,
            to,
            ahead,
            slope_from: self.slope_to,
            slope_to: backward_slope(self.from, self.to, to),
        }
    }

    /// The position at fraction `u` of the segment.
    fn at(&self, u: f64) -> f64 {
        let (u2, u3) = (u * u, u * u * u);
        (2.0 * u3 - 3.0 * u2 + 1.0) * self.from
            + (u3 - 2.0 * u2 + u) * self.slope_from
            + (-2.0 * u3 + 3.0 * u2) * self.to
            + (u3 - u2) * self.slope_to
    }
}

/// The slope (counts per segment) at a knot `at` after knots `before_last` and `last`: the
/// second-order backward difference, exact for constant acceleration.
fn backward_slope(before_last: f64, last: f64, at: f64) -> f64 {
    (3.0 * at - 4.0 * last + before_last) / 2.0
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
    /// No `PT=k`, bad MP values, or `QP[k]`, `QP[k+1]` not both written.
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
    /// Fetch one point further than the manual says (the previous model).
    reads_ahead: bool,
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
            reads_ahead: false,
        }
    }
}

impl PtTable {
    /// An empty table. With `reads_ahead` its motion fetches one point further than the
    /// manual says: `QP[r+2]` when segment `r` starts (`BG` fetches three points), the
    /// previous simulation's fetch rule, kept to show what a drive that reads ahead costs.
    pub fn new(reads_ahead: bool) -> Self {
        Self {
            reads_ahead,
            ..Self::default()
        }
    }

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
        let (Some(from), Some(to)) = (self.fetch(start), self.fetch(second)) else {
            return Err(BeginError::BadSetup);
        };
        let ahead = if self.reads_ahead {
            let third = self.next(second).ok_or(BeginError::BadSetup)?;
            Some(self.fetch(third).ok_or(BeginError::BadSetup)?)
        } else {
            None
        };
        // From rest: the point before the start is taken as the start.
        self.segment = Some(Segment {
            read: start,
            sample: 0,
            from,
            to,
            ahead,
            slope_from: 0.0,
            slope_to: backward_slope(from, from, to),
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
        // Segment boundary: QP[read + 1] is reached and becomes the start, and the new end
        // QP[read + 2] is fetched (QP[read + 3] by a drive reading ahead).
        let reached = self.next(segment.read);
        let end = reached.and_then(|r| self.next(r));
        let fetch = if self.reads_ahead {
            end.and_then(|r| self.next(r))
        } else {
            end
        };
        let emergency = match (reached, fetch) {
            (Some(reached), Some(fetch)) => {
                self.record_latency(reached, now);
                let next = self.fetch(fetch).map(|fetched| match segment.ahead {
                    Some(to) => segment.next(reached, to, Some(fetched)),
                    None => segment.next(reached, fetched, None),
                });
                match next {
                    Some(next) => {
                        self.segment = Some(next);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A cyclic ring `QP[1..=6]` of `samples` per segment holding `points` from `QP[1]`, armed
    /// at `QP[1]`.
    fn table(reads_ahead: bool, samples: i32, points: &[i32]) -> PtTable {
        let mut table = PtTable::new(reads_ahead);
        for (i, value) in [(1, 1), (2, 6), (3, 1), (4, samples), (5, 0)] {
            assert!(table.set_mp(i, value));
        }
        for (i, &p) in (1..).zip(points) {
            table.write(i, p, 0).unwrap();
        }
        assert!(table.arm(1));
        table
    }

    fn fresh(table: &PtTable, i: u16) -> bool {
        table.entry(i).is_some_and(|e| e.fresh)
    }

    #[test]
    fn each_segment_start_fetches_only_its_own_end() {
        let mut table = table(false, 4, &[0, 10, 20, 30]);
        table.begin(0).unwrap();
        // BG fetched QP[1] and QP[2]; QP[3] is still to come.
        assert!(!fresh(&table, 2) && fresh(&table, 3));
        for _ in 0..4 {
            table.sample(0, false);
        }
        // Segment 2 started: it fetched QP[3], not QP[4].
        assert_eq!(table.read_index(), 2);
        assert!(!fresh(&table, 3) && fresh(&table, 4));
    }

    #[test]
    fn a_drive_reading_ahead_fetches_one_point_further() {
        let mut table = table(true, 4, &[0, 10, 20, 30]);
        table.begin(0).unwrap();
        assert!(!fresh(&table, 3) && fresh(&table, 4));
        // It cannot begin on two points.
        let mut short = self::table(true, 4, &[0, 10]);
        assert_eq!(short.begin(0), Err(BeginError::BadSetup));
    }

    #[test]
    fn constant_acceleration_is_followed_exactly_once_two_knots_lie_behind() {
        // QP[k] = 100 (k − 1)²: from knot 3 on the backward slopes are exact, so segment 3→4
        // is the parabola itself; the first two segments start from rest.
        let samples = 8;
        let mut table = table(false, samples, &[0, 100, 400, 900, 1600]);
        table.begin(0).unwrap();
        let mut profile = std::vec::Vec::new();
        for _ in 0..3 * samples {
            profile.push(table.sample(0, false).reference.unwrap());
        }
        for (k, &p) in profile.iter().enumerate().skip(2 * samples as usize) {
            let u = (k + 1) as f64 / f64::from(samples);
            assert!((p - 100.0 * u * u).abs() < 1e-9, "{k}: {p}");
        }
        // Every segment ends on its point.
        let per = samples as usize;
        assert_eq!(
            [profile[per - 1], profile[2 * per - 1], profile[3 * per - 1]],
            [100.0, 400.0, 900.0]
        );
    }
}
