//! Deserialising fixed-capacity lists with an error that states the capacity.

use core::fmt;
use core::marker::PhantomData;

use heapless::Vec;
use serde::de::{Deserialize, Deserializer, Error, SeqAccess, Visitor};

/// Deserialises a `heapless::Vec<T, N>`; more than `N` entries gives
/// "invalid length 9, expected at most 8 entries" instead of heapless's generic message.
pub(super) fn deserialize<'de, D, T, const N: usize>(d: D) -> Result<Vec<T, N>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    struct Bounded<T, const N: usize>(PhantomData<T>);

    impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Bounded<T, N> {
        type Value = Vec<T, N>;

        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "at most {N} entries")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut out = Vec::new();
            // Bounded: the loop ends at the first element that does not fit.
            while let Some(item) = seq.next_element()? {
                if out.push(item).is_err() {
                    return Err(A::Error::invalid_length(N + 1, &self));
                }
            }
            Ok(out)
        }
    }

    d.deserialize_seq(Bounded::<T, N>(PhantomData))
}
