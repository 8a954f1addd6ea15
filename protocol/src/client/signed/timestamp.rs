//! The signature's timestamp: 48 bits of 10 µs since 2015-01-01 00:00:00 UTC (MAVLink's unit
//! and epoch), which last until the year 2104.

/// The epoch, in seconds since 1970-01-01 UTC.
pub const TIMESTAMP_EPOCH_UNIX: u64 = 1_420_070_400;
/// One timestamp step, in microseconds.
pub const TIMESTAMP_UNIT_US: u64 = 10;
/// The largest timestamp (48 bits).
pub const TIMESTAMP_MAX: u64 = (1 << 48) - 1;

/// The timestamp of a wall-clock time given in microseconds since 1970-01-01 UTC (0 before the
/// epoch, [`TIMESTAMP_MAX`] after it runs out).
pub fn timestamp_from_unix_us(unix_us: u64) -> u64 {
    let since = unix_us.saturating_sub(TIMESTAMP_EPOCH_UNIX * 1_000_000);
    (since / TIMESTAMP_UNIT_US).min(TIMESTAMP_MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_epoch_is_2015_and_the_unit_10_microseconds() {
        assert_eq!(timestamp_from_unix_us(0), 0);
        assert_eq!(timestamp_from_unix_us(TIMESTAMP_EPOCH_UNIX * 1_000_000), 0);
        // 2026-01-01 00:00:00 UTC is 1,767,225,600 s after 1970.
        let t = timestamp_from_unix_us(1_767_225_600_000_000 + 25);
        assert_eq!(t, (1_767_225_600 - 1_420_070_400) * 100_000 + 2);
        assert_eq!(timestamp_from_unix_us(u64::MAX), TIMESTAMP_MAX);
    }
}
