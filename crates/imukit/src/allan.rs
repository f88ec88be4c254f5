//! # Allan variance of rate signals
//!
//! | item | specification |
//! |---|---|
//! | input | `y`: `N` rows × `C` columns, row-major, one sample per row at `rate` Hz (`τ0 = 1/rate`), e.g. a gyro's ω [rad/s] or an accelerometer's f [m/s²] |
//! | cluster sizes | `m ≥ 1` with `2m ≤ N`, any order, repeats allowed; `τ = m τ0` |
//! | overlapping estimator | `AVAR(mτ0) = Σ_{k=0}^{N−2m} (x_{k+2m} − 2x_{k+m} + x_k)² / (2 m² τ0² (N − 2m + 1))`, with the phase `x_j = τ0 Σ_{i<j} y_i` (`N + 1` phase points, `x_0 = 0`) |
//! | non-overlapping estimator | the same sum over `k = 0, m, 2m, …`: `⌊N/m⌋ − 1` differences of adjacent cluster means |
//! | terms | returned per `τ`: `N − 2m + 1` (overlapping) or `⌊N/m⌋ − 1` (non-overlapping), allantools' `ns` |
//! | references | IEEE Std 952-1997 (Annex C); W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065 (2008), eqs. (7) and (11) |
//! | accuracy | within a few ulps of the exact value (see below); agrees with `allantools.oadev` / `adev` with `data_type="freq"` to 1e-10 relative |
//! | parallelism | rayon over (τ, column group); each result is computed by one thread in a fixed order, so results do not depend on the thread count |
//! | errors | [`Error::Parameter`] for a rate that is not finite and positive, fewer than 2 samples, no cluster size, or `m` outside `1 ≤ m ≤ N/2`; [`Error::RowLength`] when `y` is not whole rows; [`Error::NonFinite`] (first bad row) for NaN / ±inf; [`Error::Overflow`] for a sample above 1e100 in magnitude. Nothing panics. |
//!
//! ## How it is computed
//!
//! The phase is never formed. Its second difference is `τ0 d_k` with
//! `d_k = Σ_{i<m} (y_{k+m+i} − y_{k+i})`, the difference of two adjacent cluster sums, so
//! `AVAR = Σ d_k² / (2 m² n)` and τ0 cancels. The overlapping `d_k` is slid along the data with
//! `d_{k+1} = d_k + (y_{k+2m} − y_{k+m}) − (y_{k+m} − y_k)`: three reads and one dependent
//! addition per term, independent of `m`. Both that running sum and the sum of squares are
//! carried as error-free pairs (TwoSum cascade, Ogita, Rump & Oishi 2005, "Accurate sum and dot
//! product", algorithm Sum2), so neither the length of the record nor a large constant offset
//! (an accelerometer's 9.81 m/s²) costs digits: differences of nearby samples are exact
//! (Sterbenz), and rounding enters only where the result itself is rounded. A phase built by
//! a plain cumulative sum (allantools removes the mean first) instead loses about
//! `ε |x_max| / |d|` relative, i.e. ~1e-12 on a 10⁷-sample white-noise record.
//!
//! ```
//! use imukit::allan::{allan_variance, Estimator};
//!
//! // y alternating ±1 at 100 Hz: at m = 1 every difference is ±2, AVAR = 4/2 = 2.
//! let y: Vec<f64> = (0..8).map(|i| if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
//! let a = allan_variance(&y, 1, 100.0, &[1, 2], Estimator::Overlapping).unwrap();
//! assert_eq!(a.taus, vec![0.01, 0.02]);
//! assert_eq!(a.variance, vec![2.0, 0.0]);
//! assert_eq!(a.terms, vec![7, 5]);
//! ```

use std::cmp::Ordering;

use rayon::prelude::*;

use crate::{Error, Result};

/// Largest sample magnitude accepted: keeps every sum of squares far from overflow.
pub const MAX_ABS_SAMPLE: f64 = 1e100;

/// Columns processed together in one pass (independent running sums hide the addition latency).
const GROUP: usize = 3;

/// Which Allan-variance estimator to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Estimator {
    /// Every start index `k` (fully overlapping clusters): the estimator of choice.
    Overlapping,
    /// Start indices `k = 0, m, 2m, …` (adjacent, disjoint clusters): the classic definition.
    NonOverlapping,
}

/// Allan variances of every column at every cluster size.
#[derive(Debug, Clone, PartialEq)]
pub struct AllanVariance {
    /// `τ = m / rate` \[s\], one per cluster size, in the order given.
    pub taus: Vec<f64>,
    /// `M × C` row-major: `variance[i * columns + c]` is column `c` at `taus[i]` \[unit²\].
    pub variance: Vec<f64>,
    /// Number of squared differences averaged at each `τ` (allantools' `ns`).
    pub terms: Vec<usize>,
    /// Number of columns `C`.
    pub columns: usize,
}

/// Number of squared differences averaged at cluster size `m` in `n` samples (0 when `2m > n`).
pub fn term_count(n: usize, m: usize, estimator: Estimator) -> usize {
    if m == 0 || n < 2 * m {
        return 0;
    }
    match estimator {
        Estimator::Overlapping => n - 2 * m + 1,
        Estimator::NonOverlapping => n / m - 1,
    }
}

/// Octave-spaced cluster sizes `1, 2, 4, …` up to `n / 4` (at least 4 clusters, Stable32's
/// "stop ratio" for the Allan variance: Riley, NIST SP 1065, §5.2.10); empty when `n < 4`.
pub fn octave_clusters(n: usize) -> Vec<usize> {
    std::iter::successors(Some(1usize), |m| m.checked_mul(2))
        .take_while(|&m| m.saturating_mul(4) <= n)
        .collect()
}

/// Allan variance of each of the `columns` columns of `y` (row-major, `rate` Hz) at the cluster
/// sizes `clusters`; see the [module documentation](self) for the definition and the errors.
pub fn allan_variance(
    y: &[f64],
    columns: usize,
    rate: f64,
    clusters: &[usize],
    estimator: Estimator,
) -> Result<AllanVariance> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(Error::Parameter {
            name: "rate",
            expected: "a positive, finite sample rate in Hz",
            got: format!("{rate:?}"),
        });
    }
    if columns == 0 || !y.len().is_multiple_of(columns) {
        return Err(Error::RowLength {
            len: y.len(),
            row: columns,
        });
    }
    let n = y.len() / columns;
    if n < 2 {
        return Err(Error::Parameter {
            name: "y",
            expected: "at least 2 samples",
            got: format!("{n} samples"),
        });
    }
    check_samples(y, columns)?;
    if clusters.is_empty() {
        return Err(Error::Parameter {
            name: "clusters",
            expected: "at least one cluster size",
            got: "none".to_string(),
        });
    }
    if let Some(&m) = clusters.iter().find(|&&m| term_count(n, m, estimator) == 0) {
        return Err(Error::Parameter {
            name: "clusters",
            expected: "cluster sizes m with 1 ≤ m ≤ N/2",
            got: format!("m = {m} with N = {n} samples"),
        });
    }

    let groups: Vec<(usize, usize)> = (0..columns)
        .step_by(GROUP)
        .map(|first| (first, (columns - first).min(GROUP)))
        .collect();
    let tasks: Vec<(usize, (usize, usize))> = (0..clusters.len())
        .flat_map(|i| groups.iter().map(move |&g| (i, g)))
        .collect();
    let sums: Vec<[f64; GROUP]> = tasks
        .par_iter()
        .map(|&(i, (first, width))| sums_of(Columns { y, columns, first }, width, n, clusters[i], estimator))
        .collect();

    let mut variance = vec![0.0; clusters.len() * columns];
    for (&(i, (first, width)), sum) in tasks.iter().zip(&sums) {
        let m = clusters[i] as f64;
        let scale = 2.0 * m * m * term_count(n, clusters[i], estimator) as f64;
        for (c, s) in sum.iter().take(width).enumerate() {
            variance[i * columns + first + c] = s / scale;
        }
    }
    Ok(AllanVariance {
        taus: clusters.iter().map(|&m| m as f64 / rate).collect(),
        variance,
        terms: clusters.iter().map(|&m| term_count(n, m, estimator)).collect(),
        columns,
    })
}

/// NaN / ±inf → [`Error::NonFinite`], `|y| > MAX_ABS_SAMPLE` → [`Error::Overflow`], first bad row.
fn check_samples(y: &[f64], columns: usize) -> Result<()> {
    const CHUNK: usize = 1 << 16;
    // NaN compares false, so "not within the bound" catches it together with ±inf and the huge.
    let unusable = |v: &f64| {
        !matches!(
            v.abs().partial_cmp(&MAX_ABS_SAMPLE),
            Some(Ordering::Less | Ordering::Equal)
        )
    };
    let bad = y
        .par_chunks(CHUNK)
        .enumerate()
        .find_first(|(_, chunk)| chunk.iter().any(unusable))
        .and_then(|(i, chunk)| {
            let k = chunk.iter().position(unusable)?;
            Some((i * CHUNK + k, chunk[k]))
        });
    match bad {
        None => Ok(()),
        Some((index, v)) if v.is_finite() => Err(Error::Overflow { index: index / columns }),
        Some((index, _)) => Err(Error::NonFinite { index: index / columns }),
    }
}

/// `W ≤ GROUP` adjacent columns of a row-major array, starting at column `first`.
#[derive(Clone, Copy)]
struct Columns<'a> {
    y: &'a [f64],
    columns: usize,
    first: usize,
}

impl Columns<'_> {
    #[inline(always)]
    fn get<const W: usize>(&self, row: usize) -> [f64; W] {
        let at = row * self.columns + self.first;
        std::array::from_fn(|c| self.y[at + c])
    }
}

crate::simd_dispatch! {
    /// The sums of squared differences of `width` columns at cluster size `m`, per instruction-set
    /// path.
    fn sums_of(view: Columns<'_>, width: usize, n: usize, m: usize, estimator: Estimator) -> [f64; GROUP] {
        match (estimator, width) {
            (Estimator::Overlapping, 1) => widen(overlapping::<1>(view, n, m)),
            (Estimator::Overlapping, 2) => widen(overlapping::<2>(view, n, m)),
            (Estimator::Overlapping, _) => overlapping::<GROUP>(view, n, m),
            (Estimator::NonOverlapping, 1) => widen(non_overlapping::<1>(view, n, m)),
            (Estimator::NonOverlapping, 2) => widen(non_overlapping::<2>(view, n, m)),
            (Estimator::NonOverlapping, _) => non_overlapping::<GROUP>(view, n, m),
        }
    }
}

fn widen<const W: usize>(s: [f64; W]) -> [f64; GROUP] {
    std::array::from_fn(|c| if c < W { s[c] } else { 0.0 })
}

/// An exactly carried sum `hi + lo` (TwoSum cascade: Ogita, Rump & Oishi 2005, Sum2).
#[derive(Clone, Copy, Default)]
struct Sum2 {
    hi: f64,
    lo: f64,
}

impl Sum2 {
    /// Adds `x`; the rounding error of `hi + x` (Knuth's TwoSum, exact) goes into `lo`.
    #[inline(always)]
    fn add(&mut self, x: f64) {
        let s = self.hi + x;
        let back = s - self.hi;
        let err = (self.hi - (s - back)) + (x - back);
        self.hi = s;
        self.lo += err;
    }

    #[inline(always)]
    fn value(self) -> f64 {
        self.hi + self.lo
    }
}

/// `Σ_{i<m} (y_{k+m+i} − y_{k+i})` for each column: twice-adjacent cluster sums differenced.
#[inline(always)]
fn cluster_difference<const W: usize>(view: Columns<'_>, k: usize, m: usize) -> [Sum2; W] {
    let mut d = [Sum2::default(); W];
    for i in k..k + m {
        let (early, late) = (view.get::<W>(i), view.get::<W>(i + m));
        for c in 0..W {
            d[c].add(late[c] - early[c]);
        }
    }
    d
}

/// `Σ_k d_k²` of the overlapping estimator for `W` columns.
#[inline(always)]
fn overlapping<const W: usize>(view: Columns<'_>, n: usize, m: usize) -> [f64; W] {
    let terms = n - 2 * m + 1;
    let mut d = cluster_difference::<W>(view, 0, m);
    let mut squares = [Sum2::default(); W];
    for k in 0..terms {
        for c in 0..W {
            let v = d[c].value();
            squares[c].add(v * v);
        }
        if k + 1 < terms {
            // d_{k+1} − d_k = (y_{k+2m} − y_{k+m}) − (y_{k+m} − y_k).
            let (a, b, e) = (view.get::<W>(k), view.get::<W>(k + m), view.get::<W>(k + 2 * m));
            for c in 0..W {
                d[c].add((e[c] - b[c]) - (b[c] - a[c]));
            }
        }
    }
    squares.map(Sum2::value)
}

/// `Σ_j d_{jm}²` of the non-overlapping estimator for `W` columns.
#[inline(always)]
fn non_overlapping<const W: usize>(view: Columns<'_>, n: usize, m: usize) -> [f64; W] {
    let mut squares = [Sum2::default(); W];
    for j in 0..n / m - 1 {
        let d = cluster_difference::<W>(view, j * m, m);
        for c in 0..W {
            let v = d[c].value();
            squares[c].add(v * v);
        }
    }
    squares.map(Sum2::value)
}
