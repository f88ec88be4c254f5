//! Shared fixtures of the long-run stability tests (`tests/stability.rs`,
//! `tests/stability_memory.rs`): the run lengths, a reusable chunk of 1 kHz samples, and the
//! numerical checks.
//!
//! Lengths: `IMUKIT_STABILITY_STEPS` is the number of attitude steps (the full length is
//! 10^8, `make stability`); the rotation-matrix, covariance and memory runs use a tenth of it
//! (10^7 at full length). Unset, it is 10^6, short enough for a debug `cargo test`.
// Each test binary that includes this module uses only part of it.
#![allow(dead_code)]

use std::time::Instant;

use nalgebra::{DMatrix, Matrix3, SMatrix};

/// Attitude steps when `IMUKIT_STABILITY_STEPS` is unset.
const DEFAULT_STEPS: usize = 1_000_000;

/// Intervals per chunk: every long run calls the API once per chunk, continuing from its state.
pub const CHUNK_STEPS: usize = 100_000;

/// Sample interval \[s\] (1 kHz).
pub const H: f64 = 1e-3;

/// The number of attitude steps (see the module docs).
pub fn attitude_steps() -> usize {
    match std::env::var("IMUKIT_STABILITY_STEPS") {
        Ok(s) => s
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| *v >= 1.0 && v.is_finite())
            .map(|v| v as usize)
            .unwrap_or_else(|| panic!("IMUKIT_STABILITY_STEPS: expected a positive count, got {s:?}")),
        Err(_) => DEFAULT_STEPS,
    }
}

/// The length of the rotation-matrix, covariance and memory runs.
pub fn long_steps() -> usize {
    (attitude_steps() / 10).max(1)
}

/// One chunk of samples at 1 kHz, `CHUNK_STEPS + 1` of them, with chunk-local stamps from 0.
/// The last sample equals the first, so the chunk can be fed again and again as one continuous
/// stream (the midpoint schemes require a batch to start with the previous batch's last sample).
///
/// The rate stays a few rad/s and its axis keeps turning: `ω = (2 sin 0.71t + 0.5, 3 cos 0.37t,
/// 1.5 sin(1.13t + 0.4) − 1)` rad/s; the specific force is gravity-sized with a wobble.
pub struct Chunk {
    /// Stamps \[s\].
    pub t: Vec<f64>,
    /// Body rates [rad/s], flat 3n.
    pub gyro: Vec<f64>,
    /// Specific force [m/s²], flat 3n.
    pub accel: Vec<f64>,
}

impl Chunk {
    /// The chunk described above.
    pub fn new() -> Self {
        let n = CHUNK_STEPS + 1;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * H).collect();
        let mut gyro: Vec<f64> = t
            .iter()
            .flat_map(|&s| {
                [
                    2.0 * (0.71 * s).sin() + 0.5,
                    3.0 * (0.37 * s).cos(),
                    1.5 * (1.13 * s + 0.4).sin() - 1.0,
                ]
            })
            .collect();
        let mut accel: Vec<f64> = t
            .iter()
            .flat_map(|&s| {
                [
                    0.4 * (0.9 * s).sin(),
                    0.3 * (0.5 * s).cos(),
                    9.81 + 0.2 * (2.1 * s).sin(),
                ]
            })
            .collect();
        for v in [&mut gyro, &mut accel] {
            let first: [f64; 3] = [v[0], v[1], v[2]];
            v[3 * (n - 1)..].copy_from_slice(&first);
        }
        Self { t, gyro, accel }
    }

    /// The first `steps + 1` samples (`steps` intervals).
    pub fn samples(&self, steps: usize) -> imukit::imu::Samples<'_> {
        let n = steps.min(CHUNK_STEPS) + 1;
        imukit::imu::Samples::new(
            &self.t[..n],
            self.gyro[..3 * n].as_chunks().0,
            self.accel[..3 * n].as_chunks().0,
        )
        .unwrap()
    }
}

/// Calls `step(intervals)` once per chunk until `total` intervals are done.
pub fn in_chunks(total: usize, mut step: impl FnMut(usize)) {
    let mut done = 0;
    while done < total {
        let m = (total - done).min(CHUNK_STEPS);
        step(m);
        done += m;
    }
}

/// Runs `f`, printing `label`, the length and the wall time; returns `f`'s result.
pub fn timed<T>(label: &str, steps: usize, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = f();
    println!("{label}: {steps} steps in {:.2} s", start.elapsed().as_secs_f64());
    out
}

/// `‖RᵀR − I‖_F`.
pub fn orthonormality_error(r: &Matrix3<f64>) -> f64 {
    (r.transpose() * r - Matrix3::identity()).norm()
}

/// How far a covariance is from a symmetric positive semidefinite matrix.
#[derive(Debug, Clone, Copy)]
pub struct PsdReport {
    /// `max |P − Pᵀ|` (exact symmetry: 0).
    pub asymmetry: f64,
    /// The smallest eigenvalue over the largest: ≥ 0 up to the eigensolver's rounding.
    pub min_eigenvalue_ratio: f64,
    /// The smallest eigenvalue of the correlation matrix `D^{-1/2} P D^{-1/2}` (scale-free: the
    /// tiny bias variances are not lost against the huge position variances).
    pub min_correlation_eigenvalue: f64,
    /// Whether the Cholesky factorisation of `P + 1e-12 ‖P‖ I` exists.
    pub cholesky: bool,
}

/// [`PsdReport`] of `p`, whose diagonal must be positive.
pub fn psd_report<const N: usize>(p: &SMatrix<f64, N, N>) -> PsdReport {
    let asymmetry = (p - p.transpose()).amax();
    // Dynamic matrices: nalgebra's eigensolver is not generic over a const dimension.
    let sym = DMatrix::from_fn(N, N, |i, j| 0.5 * (p[(i, j)] + p[(j, i)]));
    let eig = sym.clone().symmetric_eigenvalues();
    let largest = eig.max();
    let corr = DMatrix::from_fn(N, N, |i, j| sym[(i, j)] / (sym[(i, i)] * sym[(j, j)]).sqrt());
    let shifted = &sym + DMatrix::identity(N, N) * (1e-12 * largest);
    PsdReport {
        asymmetry,
        min_eigenvalue_ratio: eig.min() / largest,
        min_correlation_eigenvalue: corr.symmetric_eigenvalues().min(),
        cholesky: shifted.cholesky().is_some(),
    }
}

/// Keeps the worst of each field over a run.
#[derive(Debug, Clone, Copy)]
pub struct Worst {
    /// Largest asymmetry seen.
    pub asymmetry: f64,
    /// Smallest eigenvalue ratio seen.
    pub min_eigenvalue_ratio: f64,
    /// Smallest correlation eigenvalue seen.
    pub min_correlation_eigenvalue: f64,
    /// Whether every Cholesky factorisation existed.
    pub cholesky: bool,
    /// Checks made.
    pub checks: usize,
}

impl Default for Worst {
    fn default() -> Self {
        Self {
            asymmetry: 0.0,
            min_eigenvalue_ratio: f64::INFINITY,
            min_correlation_eigenvalue: f64::INFINITY,
            cholesky: true,
            checks: 0,
        }
    }
}

impl Worst {
    /// Folds one check in.
    pub fn add(&mut self, r: PsdReport) {
        self.asymmetry = self.asymmetry.max(r.asymmetry);
        self.min_eigenvalue_ratio = self.min_eigenvalue_ratio.min(r.min_eigenvalue_ratio);
        self.min_correlation_eigenvalue = self.min_correlation_eigenvalue.min(r.min_correlation_eigenvalue);
        self.cholesky &= r.cholesky;
        self.checks += 1;
    }

    /// Asserts the guarantee: exactly symmetric, eigenvalues ≥ −1e-12 ‖P‖, Cholesky of
    /// `P + 1e-12 ‖P‖ I` exists, at every check.
    pub fn assert_psd(&self, label: &str) {
        println!("{label}: {self:?}");
        assert!(self.checks > 0, "{label}: nothing was checked");
        assert_eq!(self.asymmetry, 0.0, "{label}: covariance not exactly symmetric");
        assert!(
            self.min_eigenvalue_ratio >= -1e-12,
            "{label}: eigenvalue {:e} ‖P‖",
            self.min_eigenvalue_ratio
        );
        assert!(self.cholesky, "{label}: Cholesky of P + 1e-12 ‖P‖ I failed");
    }
}
