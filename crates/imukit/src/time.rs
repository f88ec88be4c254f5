//! Timestamps: validation and step sizes.
//!
//! Times are `f64` seconds. Bindings convert int64 nanoseconds (EuRoC style) to seconds relative
//! to the first sample before calling in, so no precision is lost to a large epoch offset: an
//! hour of data keeps sub-nanosecond resolution.

use crate::{Error, Result};

/// Checks that `t` is finite and strictly increasing; the error names the first offending index
/// (the later sample of a non-increasing pair).
pub fn check_increasing(t: &[f64]) -> Result<()> {
    if let Some(index) = t.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite { index });
    }
    if let Some(k) = t.windows(2).position(|w| w[1] <= w[0]) {
        return Err(Error::NonIncreasingTime {
            index: k + 1,
            dt: t[k + 1] - t[k],
        });
    }
    Ok(())
}
