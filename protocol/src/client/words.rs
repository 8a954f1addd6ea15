//! The building blocks of the texts' grammar, each written and read in one place: fixed
//! phrases, unsigned decimals, values in thousandths.

use core::fmt;

/// The phrase of `value` in a table of fixed phrases.
pub(super) fn phrase<T: PartialEq>(table: &[(T, &'static str)], value: &T) -> Option<&'static str> {
    table.iter().find(|(v, _)| v == value).map(|(_, p)| *p)
}

/// The value whose phrase `text` is (the first, where several share one).
pub(super) fn value_of<T: Copy>(table: &[(T, &'static str)], text: &str) -> Option<T> {
    table.iter().find(|(_, p)| *p == text).map(|(v, _)| *v)
}

/// An unsigned decimal number of ASCII digits only (no sign, no spaces).
pub(super) fn decimal<T: core::str::FromStr>(s: &str) -> Option<T> {
    let digits = !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    digits.then(|| s.parse().ok()).flatten()
}

/// A value in thousandths, printed with three decimals (`-1.745`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Milli(pub(super) i32);

impl Milli {
    /// Reads `-1.745` back: an optional minus, digits, a point, exactly three digits.
    pub(super) fn parse(s: &str) -> Option<Self> {
        let (negative, magnitude) = match s.strip_prefix('-') {
            Some(m) => (true, m),
            None => (false, s),
        };
        let (whole, thousandths) = magnitude.split_once('.')?;
        if thousandths.len() != 3 {
            return None;
        }
        let whole: i64 = decimal(whole)?;
        let thousandths: i64 = decimal(thousandths)?;
        let value = whole.checked_mul(1000)?.checked_add(thousandths)?;
        let value = if negative { -value } else { value };
        i32::try_from(value).ok().map(Self)
    }
}

impl fmt::Display for Milli {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sign = if self.0 < 0 { "-" } else { "" };
        let magnitude = self.0.unsigned_abs();
        write!(f, "{sign}{}.{:03}", magnitude / 1000, magnitude % 1000)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousandths_read_back_what_they_print() {
        for v in [0, 1, -1, 785, -1745, 2967, 1_600, i32::MAX, i32::MIN] {
            assert_eq!(Milli::parse(&Milli(v).to_string()), Some(Milli(v)), "{v}");
        }
        assert_eq!(Milli(-1745).to_string(), "-1.745");
        for bad in [
            "1.5",
            "1.7450",
            "+1.745",
            "1,745",
            ".745",
            "-",
            "1.-45",
            "9999999.999",
        ] {
            assert_eq!(Milli::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn decimals_are_digits_only() {
        assert_eq!(decimal::<u8>("05"), Some(5));
        assert_eq!(decimal::<u8>("+5"), None);
        assert_eq!(decimal::<u8>(""), None);
        assert_eq!(decimal::<u8>("256"), None);
    }
}
