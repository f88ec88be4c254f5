//! Keyframe windows: one preintegration between each pair of consecutive boundary times, the
//! windows run in parallel (rayon; results do not depend on the thread count).
//!
//! A boundary between two samples is a point of the scheme's own signal model, so that the
//! windows cover the samples exactly once and their merge equals one preintegration over the
//! whole span: in the euler scheme the sample before it (held until the boundary, as
//! `integrateMeasurement(a_k, ω_k, b − t_k)` in GTSAM), in the midpoint scheme the linear
//! interpolation of its two neighbours. With saturation flags, a boundary point carries the flags
//! of the sample it is (euler: the held one) or, when interpolated, of either neighbour.

use std::cmp::Ordering;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::{clipped_at, ClipMask, Clipped, Preintegrator, Scheme};
use crate::error::{Error, Result};
use crate::imu::Samples;

/// `template` (an empty preintegrator: scheme, bias, noise, bias walk) run over each window
/// `[boundaries[m], boundaries[m + 1]]` of `samples`.
pub fn preintegrate_windows(
    samples: &Samples<'_>,
    boundaries: &[f64],
    template: &Preintegrator,
) -> Result<Vec<Preintegrator>> {
    preintegrate_windows_clipped(samples, None, boundaries, template)
}

/// [`preintegrate_windows`] with per-sample saturation flags (`None`: nothing clipped), applied as
/// in [`Preintegrator::integrate_samples_clipped`].
pub fn preintegrate_windows_clipped(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    boundaries: &[f64],
    template: &Preintegrator,
) -> Result<Vec<Preintegrator>> {
    samples.validate()?;
    let n = samples.t.len();
    if let Some(mask) = clipped {
        mask.check(n)?;
    }
    check_boundaries(boundaries, samples.t[0], samples.t[n - 1])?;
    let windows: Vec<Preintegrator> = boundaries
        .par_windows(2)
        .map(|w| window(samples, clipped, w[0], w[1], template))
        .collect();
    // Finite samples can still overflow a window (a noise density of 1e200, squared): name the
    // sample that ends the first such window.
    if let Some(m) = windows.iter().position(|w| !w.is_finite()) {
        let end = samples.t.partition_point(|&x| x < boundaries[m + 1]);
        return Err(Error::Overflow { index: end.min(n - 1) });
    }
    Ok(windows)
}

fn check_boundaries(b: &[f64], first: f64, last: f64) -> Result<()> {
    let bad = |expected: &'static str, got: String| {
        Err(Error::Parameter {
            name: "boundaries",
            expected,
            got,
        })
    };
    if b.len() < 2 {
        return bad("at least two times", format!("{} times", b.len()));
    }
    if let Some(k) = b
        .windows(2)
        .position(|w| w[1].partial_cmp(&w[0]) != Some(Ordering::Greater))
    {
        return bad(
            "strictly increasing",
            format!("{} then {} at index {}", b[k], b[k + 1], k + 1),
        );
    }
    // No NaN is left (it compares as unordered above).
    if b[0] < first || b[b.len() - 1] > last {
        let span = format!("[{}, {}] outside the samples' [{first}, {last}]", b[0], b[b.len() - 1]);
        return bad("times within the samples' span", span);
    }
    Ok(())
}

/// A point of the signal: `(accel, gyro, flags)`.
type Point = (Vector3<f64>, Vector3<f64>, Clipped);

/// The sample at time `x` in `[t_k, t_k+1]` under the scheme's signal model (module docs).
fn at(samples: &Samples<'_>, clipped: Option<&ClipMask<'_>>, k: usize, x: f64, scheme: Scheme) -> Point {
    let point = |k: usize| (samples.accel_at(k), samples.gyro_at(k), clipped_at(clipped, k));
    let (a0, w0, c0) = point(k);
    if scheme == Scheme::Euler || x == samples.t[k] {
        return (a0, w0, c0);
    }
    let (a1, w1, c1) = point(k + 1);
    if x == samples.t[k + 1] {
        return (a1, w1, c1); // exactly the sample, so that adjacent windows share it bit for bit
    }
    let s = (x - samples.t[k]) / (samples.t[k + 1] - samples.t[k]);
    // A value interpolated from a clipped reading is as unknown as that reading.
    let c = Clipped {
        gyro: c0.gyro || c1.gyro,
        accel: c0.accel || c1.accel,
    };
    (a0 + (a1 - a0) * s, w0 + (w1 - w0) * s, c)
}

fn window(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    lo: f64,
    hi: f64,
    template: &Preintegrator,
) -> Preintegrator {
    let t = samples.t;
    let scheme = template.scheme;
    let mut p = template.clone();
    // Samples strictly inside (lo, hi); k0 is the last sample at or before lo.
    let inside = t.partition_point(|&x| x <= lo)..t.partition_point(|&x| x < hi);
    let k0 = inside.start - 1;
    let mut current = at(samples, clipped, k0, lo, scheme);
    let mut time = lo;
    if scheme == Scheme::Midpoint {
        p.integrate_measurement_clipped(&current.0, &current.1, 0.0, current.2);
    }
    let mut add = |p: &mut Preintegrator, next_time: f64, next: Point| {
        // euler: the sample at the start is held; midpoint: the sample at the end is given.
        let (sa, sw, sc) = if scheme == Scheme::Euler { current } else { next };
        p.integrate_measurement_clipped(&sa, &sw, next_time - time, sc);
        (time, current) = (next_time, next);
    };
    for (k, &tk) in t.iter().enumerate().take(inside.end).skip(inside.start) {
        add(
            &mut p,
            tk,
            (samples.accel_at(k), samples.gyro_at(k), clipped_at(clipped, k)),
        );
    }
    add(&mut p, hi, at(samples, clipped, inside.end - 1, hi, scheme));
    p
}
