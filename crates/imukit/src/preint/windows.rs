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

#[cfg(target_arch = "x86_64")]
use super::lanes;
use super::{clipped_at, ClipMask, Clipped, End, Ends, Preintegrator, Scheme};
use crate::error::{try_vec, Cancel, Error, Result};
use crate::imu::Samples;

/// `template` (an empty preintegrator: scheme, bias, noise, bias walk) run over each window
/// `[boundaries\[m\], boundaries[m + 1]]` of `samples`.
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
    preintegrate_windows_clipped_cancellable(samples, clipped, (boundaries, template), &Cancel::new())
}

/// [`preintegrate_windows_clipped`] of `(boundaries, template)`, stopping with
/// [`Error::Interrupted`] when `cancel` is set (polled before each block of windows: at most 4096 and about 2^17 samples).
pub fn preintegrate_windows_clipped_cancellable(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    (boundaries, template): (&[f64], &Preintegrator),
    cancel: &Cancel,
) -> Result<Vec<Preintegrator>> {
    check_inputs(samples, clipped, boundaries)?;
    // One state (a few kB) per window: 20,000,000 windows would need 51.7 GB.
    let m = boundaries.len() - 1;
    let mut windows = try_vec(m, "windows").map_err(|e| e.in_argument("boundaries"))?;
    let block = windows_per_block(samples.t.len(), m);
    for first in (0..m).step_by(block) {
        cancel.check(0)?;
        let edges = &boundaries[first..(first + block + 1).min(m + 1)];
        windows.extend(run_block(samples, clipped, edges, template));
    }
    check_windows(samples, boundaries, 0, &windows)?;
    Ok(windows)
}

/// The buffers that [`preintegrate_windows_into`] fills: one row per window (M = boundaries − 1),
/// matrices row-major. `covariance_combined` is filled when given (the template must then track
/// the bias walk).
#[derive(Debug)]
pub struct WindowsOut<'a> {
    /// `ΔR` (M, 3, 3).
    pub delta_rotation: &'a mut [[[f64; 3]; 3]],
    /// `Δv` (M, 3) [m/s].
    pub delta_velocity: &'a mut [[f64; 3]],
    /// `Δp` (M, 3) \[m\].
    pub delta_position: &'a mut [[f64; 3]],
    /// `Δt` (M,) \[s\].
    pub delta_t: &'a mut [f64],
    /// Covariance of `[δθ, δv, δp]` (M, 9, 9).
    pub covariance: &'a mut [[[f64; 9]; 9]],
    /// Bias Jacobian, rows `[θ, v, p]`, columns `[b_g, b_a]` (M, 9, 6).
    pub bias_jacobian: &'a mut [[[f64; 6]; 9]],
    /// Covariance of `[δθ, δv, δp, δb_g, δb_a]` (M, 15, 15), when wanted.
    pub covariance_combined: Option<&'a mut [[[f64; 15]; 15]]>,
}

/// Windows computed at once before they are written out: bounds the memory of the states (a few
/// kB each) while leaving every core enough windows to share.
const WINDOWS_PER_BLOCK: usize = 4096;

/// Samples a block should hold at most, so that an interrupt is seen within a few tens of
/// milliseconds even for long windows (4096 windows of 100 samples with the bias walk took ~1 s on
/// a loaded machine).
const SAMPLES_PER_BLOCK: usize = 1 << 17;

/// Windows per block for `m` windows over `n` samples: [`WINDOWS_PER_BLOCK`], fewer when the
/// windows are long (never fewer than 64, so that the cores still share a block).
fn windows_per_block(n: usize, m: usize) -> usize {
    let per_window = n.div_ceil(m.max(1)).max(1);
    (SAMPLES_PER_BLOCK / per_window).clamp(64, WINDOWS_PER_BLOCK)
}

/// [`preintegrate_windows_clipped`] written into `out` (one row per window) instead of returned as
/// states: the kernel behind one call for a whole record of windows. On an error the rows of
/// `out` are unspecified.
pub fn preintegrate_windows_into(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    boundaries: &[f64],
    template: &Preintegrator,
    out: WindowsOut<'_>,
) -> Result<()> {
    preintegrate_windows_cancellable(samples, clipped, (boundaries, template), out, &Cancel::new())
}

/// [`preintegrate_windows_into`] of `(boundaries, template)`, stopping with
/// [`Error::Interrupted`] when `cancel` is set (polled before each block of windows: at most 4096 and about 2^17 samples).
pub fn preintegrate_windows_cancellable(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    (boundaries, template): (&[f64], &Preintegrator),
    out: WindowsOut<'_>,
    cancel: &Cancel,
) -> Result<()> {
    check_inputs(samples, clipped, boundaries)?;
    let m = boundaries.len() - 1;
    let lengths = [
        out.delta_rotation.len(),
        out.delta_velocity.len(),
        out.delta_position.len(),
        out.delta_t.len(),
        out.covariance.len(),
        out.bias_jacobian.len(),
        out.covariance_combined.as_ref().map_or(m, |c| c.len()),
    ];
    if let Some(&output) = lengths.iter().find(|&&len| len != m) {
        return Err(Error::RowCount { input: m, output });
    }
    if out.covariance_combined.is_some() && template.covariance_combined().is_none() {
        return Err(Error::Parameter {
            name: "template",
            expected: "a preintegrator tracking the bias walk for a combined covariance",
            got: "one without".to_string(),
        });
    }
    let WindowsOut {
        delta_rotation,
        delta_velocity,
        delta_position,
        delta_t,
        covariance,
        bias_jacobian,
        mut covariance_combined,
    } = out;
    let block = windows_per_block(samples.t.len(), m);
    for first in (0..m).step_by(block) {
        cancel.check(0)?;
        let edges = &boundaries[first..(first + block + 1).min(m + 1)];
        let windows = run_block(samples, clipped, edges, template);
        check_windows(samples, boundaries, first, &windows)?;
        for (k, p) in windows.iter().enumerate() {
            let row = first + k;
            write_rows(&mut delta_rotation[row], &p.delta_rotation);
            delta_velocity[row] = p.delta_velocity.into();
            delta_position[row] = p.delta_position.into();
            delta_t[row] = p.delta_t;
            write_rows(&mut covariance[row], &p.covariance());
            write_rows(&mut bias_jacobian[row], &p.bias_jacobian());
            if let (Some(rows), Some(c)) = (covariance_combined.as_deref_mut(), p.covariance_combined()) {
                write_rows(&mut rows[row], &c);
            }
        }
    }
    Ok(())
}

/// A matrix into row-major rows.
fn write_rows<const R: usize, const C: usize>(rows: &mut [[f64; C]; R], m: &nalgebra::SMatrix<f64, R, C>) {
    for (r, row) in rows.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = m[(r, c)];
        }
    }
}

fn check_inputs(samples: &Samples<'_>, clipped: Option<&ClipMask<'_>>, boundaries: &[f64]) -> Result<()> {
    samples.validate()?;
    let n = samples.t.len();
    if let Some(mask) = clipped {
        mask.check(n)?;
    }
    check_boundaries(boundaries, samples.t[0], samples.t[n - 1])
}

/// Finite samples can still overflow a window (a noise density of 1e200, squared): names the
/// sample that ends the first such window (`windows` start at window `first`).
fn check_windows(samples: &Samples<'_>, boundaries: &[f64], first: usize, windows: &[Preintegrator]) -> Result<()> {
    match windows.iter().position(|w| !w.is_finite()) {
        None => Ok(()),
        Some(k) => {
            let n = samples.t.len();
            let end = samples.t.partition_point(|&x| x < boundaries[first + k + 1]);
            Err(Error::Overflow { index: end.min(n - 1) })
        }
    }
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

crate::simd_dispatch! {
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
        let whole = span(t, lo, hi);
        let Span { k0, steps, .. } = whole;
        // Samples strictly inside (lo, hi).
        let inside = k0 + 1..k0 + steps;
        let first = at(samples, clipped, k0, lo, scheme);
        let mut current = first;
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
        let last = at(samples, clipped, inside.end - 1, hi, scheme);
        add(&mut p, hi, last);
        p.boundary = boundary(samples, &whole, scheme);
        p
    }
}

/// One euler window as a sequence of intervals: interval j holds sample `k0 + j` from `T(j)` to
/// `T(j + 1)`, with `T(0) = lo`, `T(steps) = hi` and `T(j) = t[k0 + j]` between.
#[derive(Debug, Clone, Copy)]
pub(super) struct Span {
    /// The sample held at `lo` (the last one at or before it).
    pub k0: usize,
    /// The number of intervals.
    pub steps: usize,
    /// Start time.
    pub lo: f64,
    /// End time.
    pub hi: f64,
}

impl Span {
    /// `T(j)`.
    #[inline(always)]
    fn time(&self, t: &[f64], j: usize) -> f64 {
        if j == 0 {
            self.lo
        } else if j == self.steps {
            self.hi
        } else {
            t[self.k0 + j]
        }
    }

    /// `(accel, gyro, h)` of interval j in the euler scheme: the sample held over it.
    #[inline(always)]
    pub fn interval(&self, samples: &Samples<'_>, j: usize) -> (Vector3<f64>, Vector3<f64>, f64) {
        let k = self.k0 + j;
        let h = self.time(samples.t, j + 1) - self.time(samples.t, j);
        (samples.accel_at(k), samples.gyro_at(k), h)
    }

    /// `(accel, gyro, 0)` at the start of a midpoint window (interpolated at `lo`, as [`window`]
    /// takes it), unflagged.
    pub fn start_point(&self, samples: &Samples<'_>) -> (Vector3<f64>, Vector3<f64>, f64) {
        let (a, w, _) = at(samples, None, self.k0, self.lo, Scheme::Midpoint);
        (a, w, 0.0)
    }

    /// `(accel, gyro, h)` of interval j in the midpoint scheme: the point at its end (the next
    /// sample, or the one interpolated at `hi`), unflagged.
    #[inline(always)]
    pub fn end_point(&self, samples: &Samples<'_>, j: usize) -> (Vector3<f64>, Vector3<f64>, f64) {
        let h = self.time(samples.t, j + 1) - self.time(samples.t, j);
        if j + 1 < self.steps {
            let k = self.k0 + j + 1;
            (samples.accel_at(k), samples.gyro_at(k), h)
        } else {
            let (a, w, _) = at(samples, None, self.k0 + self.steps - 1, self.hi, Scheme::Midpoint);
            (a, w, h)
        }
    }
}

/// The intervals of the window `[lo, hi]` (k0: the last sample at or before lo; then one interval
/// per sample strictly inside).
fn span(t: &[f64], lo: f64, hi: f64) -> Span {
    let (start, end) = (t.partition_point(|&x| x <= lo), t.partition_point(|&x| x < hi));
    Span {
        k0: start - 1,
        steps: end - start + 1,
        lo,
        hi,
    }
}

/// The signal at each end of window `s`, which the adjacent window shares (`Preintegrator`'s
/// `boundary`): in euler the samples held at its ends ([`held_ends`]), in midpoint its first and
/// last points.
fn boundary(samples: &Samples<'_>, s: &Span, scheme: Scheme) -> Ends {
    match scheme {
        Scheme::Euler => held_ends(samples, s.k0, s.hi),
        Scheme::Midpoint => {
            let end = |(accel, gyro, _): (Vector3<f64>, Vector3<f64>, f64)| End { t: None, accel, gyro };
            Ends {
                first: Some(end(s.start_point(samples))),
                last: Some(end(s.end_point(samples, s.steps - 1))),
            }
        }
    }
}

/// The signal at each end of an euler window, which the adjacent window shares: the sample held
/// from its start, and the one held at `hi` (the one starting there when `hi` is a sample time).
fn held_ends(samples: &Samples<'_>, k0: usize, hi: f64) -> Ends {
    let held = samples.t.partition_point(|&x| x <= hi) - 1;
    let end = |k: usize| End {
        t: None,
        accel: samples.accel_at(k),
        gyro: samples.gyro_at(k),
    };
    Ends {
        first: Some(end(k0)),
        last: Some(end(held)),
    }
}

/// Windows per bundle of the SIMD lanes (`lanes/`): batches cut a long sequence into a multiple of
/// it.
pub(super) const BUNDLE: usize = 4;

/// How many of `n` windows (sorted by length) go into the lanes: all but a last bundle too small to
/// pay. A step of the lanes costs about the same whatever number of them carry a window: on AVX2,
/// 1.7 (euler) and 2.4 (midpoint) steps of the per-window kernel (docs/performance.md, "Structure
/// of arrays: windows in SIMD lanes": 69 against 165 and 129 against 215 ns a window-sample, four
/// lanes). So one window runs faster alone in either scheme, and two in the midpoint scheme (one
/// window over a record ran 2–3× faster alone: "One or two windows do not pay for the lanes").
pub(super) fn bundled(n: usize, scheme: Scheme) -> usize {
    let fewest = match scheme {
        Scheme::Euler => 2,
        Scheme::Midpoint => 3,
    };
    let last = n % BUNDLE;
    if last < fewest {
        n - last
    } else {
        n
    }
}

/// The windows between consecutive `edges`, in order, in parallel: windows without a clipped
/// sample in SIMD lanes on the AVX paths (`lanes/`), the others on the per-window kernel.
pub(super) fn run_block(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    edges: &[f64],
    template: &Preintegrator,
) -> Vec<Preintegrator> {
    #[cfg(target_arch = "x86_64")]
    if let Some(k) = lanes::lanes() {
        return run_block_in_lanes(samples, clipped, edges, template, k);
    }
    edges
        .par_windows(2)
        .map(|w| window(samples, clipped, w[0], w[1], template))
        .collect()
}

/// [`run_block`] with the lanes `k`: the unflagged windows bundled in order of length, so that a
/// bundle's windows end together (the grouping does not depend on the thread count); a last
/// bundle too small to pay ([`bundled`]; the longest windows) runs window by window instead.
#[cfg(target_arch = "x86_64")]
fn run_block_in_lanes(
    samples: &Samples<'_>,
    clipped: Option<&ClipMask<'_>>,
    edges: &[f64],
    template: &Preintegrator,
    k: lanes::P4,
) -> Vec<Preintegrator> {
    let spans: Vec<Span> = edges.windows(2).map(|w| span(samples.t, w[0], w[1])).collect();
    // The samples a window reads: euler holds k0 … k0 + steps − 1; midpoint's end point at `hi`
    // may be interpolated towards the next one, whose flag it takes.
    let reach = usize::from(template.scheme == Scheme::Midpoint);
    let flagged = |s: &Span| {
        let end = (s.k0 + s.steps + reach).min(samples.t.len());
        clipped.is_some_and(|m| (s.k0..end).any(|j| m.gyro[j] || m.accel[j]))
    };
    let (mut in_lanes, mut per_window): (Vec<usize>, Vec<usize>) = (0..spans.len()).partition(|&i| !flagged(&spans[i]));
    in_lanes.sort_by_key(|&i| spans[i].steps);
    per_window.extend(in_lanes.drain(bundled(in_lanes.len(), template.scheme)..));
    // Each result (3 kB) is moved as few times as possible: the indexed collects write in place,
    // then once into `done` and once into place.
    let bundles: Vec<Vec<Preintegrator>> = in_lanes
        .par_chunks(lanes::WIDTH)
        .map(|chunk| {
            let bundle: Vec<Span> = chunk.iter().map(|&i| spans[i]).collect();
            let mut done = lanes::run(samples, &bundle, template, k);
            for (p, s) in done.iter_mut().zip(&bundle) {
                p.boundary = boundary(samples, s, template.scheme);
            }
            done
        })
        .collect();
    let singles: Vec<Preintegrator> = per_window
        .par_iter()
        .map(|&i| window(samples, clipped, edges[i], edges[i + 1], template))
        .collect();
    // `done[j]` is window `order[j]`.
    let order = in_lanes.iter().chain(&per_window);
    let mut slot = vec![0; spans.len()];
    for (j, &i) in order.enumerate() {
        slot[i] = j;
    }
    // Sized up front: a collect from `flatten` or `filter_map` grows by reallocation (copies).
    let mut done: Vec<Option<Preintegrator>> = Vec::with_capacity(spans.len());
    done.extend(bundles.into_iter().flatten().chain(singles).map(Some));
    let mut out = Vec::with_capacity(spans.len());
    out.extend(slot.iter().filter_map(|&j| done[j].take()));
    out
}

#[cfg(all(test, target_arch = "x86_64"))]
#[path = "windows_tests.rs"]
mod tests;
