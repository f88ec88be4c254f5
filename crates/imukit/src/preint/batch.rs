//! Batch preintegration of sampled data: N samples, N − 1 intervals.
//!
//! Long batches run in parallel: preintegration is associative ([`Preintegrator::merge`]
//! is exact composition, covariance and bias Jacobians included), so chunks of at most [`CHUNK`]
//! intervals are preintegrated as keyframe windows (`windows.rs`: on separate cores, and four at
//! a time in the SIMD lanes of one core on the AVX paths) and merged in order. The chunks are
//! equal to within one interval and their number is a multiple of the lanes' bundle, so that each
//! bundle's chunks end together. The chunking depends on N only, never on the thread count or the
//! path, so results are reproducible; they differ from sample-by-sample streaming by rounding only
//! (1e-12 relative, tested). Long midpoint batches the same way: adjacent chunks share a sample,
//! whose noise correlation and variance the merge accounts for exactly (`merge.rs`). The bias random
//! walk (not merged) runs sequentially.

use super::windows::{run_block, BUNDLE};
use super::{clipped_at, ClipMask, End, Ends, Preintegrator, Scheme};
use crate::error::{Cancel, Error, Result};
use crate::imu::Samples;

/// Most intervals per parallel chunk: long enough that a merge (a few dense 9×9 products) is noise.
pub const CHUNK: usize = 1 << 15;

/// Chunks run between two polls of the cancellation flag (about 2^19 samples).
const CHUNKS_PER_POLL: usize = 4 * BUNDLE;

/// The times where the chunks of the intervals of `t` (N samples, N − 1 intervals) start and end:
/// the fewest chunks of at most [`CHUNK`] intervals whose number is a multiple of [`BUNDLE`],
/// cut equal to within one interval, on sample times.
fn chunk_edges(t: &[f64]) -> Vec<f64> {
    let intervals = t.len() - 1;
    let m = intervals.div_ceil(CHUNK).next_multiple_of(BUNDLE);
    (0..=m).map(|i| t[i * intervals / m]).collect()
}

impl Preintegrator {
    /// Adds the N − 1 intervals of `samples` (euler: sample k held over `[t_k, t_k+1)`; midpoint:
    /// between samples k and k+1, continuing from the last sample, which must then be sample 0).
    /// Everything is validated first: on an error nothing has been added. Finite samples whose
    /// deltas or covariance overflow (e.g. a noise density of 1e200, squared) are an
    /// [`Error::Overflow`] at the last sample, again with nothing added.
    pub fn integrate_samples(&mut self, samples: &Samples<'_>) -> Result<()> {
        self.integrate_samples_clipped(samples, None)
    }

    /// [`Preintegrator::integrate_samples`] with per-sample saturation flags (`None`: nothing
    /// clipped): a flagged sample's white noise is inflated as in
    /// [`Preintegrator::integrate_measurement_clipped`] (euler: on the interval it starts;
    /// midpoint: on both intervals it bounds; the first sample of a midpoint batch that continues
    /// a window is the window's last sample, and keeps that sample's flags).
    pub fn integrate_samples_clipped(&mut self, samples: &Samples<'_>, clipped: Option<&ClipMask<'_>>) -> Result<()> {
        samples.validate()?;
        let n = samples.t.len();
        self.integrate_samples_at(samples, clipped, [samples.t[0], samples.t[n - 1]])
    }

    /// [`Preintegrator::integrate_samples_clipped`] of samples whose first and last times on the
    /// caller's clock are `clock` (a caller that re-bases `samples.t`, as Python does, keeps its
    /// own clock): a batch continuing a preintegration must start with its last sample, the same
    /// time and readings, in both schemes (module docs of `continuity.rs`; errors name `samples`).
    pub fn integrate_samples_at(
        &mut self,
        samples: &Samples<'_>,
        clipped: Option<&ClipMask<'_>>,
        clock: [f64; 2],
    ) -> Result<()> {
        self.integrate_samples_cancellable(samples, clipped, clock, &Cancel::new())
    }

    /// [`Preintegrator::integrate_samples_at`], stopping with [`Error::Interrupted`] (nothing added)
    /// when `cancel` is set (polled every [`Cancel::EVERY`] intervals, and between parallel chunks).
    pub fn integrate_samples_cancellable(
        &mut self,
        samples: &Samples<'_>,
        clipped: Option<&ClipMask<'_>>,
        clock: [f64; 2],
        cancel: &Cancel,
    ) -> Result<()> {
        samples.validate()?;
        if let Some(mask) = clipped {
            mask.check(samples.t.len())?;
        }
        let n = samples.t.len();
        let end = |k: usize, t: f64| End {
            t: Some(t),
            accel: samples.accel_at(k),
            gyro: samples.gyro_at(k),
        };
        let ends = Ends {
            first: Some(end(0, clock[0])),
            last: Some(end(n - 1, clock[1])),
        };
        if let Some(first) = &ends.first {
            self.boundary.check_next(first, "samples")?;
        }
        let mut next = self.clone();
        next.add_validated(samples, clipped, cancel)?;
        if !next.is_finite() {
            return Err(Error::Overflow { index: n - 1 });
        }
        next.boundary = self.boundary.then(&ends);
        *self = next;
        Ok(())
    }

    /// The intervals of validated `samples`, continuing this preintegration.
    fn add_validated(&mut self, samples: &Samples<'_>, clipped: Option<&ClipMask<'_>>, cancel: &Cancel) -> Result<()> {
        let n = samples.t.len();
        let first = (samples.accel_at(0), samples.gyro_at(0));
        match self.scheme {
            _ if self.bias_walk.is_none() && n > 2 * CHUNK => {
                let template = Preintegrator {
                    saturation_noise_factor: self.saturation_noise_factor,
                    ..Preintegrator::new(self.bias_gyro, self.bias_accel, self.noise).with_scheme(self.scheme)
                };
                let edges = chunk_edges(samples.t);
                let mut chunks = Vec::with_capacity(edges.len() - 1);
                for first in (0..edges.len() - 1).step_by(CHUNKS_PER_POLL) {
                    cancel.check(0)?;
                    let block = &edges[first..(first + CHUNKS_PER_POLL + 1).min(edges.len())];
                    chunks.extend(run_block(samples, clipped, block, &template));
                }
                // Midpoint chunks share their edge samples (the first chunk this one's last); the
                // merge keeps a shared sample's first-interval variance, as one run does.
                for mut chunk in chunks {
                    // Each chunk's ends are its neighbours' (sample times): none to check.
                    chunk.boundary = Ends::default();
                    *self = self.merge_unchecked(&chunk)?;
                }
            }
            Scheme::Euler => run_euler(self, samples, clipped, 0, n - 1, cancel)?,
            Scheme::Midpoint => {
                if self.last_sample().is_none() {
                    self.integrate_measurement_clipped(&first.0, &first.1, 0.0, clipped_at(clipped, 0));
                }
                run_midpoint(self, samples, clipped, cancel)?;
            }
        }
        Ok(())
    }
}

crate::simd_dispatch! {
    /// Euler intervals `start..end` of `p` (interval k from sample k to k+1).
    fn run_euler(
        p: &mut Preintegrator,
        samples: &Samples<'_>,
        clipped: Option<&ClipMask<'_>>,
        start: usize,
        end: usize,
        cancel: &Cancel,
    ) -> Result<()> {
        for k in start..end {
            cancel.check(k)?;
            let h = samples.t[k + 1] - samples.t[k];
            let (a, w) = (samples.accel_at(k), samples.gyro_at(k));
            p.integrate_measurement_clipped(&a, &w, h, clipped_at(clipped, k));
        }
        Ok(())
    }
}

crate::simd_dispatch! {
    /// Midpoint intervals 1..n of `p`, whose last sample is sample 0.
    fn run_midpoint(p: &mut Preintegrator, samples: &Samples<'_>, clipped: Option<&ClipMask<'_>>, cancel: &Cancel) -> Result<()> {
        for k in 1..samples.t.len() {
            cancel.check(k)?;
            let h = samples.t[k] - samples.t[k - 1];
            let (a, w) = (samples.accel_at(k), samples.gyro_at(k));
            p.integrate_measurement_clipped(&a, &w, h, clipped_at(clipped, k));
        }
        Ok(())
    }
}
