//! The replay reservation in two flash sectors (the board's [`ReplayStore`]): a log of 32-byte
//! records (the STM32H7's flash word), written one after the other, the two sectors used in
//! turn so that one is always erased and ready.
//!
//! * **Write.** [`keep`](ReplayStore::keep) programs the next record of the active sector:
//!   one flash word, no erase. A full sector hands over to the other one, erased at the start.
//! * **Start.** [`FlashLog::open`] reads both sectors (the newest valid record wins), erases the
//!   other sector if it is not, and moves the reservation over to it if the active one is half
//!   full, so that every run has at least a sector and a half of records. Erasing takes seconds
//!   on the board: `open` runs before the control loop and its watchdog.
//! * **Power loss.** A record is valid only if its magic and its value's complement match: a
//!   torn write is skipped, and the record before it (written before anything above it was
//!   served) still holds.
//!
//! Wear, at one write per [`RESERVE_AHEAD`](super::RESERVE_AHEAD) of signed use: docs/safety.md.

use super::replay::ReplayStore;

/// Bytes per record (one flash word on the STM32H7).
pub const RECORD_LEN: usize = 32;

/// What a valid record starts with.
const MAGIC: [u8; 4] = *b"AGR1";

/// Two flash sectors of records: what the board's flash driver provides.
pub trait FlashSectors {
    /// Records per sector.
    fn records(&self) -> u32;
    /// Record `record` of sector `sector` (0 or 1); `None` if it cannot be read.
    fn read(&mut self, sector: u8, record: u32) -> Option<[u8; RECORD_LEN]>;
    /// Programs record `record` of `sector` (erased before); `false` if that failed.
    fn write(&mut self, sector: u8, record: u32, bytes: &[u8; RECORD_LEN]) -> bool;
    /// Erases `sector`; `false` if that failed.
    fn erase(&mut self, sector: u8) -> bool;
}

/// The reservation's log in two sectors.
#[derive(Clone, Debug)]
pub struct FlashLog<F> {
    flash: F,
    /// The sector written to.
    active: u8,
    /// Its next free record.
    next: u32,
    /// The reservation found at the start.
    loaded: u64,
}

impl<F: FlashSectors> FlashLog<F> {
    /// Opens the log in `flash`: the newest reservation, and a sector and a half free to write
    /// (erasing as needed; seconds on the board).
    pub fn open(mut flash: F) -> Self {
        let [(a, a_free), (b, b_free)] = [0, 1].map(|s| scan(&mut flash, s));
        let active = u8::from(b > a);
        let (loaded, free) = if active == 1 {
            (b.unwrap_or(0), b_free)
        } else {
            (a.unwrap_or(0), a_free)
        };
        let other = active ^ 1;
        let mut log = Self {
            flash,
            active,
            next: free,
            loaded,
        };
        // Every record checked: an erase cut by a power loss may leave the first erased only.
        if !log.erased(other, log.flash.records()) {
            let _ = log.flash.erase(other);
        }
        if log.next >= log.flash.records() / 2
            && log.flash.write(other, 0, &encode(loaded))
            && log.flash.erase(active)
        {
            log.active = other;
            log.next = 1;
        }
        log
    }

    /// The flash, for a shell that reads what was written (tests).
    pub fn flash(&self) -> &F {
        &self.flash
    }

    /// True if `sector`'s first `records` records are erased.
    fn erased(&mut self, sector: u8, records: u32) -> bool {
        (0..records).all(|k| {
            self.flash
                .read(sector, k)
                .is_some_and(|r| r.iter().all(|b| *b == 0xff))
        })
    }
}

impl<F: FlashSectors> ReplayStore for FlashLog<F> {
    fn load(&mut self) -> u64 {
        self.loaded
    }

    fn keep(&mut self, reserved: u64) -> bool {
        if self.next >= self.flash.records() {
            let other = self.active ^ 1;
            // Checked whole at the start (records are written in order): the first suffices.
            if !self.erased(other, 1) {
                return false;
            }
            self.active = other;
            self.next = 0;
        }
        let written = self.flash.write(self.active, self.next, &encode(reserved));
        self.next = self.next.saturating_add(1);
        written
    }
}

/// The newest valid value in `sector`, and its first erased record (its end if full).
fn scan(flash: &mut impl FlashSectors, sector: u8) -> (Option<u64>, u32) {
    let records = flash.records();
    let mut newest = None;
    for k in 0..records {
        let Some(record) = flash.read(sector, k) else {
            continue;
        };
        if record.iter().all(|b| *b == 0xff) {
            return (newest, k);
        }
        newest = newest.max(decode(&record));
    }
    (newest, records)
}

/// A record: the magic, the value and its complement (little-endian), zeros.
fn encode(value: u64) -> [u8; RECORD_LEN] {
    let mut record = [0; RECORD_LEN];
    let (low, high) = (value.to_le_bytes(), (!value).to_le_bytes());
    let parts = MAGIC.iter().chain(&low).chain(&high);
    record.iter_mut().zip(parts).for_each(|(r, p)| *r = *p);
    record
}

/// The value of a valid record.
fn decode(record: &[u8; RECORD_LEN]) -> Option<u64> {
    let word = |at: usize| -> Option<u64> {
        let bytes: [u8; 8] = record.get(at..at + 8)?.try_into().ok()?;
        Some(u64::from_le_bytes(bytes))
    };
    let value = word(4)?;
    (record.get(..4) == Some(&MAGIC[..]) && word(12)? == !value).then_some(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two sectors of 8 records of NOR flash, counting erases: an erase sets every bit,
    /// programming only clears bits, one 32-byte flash word at a time and only an erased one
    /// (the STM32H7 refuses to program a word twice). A power cut at operation `cut` (counted
    /// from 0) tears it, a write leaving the first `torn` bytes of its word programmed and the
    /// rest erased, an erase setting the first half of the sector only; after it nothing
    /// changes until [`restored`](Self::restored).
    #[derive(Clone, Debug)]
    struct Nor {
        sectors: [[[u8; RECORD_LEN]; 8]; 2],
        erases: [u32; 2],
        operations: u32,
        cut: Option<u32>,
        torn: usize,
    }

    impl Nor {
        fn new() -> Self {
            Self {
                sectors: [[[0xff; RECORD_LEN]; 8]; 2],
                erases: [0; 2],
                operations: 0,
                cut: None,
                torn: 0,
            }
        }

        /// Power on: the flash as the cut left it.
        fn restored(&self) -> Self {
            Self {
                cut: None,
                ..self.clone()
            }
        }

        /// Counts an operation: `Some(true)` if it completes, `Some(false)` if power is cut
        /// during it, `None` if power is gone.
        fn power(&mut self) -> Option<bool> {
            let k = self.operations;
            self.operations += 1;
            match self.cut {
                Some(cut) if k > cut => None,
                Some(cut) => Some(k != cut),
                None => Some(true),
            }
        }
    }

    impl FlashSectors for Nor {
        fn records(&self) -> u32 {
            8
        }
        fn read(&mut self, sector: u8, record: u32) -> Option<[u8; RECORD_LEN]> {
            Some(self.sectors[usize::from(sector)][record as usize])
        }
        fn write(&mut self, sector: u8, record: u32, bytes: &[u8; RECORD_LEN]) -> bool {
            let word = &mut self.sectors[usize::from(sector)][record as usize];
            if word.iter().any(|b| *b != 0xff) {
                return false;
            }
            let Some(whole) = self.power() else {
                return false;
            };
            let word = &mut self.sectors[usize::from(sector)][record as usize];
            let programmed = if whole { RECORD_LEN } else { self.torn };
            for (w, b) in word.iter_mut().zip(bytes).take(programmed) {
                *w &= *b;
            }
            whole
        }
        fn erase(&mut self, sector: u8) -> bool {
            let Some(whole) = self.power() else {
                return false;
            };
            let records = if whole { 8 } else { 4 };
            for word in self.sectors[usize::from(sector)].iter_mut().take(records) {
                *word = [0xff; RECORD_LEN];
            }
            self.erases[usize::from(sector)] += 1;
            whole
        }
    }

    /// Writes 1, 2, ... with a restart after every `restart_every` writes (`writes` in all),
    /// on `flash`; the last value written whole (its write reported done) and the flash.
    fn run(flash: Nor, writes: u64, restart_every: u64) -> (u64, Nor) {
        let mut log = FlashLog::open(flash);
        let mut kept = 0;
        for value in 1..=writes {
            if log.keep(value) {
                kept = value;
            }
            if value % restart_every == 0 {
                log = FlashLog::open(log.flash().clone());
            }
        }
        (kept, log.flash().clone())
    }

    #[test]
    fn the_newest_reservation_survives_restarts_and_sectors_take_turns() {
        let mut log = FlashLog::open(Nor::new());
        assert_eq!(log.load(), 0);
        let mut value = 1_000;
        let mut flash = log.flash().clone();
        for restart in 0..10 {
            for _ in 0..restart % 7 + 1 {
                value += 200_000;
                assert!(log.keep(value), "restart {restart}");
            }
            flash = log.flash().clone();
            log = FlashLog::open(flash.clone());
            assert_eq!(log.load(), value, "restart {restart}");
        }
        // A sector and a half free after every start: 12 writes in a row fit.
        for _ in 0..12 {
            value += 1;
            assert!(log.keep(value));
        }
        assert_eq!(FlashLog::open(log.flash().clone()).load(), value);
        // A torn record (power lost while programming) is skipped; the one before holds.
        let erases = flash.erases[0] + flash.erases[1];
        assert!(erases <= 10, "sectors erased only at starts: {erases}");
    }

    #[test]
    fn a_power_cut_at_any_write_or_erase_never_lowers_the_value_found_at_the_next_start() {
        let (writes, restart_every) = (40, 5);
        let operations = run(Nor::new(), writes, restart_every).1.operations;
        for cut in 0..operations {
            for torn in [0, 4, 12, 19, 20, 31] {
                let flash = Nor {
                    cut: Some(cut),
                    torn,
                    ..Nor::new()
                };
                let (kept, cut_flash) = run(flash, writes, restart_every);
                let mut log = FlashLog::open(cut_flash.restored());
                let found = log.load();
                assert!(
                    (kept..=writes).contains(&found),
                    "cut at {cut}, {torn} bytes: {found}, last written whole {kept}"
                );
                // The log goes on: a sector and a half of values kept, found after a restart.
                let (more, _) = (writes + 1..=writes + 12).fold((found, ()), |(_, ()), v| {
                    assert!(log.keep(v), "cut at {cut}, {torn} bytes: writing {v}");
                    (v, ())
                });
                assert_eq!(FlashLog::open(log.flash().clone()).load(), more);
            }
        }
    }

    #[test]
    fn records_are_the_magic_the_value_and_its_complement() {
        let record = encode(0x0123_4567_89ab_cdef);
        assert_eq!(&record[..4], b"AGR1");
        assert_eq!(decode(&record), Some(0x0123_4567_89ab_cdef));
        assert_eq!(decode(&[0xff; RECORD_LEN]), None);
        let mut bad = record;
        bad[15] ^= 1;
        assert_eq!(decode(&bad), None);
    }
}
