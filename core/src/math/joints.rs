//! A joint vector of fixed capacity.

use core::ops::{Deref, DerefMut};

use crate::MAX_JOINTS;

/// Joint positions (rad for revolute joints, m for prismatic joints), up to [`MAX_JOINTS`].
///
/// `Copy` and allocation-free, so the control step can pass it around by value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Joints {
    values: [f64; MAX_JOINTS],
    len: usize,
}

impl Joints {
    /// `n` zeros (`n` is capped at [`MAX_JOINTS`]).
    pub fn zeros(n: usize) -> Self {
        Self {
            values: [0.0; MAX_JOINTS],
            len: n.min(MAX_JOINTS),
        }
    }

    /// The first `n` entries of `values` (`n` capped at [`MAX_JOINTS`]), the rest zeroed: a
    /// fixed-size move, where a slice's copy is a `memcpy` call.
    pub fn from_array(mut values: [f64; MAX_JOINTS], n: usize) -> Self {
        let len = n.min(MAX_JOINTS);
        // A select per entry, not a fill (which becomes a `memset` call).
        for (i, v) in values.iter_mut().enumerate() {
            *v = if i < len { *v } else { 0.0 };
        }
        Self { values, len }
    }

    /// A copy of `values`, or `None` if it holds more than [`MAX_JOINTS`] entries.
    pub fn from_slice(values: &[f64]) -> Option<Self> {
        let mut joints = Self::zeros(values.len());
        if values.len() > MAX_JOINTS {
            return None;
        }
        joints.copy_from_slice(values);
        Some(joints)
    }

    /// The underlying fixed array; entries past `len()` are zero.
    pub fn as_array(&self) -> &[f64; MAX_JOINTS] {
        &self.values
    }

    /// True if every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.iter().all(|v| v.is_finite())
    }
}

impl Deref for Joints {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        self.values.get(..self.len).unwrap_or(&[])
    }
}

impl DerefMut for Joints {
    fn deref_mut(&mut self) -> &mut [f64] {
        self.values.get_mut(..self.len).unwrap_or(&mut [])
    }
}
