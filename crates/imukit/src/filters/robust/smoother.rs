//! The acausal smoother of [`super::Robust`]: the online filter run forward and on the
//! time-reversed record, the two estimates fused sample by sample by their uncertainties.
//!
//! Time reversal: with `t' = −t` the body turns at `−ω`, so the reversed record has gyro
//! `−ω_m = −ω − b` (bias `−b`) and the same accelerometer and field; the backward pass estimates
//! the same `q_wb(t)` from the samples after `t`. Each interval is integrated with the same gyro
//! sample in both passes (the later one, as the online step does).
//!
//! Stage 1, the bias (two independent Gaussian estimates, weights by inverse variance, the
//! two-filter smoother of Fraser & Potter, IEEE Trans. Automatic Control 14 (1969) 387–390): per
//! axis `b = (b_f/σ_f² + b_b/σ_b²)/(1/σ_f² + 1/σ_b²)`.
//!
//! Stage 2, the inclination (zero phase): strapdown with the fused bias into the almost-inertial
//! frame `I`, the specific force there filtered by the online filter's Butterworth forward and then
//! backward over the whole record (response `|H(ω)|²`: no phase, so no lag, and an acceleration
//! above the cut-off attenuated as `(ω_c/ω)⁴` where one pass gives `(ω_c/ω)²` and the mean of a
//! forward and a backward pass `Re H`, no better); the attitude's up is the filtered specific
//! force (the smallest rotation taking it to up). Every sample's tilt so uses the accelerometer
//! before and after it. (BROAD 6D offline 0.530° → 0.487°; the mean of the two passes' tilts,
//! the first version, is what this replaces.)
//!
//! Stage 2, the heading (9D): the online step's heading loop alone (the field's gate, reference
//! learning and heading filter) runs forward and backward on the zero-phase attitudes, i.e. with
//! the fused bias and the zero-phase inclination in place of each pass's own; the two headings
//! are fused with `w = v_f/(v_f + v_b)` on the backward one, each pass's variance `v` taken as
//! `‖σ_b‖²` of stage 1 (a bias error ε leaves the heading `ε τ_mag` behind; a pass that has just
//! started has the prior σ and so little weight): the two headings differ in quality, as each
//! pass rejects the field at other times (`½` instead: 9D 2.16° → 2.38°). Before, both full passes
//! ran again with the fused bias, each with its own causal inclination: BROAD 9D offline 2.100° →
//! 2.059° with the zero-phase one (the field's horizontal part is taken about a better vertical),
//! and a heading pass costs a fifth of a full one. A two-sided kernel `exp(−|Δt|/τ_mag)` on the
//! field in `E'`, weighted 0 where either pass rejected it, was tried instead: 9D 2.14° → 2.43°
//! (trials 32, 34, attached magnets: the passes' own reference learning does better), not taken.
//! In 6D the heading is the zero-phase attitude's (the strapdown's, from its start).
//!
//! Flags: rest where either pass detects it (detection needs `rest_duration_s` of history, which
//! each pass has on its own side); disturbed where both passes reject the field.

use std::ops::Range;

use nalgebra::{Quaternion, UnitQuaternion, Vector2, Vector3};

use super::step::{
    carry, compose, from_world, heading_error, set_heading, start_heading, to_up, to_world, turn, turn_heading, wrap,
    yawed, Coefs, CoefsCache, Field,
};
use super::{Outputs, Robust, RobustParams, RobustState, Track};
use crate::filters::{initial_attitude, row, Inputs, World};
use crate::pages;
use crate::quat::exp_step;
use crate::{Cancel, Result};

fn quat(x: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(x[3], x[0], x[1], x[2]))
}

/// Rows of the record reversed in time (see the module doc), a part at a time: the backward pass
/// is fed [`REVERSED_PART`] rows per call into buffers it reuses (a reversed copy of the whole
/// record was 80 B per sample of fresh pages in 9D; parts give the same result, bit for bit).
#[derive(Default)]
struct Reversed {
    t: Vec<f64>,
    gyro: Vec<[f64; 3]>,
    accel: Vec<[f64; 3]>,
    mag: Option<Vec<[f64; 3]>>,
}

/// Samples per block of a heading pass's [`Field`]s (6 kB on the stack, in L1).
const HEADING_BLOCK: usize = 256;

/// Rows of the reversed record per part of the backward pass (9D: 1.3 MB of buffers).
const REVERSED_PART: usize = 1 << 14;

impl Reversed {
    /// Rows `rows` of the reversed record: its row `j` is the record's row `n − 1 − j`.
    fn fill(&mut self, inputs: &Inputs<'_>, rows: Range<usize>) {
        let n = inputs.t.len();
        let back = |j: usize| n - 1 - j;
        self.t.clear();
        self.t.extend(rows.clone().map(|j| -inputs.t[back(j)]));
        // The forward step over (t_k, t_k+1] integrates ω_k+1; the backward one over the same
        // interval must too (ω_k would put it one sample's rotation apart: 1° at 5 rad/s, 285 Hz).
        self.gyro.clear();
        self.gyro.extend(rows.clone().map(|j| {
            let w = inputs.gyro[(n - j).min(n - 1)];
            [-w[0], -w[1], -w[2]]
        }));
        self.accel.clear();
        self.accel.extend(rows.clone().map(|j| inputs.accel[back(j)]));
        if let Some(mags) = inputs.mag {
            let mag = self.mag.get_or_insert_with(Vec::new);
            mag.clear();
            mag.extend(rows.map(|j| mags[back(j)]));
        }
    }

    fn inputs(&self) -> Inputs<'_> {
        Inputs {
            t: &self.t,
            gyro: &self.gyro,
            accel: &self.accel,
            mag: self.mag.as_deref(),
        }
    }
}

impl Robust {
    /// The smoothed estimate of a whole record (one row of `out` per sample): `state` starts
    /// the forward pass (uninitialised, or at an initial attitude) and ends as the first forward
    /// pass's final state. Deterministic; errors as [`Robust::run`].
    ///
    /// Two stages: forward and backward passes estimate the bias, fused; then the inclination of
    /// the zero-phase filtered specific force with that bias, and in 9D the heading loop run
    /// forward and backward on that attitude, fused.
    pub fn smooth(&self, state: &mut RobustState, inputs: &Inputs<'_>, out: &mut Outputs<'_>) -> Result<()> {
        self.smooth_cancellable(state, inputs, out, &Cancel::new())
    }

    /// [`Robust::smooth`], stopping with [`Error::Interrupted`](crate::Error::Interrupted) when
    /// `cancel` is set: polled by both first-stage passes (every [`Cancel::EVERY`] samples, and
    /// at each part of the backward pass) and before the second stage, which then runs to its
    /// end (about half the work).
    pub fn smooth_cancellable(
        &self,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        out: &mut Outputs<'_>,
        cancel: &Cancel,
    ) -> Result<()> {
        let n = inputs.t.len();
        if !out.len_ok(n, true) {
            return Err(crate::Error::RowCount {
                input: n,
                output: out.q.len(),
            });
        }
        let start = *state;
        if n == 0 {
            return self.run(state, inputs, false, &mut Track::new(0).outputs());
        }
        // The two passes are independent: one thread each (every pass is the same
        // sequential loop, so the result does not depend on the threads; errors are the forward
        // pass's first, as in sequence). Neither writes its attitude: nothing reads it. The
        // forward pass writes its bias, σ and flags into `out`, where they are fused in place:
        // only the backward pass has a track of its own.
        let mut bwd = unposed(n);
        let (forward, backward) = rayon::join(
            || self.run_checked(state, inputs, (0, false), false, &mut out.unposed(), cancel),
            || self.run_reversed(inputs, &mut bwd, cancel),
        );
        forward?;
        backward?;
        cancel.check(0).map_err(|_| crate::Error::Interrupted { index: n })?;

        // The backward track is in reversed time: sample k is its row n − 1 − k (indexed so, not
        // reversed in place). The fusions are per sample: the record's halves on two threads,
        // bit for bit.
        let nine = inputs.mag.is_some();
        let half = n / 2;
        let mut weights = if nine { pages::rows(0.0, n) } else { Vec::new() };
        {
            let (mut early, mut late) = out.split_at(half);
            let split = half.min(weights.len()); // 6D: no weights
            let (w_early, w_late) = weights.split_at_mut(split);
            rayon::join(
                || fuse_bias(&bwd, 0, &mut early, w_early),
                || fuse_bias(&bwd, half, &mut late, w_late),
            );
        }

        // Second stage: the zero-phase inclination from the fused bias; in 9D the heading loop
        // forward and backward on it (on two threads), fused by the weights.
        let q0 = if start.initialized {
            from_world(self.world, &start.q)
        } else {
            from_world(self.world, &initial_attitude(self.world, &row(&inputs.accel[0]), None))
        };
        // The backward track is dead once fused: its two rows of 24 B per sample are the second
        // stage's scratch, pages already mapped (fresh ones fault on first write, `pages`).
        let Track {
            bias: scratch_a,
            bias_sigma: scratch_b,
            ..
        } = &mut bwd;
        // 6D: the zero-phase attitude is the estimate, turned into the world as it is written.
        zero_phase(
            &self.params,
            q0,
            inputs,
            out.bias,
            scratch_a,
            scratch_b,
            out.q,
            (!nine).then_some(self.world),
        );
        if let Some(mags) = inputs.mag {
            let base: &[[f64; 4]] = out.q;
            let pass = |from: &RobustState, backward: bool, headings: &mut [[f64; 3]]| {
                heading_pass(&self.params, from, inputs, mags, base, backward, headings);
            };
            rayon::join(
                || pass(&start, false, scratch_b),
                || pass(&RobustState::default(), true, scratch_a),
            );
            let (fwd_h, bwd_h) = (&scratch_b[..], &scratch_a[..]);
            let (early, late) = out.q.split_at_mut(half);
            let (f, b, w) = (fwd_h.split_at(half), bwd_h.split_at(half), weights.split_at(half));
            rayon::join(
                || fuse_headings(self.world, f.0, b.0, w.0, early),
                || fuse_headings(self.world, f.1, b.1, w.1, late),
            );
        }
        Ok(())
    }

    /// Stage 1's backward pass into `track`: the record reversed in time, fed a part at a time
    /// ([`Reversed`]); errors name rows of the reversed record.
    fn run_reversed(&self, inputs: &Inputs<'_>, track: &mut Track, cancel: &Cancel) -> Result<()> {
        let n = inputs.t.len();
        let mut state = RobustState::default();
        let mut part = Reversed::default();
        for first in (0..n).step_by(REVERSED_PART) {
            let rows = first..(first + REVERSED_PART).min(n);
            part.fill(inputs, rows.clone());
            let mut out = Outputs {
                q: &mut [],
                bias: &mut track.bias[rows.clone()],
                bias_sigma: &mut track.bias_sigma[rows.clone()],
                rest: &mut track.rest[rows.clone()],
                mag_disturbed: &mut track.mag_disturbed[rows],
            };
            self.run_checked(&mut state, &part.inputs(), (first, first > 0), false, &mut out, cancel)?;
        }
        Ok(())
    }
}

impl Outputs<'_> {
    /// These rows without the attitude, for a pass that writes none.
    fn unposed(&mut self) -> Outputs<'_> {
        Outputs {
            q: &mut [],
            bias: self.bias,
            bias_sigma: self.bias_sigma,
            rest: self.rest,
            mag_disturbed: self.mag_disturbed,
        }
    }
}

/// A first-stage track: `n` rows of zeros but no attitude.
fn unposed(n: usize) -> Track {
    Track {
        q: Vec::new(),
        bias: pages::rows([0.0; 3], n),
        bias_sigma: pages::rows([0.0; 3], n),
        rest: vec![false; n],
        mag_disturbed: vec![false; n],
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// Stage 1's fusion of the forward pass, whose bias, σ and flags `out` holds, with `bwd` (in
    /// reversed time), in place; and in 9D (`weights` not empty) each sample's heading weight
    /// `v_f/(v_f + v_b)` of the backward pass (½ where both are 0); `out`'s and `weights`' rows are
    /// the record's from row `first`. Per axis `b = b_f w_f + b_b w_b`, `w_f = σ_b²/(σ_f² + σ_b²)`:
    /// one division for both weights and the variance `σ_f² σ_b²/(σ_f² + σ_b²)`, the three axes
    /// side by side (no branch: an axis with both σ zero takes the mean and σ = 0).
    fn fuse_bias<'a>(bwd: &Track, first: usize, out: &mut Outputs<'a>, weights: &mut [f64]) -> () {
        let n = bwd.bias.len();
        for row in 0..out.bias.len() {
            let j = n - 1 - first - row;
            let (sf, sb) = (out.bias_sigma[row], bwd.bias_sigma[j]);
            let (pf, pb) = (sf.map(|s| s * s), sb.map(|s| s * s));
            if let Some(weight) = weights.get_mut(row) {
                let (vf, vb) = (pf[0] + pf[1] + pf[2], pb[0] + pb[1] + pb[2]);
                *weight = if vf + vb > 0.0 { vf / (vf + vb) } else { 0.5 };
            }
            let (bf, bb) = (out.bias[row], bwd.bias[j]);
            let (mut fused, mut sigma) = ([0.0; 3], [0.0; 3]);
            for i in 0..3 {
                let sum = pf[i] + pb[i];
                let live = sum > 0.0;
                let r = 1.0 / if live { sum } else { 1.0 };
                let (wf, wb) = if live { (pb[i] * r, pf[i] * r) } else { (0.5, 0.5) };
                // The backward pass runs on −ω: its bias is −b.
                fused[i] = bf[i] * wf - bb[i] * wb;
                sigma[i] = (pf[i] * pb[i] * r).sqrt();
            }
            out.bias[row] = fused;
            out.bias_sigma[row] = sigma;
            out.rest[row] = out.rest[row] || bwd.rest[j];
            out.mag_disturbed[row] = out.mag_disturbed[row] && bwd.mag_disturbed[j];
        }
    }
}

/// Records from this length on run the zero-phase filter in two halves on two threads.
const ZERO_PHASE_SPLIT_FROM: usize = 1 << 12;

/// The 6D attitude of [`Robust::smooth`] into `out` (`q_wb`, internal ENU, or `world`'s when
/// given): strapdown from `q0` with the fused `bias` into the almost-inertial frame `I`, the
/// specific force there filtered by the Butterworth forward and then backward (zero phase,
/// `|H|²`), the inclination the smallest rotation taking it to up, applied as the backward pass
/// reaches each sample. The heading is the strapdown's (its start's). `a_i` and `free` (n rows
/// each) are scratch.
///
/// Both passes are sequential; from [`ZERO_PHASE_SPLIT_FROM`] samples on, the record is cut in
/// two halves that run side by side (the cut fixed by `n`, not by the threads: the result is the
/// same on any number of them), because every step is linear in what it carries:
/// - the late half runs its strapdown from the identity (`r_k`; the attitude is `q_m−1 ⊗ r_k`)
///   and its Butterworth from a zero state on `r_k a_k` (the filter commutes with the constant
///   rotation `q_m−1`); the early half's end state `s_m` enters as the free response `Φ_k s_m`
///   (`Φ` the product of the zero-input steps, [`Coefs::free_step`]). The backward pass is linear
///   too, so the late half filters backward its own output and the two rows of `Φ_k` that
///   multiply `s_m` without waiting for the early half;
/// - the early half's backward pass runs from a zero state, and the late half's end state enters
///   as its free response;
/// - then every sample is put together, tilted and written, in any order.
///
/// Rounding differs from one sequential pass (products and sums associate otherwise).
#[allow(clippy::too_many_arguments)] // the pass's inputs, two scratch rows and the output
fn zero_phase(
    p: &RobustParams,
    q0: UnitQuaternion<f64>,
    inputs: &Inputs<'_>,
    bias: &[[f64; 3]],
    a_i: &mut [[f64; 3]],
    free: &mut [[f64; 3]],
    out: &mut [[f64; 4]],
    world: Option<World>,
) {
    let n = inputs.t.len();
    if n < ZERO_PHASE_SPLIT_FROM {
        forward(p, q0, inputs, bias, a_i, &mut [], out);
        backward(p, inputs, a_i, out, world);
        return;
    }
    let m = n / 2;
    let (a_early, a_late) = a_i.split_at_mut(m);
    let (f_early, f_late) = free.split_at_mut(m);
    let (o_early, o_late) = out.split_at_mut(m);
    let (mid, late) = rayon::join(
        || {
            let mid = forward(p, q0, inputs, bias, a_early, &mut [], o_early);
            backward_zero_state(p, inputs, a_early, f_early);
            mid
        },
        || {
            forward(p, UnitQuaternion::identity(), inputs, bias, a_late, f_late, o_late);
            backward_late(p, inputs, m, a_late, f_late)
        },
    );
    // The late half's backward state after its first row, for the early half's free response.
    let s = &mid.s;
    let end = [0, 1].map(|j| mid.q * late.s[j] + s[0] * late.phi[j].x + s[1] * late.phi[j].y);
    let (h_early, h_late) = (m / 2, (n - m) / 2);
    let (a1, a2) = a_early.split_at(h_early);
    let (f1, f2) = f_early.split_at(h_early);
    let (o1, o2) = o_early.split_at_mut(h_early);
    let (a3, a4) = a_late.split_at(h_late);
    let (f3, f4) = f_late.split_at(h_late);
    let (o3, o4) = o_late.split_at_mut(h_late);
    rayon::join(
        || {
            rayon::join(
                || add_free_response(&end, a1, f1, o1, world),
                || add_free_response(&end, a2, f2, o2, world),
            )
        },
        || {
            rayon::join(
                || finish_late(&mid, a3, f3, o3, world),
                || finish_late(&mid, a4, f4, o4, world),
            )
        },
    );
}

/// The end of the early forward half: the attitude of its last sample and the Butterworth's
/// state after it.
struct HalfEnd {
    q: UnitQuaternion<f64>,
    s: [Vector3<f64>; 2],
}

/// The late half's backward pass after its first row, in the parts that the early half's end
/// `s_m` is not yet known for: the delay elements of the pass over the zero-state output (`s`),
/// and those of the passes over `Φ_k`'s two entries that multiply `s_m`'s `s1` and `s2` (`phi[j]`
/// the j-th delay element, x for `s1`'s entry, y for `s2`'s).
struct LateEnd {
    s: [Vector3<f64>; 2],
    phi: [Vector2<f64>; 2],
}

/// The step `dt` reaching sample `k` (0 for the first).
#[inline(always)]
fn step_dt(inputs: &Inputs<'_>, k: usize) -> f64 {
    if k == 0 {
        0.0
    } else {
        inputs.t[k] - inputs.t[k - 1]
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// The forward pass: strapdown from `q` (sample k integrates (t_k−1, t_k] with bias k, as the
    /// online step) into `out`, and the specific force in `I` filtered forward into `a_i`. With
    /// `phi` empty, over the rows from the first on (`a_i.len()` of them) from the steady state of
    /// the first sample; otherwise over the last `a_i.len()` rows (the late half) from a zero
    /// state, with each row's `Φ_k` (the map from the state before the half to the state before
    /// row k; its first row, the output's) in `phi`.
    fn forward<'a>(
        p: &RobustParams,
        q: UnitQuaternion<f64>,
        inputs: &Inputs<'a>,
        bias: &[[f64; 3]],
        a_i: &mut [[f64; 3]],
        phi: &mut [[f64; 3]],
        out: &mut [[f64; 4]],
    ) -> HalfEnd {
        let n = inputs.t.len();
        let first = if phi.is_empty() { 0 } else { n - a_i.len() };
        let mut q = q;
        let mut coefs = Coefs::new(p, step_dt(inputs, first.max(1).min(n - 1)));
        let mut cache = CoefsCache::new(coefs);
        let (mut s1, mut s2) = if first == 0 {
            coefs.steady(q * row(&inputs.accel[0]))
        } else {
            (Vector3::zeros(), Vector3::zeros())
        };
        let mut map = [[1.0, 0.0], [0.0, 1.0]];
        // The late half continues the early half's last step (one pass over the record, split).
        let mut prev_dt = step_dt(inputs, first.saturating_sub(1).max(1).min(n - 1));
        for (j, (a, o)) in a_i.iter_mut().zip(out.iter_mut()).enumerate() {
            let k = first + j;
            if k > 0 {
                let dt = step_dt(inputs, k);
                q = compose(&q, &exp_step(&((row(&inputs.gyro[k]) - row(&bias[k])) * dt)));
                coefs = cache.for_dt(p, dt);
                if let Some(m) = carry(p, &coefs, prev_dt) {
                    m.apply(&mut s1, &mut s2);
                    map = m.apply_map(map);
                }
                prev_dt = dt;
            }
            *o = q.coords.into();
            *a = coefs.butter(q * row(&inputs.accel[k]), &mut s1, &mut s2).into();
            if let Some(f) = phi.get_mut(j) {
                *f = [map[0][0], map[0][1], 0.0];
                map = coefs.free_step(map);
            }
        }
        HalfEnd { q, s: [s1, s2] }
    }
}

/// The coefficients of the backward step reaching sample `k` over (t_k, t_k+1] (the last
/// sample's own step at the end, where the pass starts).
#[inline(always)]
fn back_coefs(p: &RobustParams, inputs: &Inputs<'_>, cache: &mut CoefsCache, k: usize) -> Coefs {
    let n = inputs.t.len();
    cache.for_dt(p, step_dt(inputs, (k + 1).min(n - 1)))
}

/// A cache holding the coefficients the backward pass starts with at row `last`.
fn back_cache(p: &RobustParams, inputs: &Inputs<'_>, last: usize) -> CoefsCache {
    CoefsCache::new(Coefs::new(p, step_dt(inputs, (last + 1).min(inputs.t.len() - 1))))
}

/// `out`'s attitude (internal ENU) tilted so that `a` points up, written in `world` when given.
#[inline(always)]
fn tilted(a: &Vector3<f64>, out: &mut [f64; 4], world: Option<World>) {
    let mut q = quat(out);
    if let Some(tilt) = to_up(a) {
        q = tilt * q;
    }
    *out = world.map_or(q, |w| to_world(w, &q)).coords.into();
}

crate::simd_dispatch! {
    widest = avx2;
    /// The backward pass over the whole record from the steady state of its last input, tilting
    /// each attitude as it reaches it.
    fn backward<'a>(
        p: &RobustParams,
        inputs: &Inputs<'a>,
        a_i: &[[f64; 3]],
        out: &mut [[f64; 4]],
        world: Option<World>,
    ) -> () {
        let last = a_i.len() - 1;
        let mut cache = back_cache(p, inputs, last);
        let start = back_coefs(p, inputs, &mut cache, last);
        let (mut s1, mut s2) = start.steady(row(&a_i[last]));
        let mut prev_dt = start.dt;
        for (k, (a, o)) in a_i.iter().zip(out.iter_mut()).enumerate().rev() {
            let coefs = back_coefs(p, inputs, &mut cache, k);
            if let Some(m) = carry(p, &coefs, prev_dt) {
                m.apply(&mut s1, &mut s2);
            }
            prev_dt = coefs.dt;
            tilted(&coefs.butter(row(a), &mut s1, &mut s2), o, world);
        }
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// The late half's backward pass (rows from `first` to the end), from the steady state of
    /// its last input, over its zero-state output `a_i` and the two entries of `Φ_k` in `phi`,
    /// each replaced by its filtered value.
    fn backward_late<'a>(
        p: &RobustParams,
        inputs: &Inputs<'a>,
        first: usize,
        a_i: &mut [[f64; 3]],
        phi: &mut [[f64; 3]],
    ) -> LateEnd {
        let last = a_i.len() - 1;
        let mut cache = back_cache(p, inputs, first + last);
        let c = back_coefs(p, inputs, &mut cache, first + last);
        let (mut s1, mut s2) = c.steady(row(&a_i[last]));
        // The two entries of Φ_k as one two-lane channel.
        let (mut g1, mut g2) = c.steady(Vector2::new(phi[last][0], phi[last][1]));
        let mut prev_dt = c.dt;
        for (j, (a, m)) in a_i.iter_mut().zip(phi.iter_mut()).enumerate().rev() {
            let coefs = back_coefs(p, inputs, &mut cache, first + j);
            if let Some(map) = carry(p, &coefs, prev_dt) {
                map.apply(&mut s1, &mut s2);
                map.apply(&mut g1, &mut g2);
            }
            prev_dt = coefs.dt;
            *a = coefs.butter(row(a), &mut s1, &mut s2).into();
            let g = coefs.butter(Vector2::new(m[0], m[1]), &mut g1, &mut g2);
            *m = [g.x, g.y, 0.0];
        }
        LateEnd { s: [s1, s2], phi: [g1, g2] }
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// The early half's backward pass from a zero state (rows 0..a_i.len(), into `a_i`), and in
    /// `free` the first row of the map from the late half's end state to each sample's state.
    fn backward_zero_state<'a>(
        p: &RobustParams,
        inputs: &Inputs<'a>,
        a_i: &mut [[f64; 3]],
        free: &mut [[f64; 3]],
    ) -> () {
        let mut cache = back_cache(p, inputs, a_i.len() - 1);
        let (mut s1, mut s2) = (Vector3::zeros(), Vector3::zeros());
        let mut psi = [[1.0, 0.0], [0.0, 1.0]];
        // The late half's first row (`a_i.len()`) was the step before this half's last.
        let mut prev_dt = step_dt(inputs, (a_i.len() + 1).min(inputs.t.len() - 1));
        for (k, (a, f)) in a_i.iter_mut().zip(free.iter_mut()).enumerate().rev() {
            let coefs = back_coefs(p, inputs, &mut cache, k);
            if let Some(m) = carry(p, &coefs, prev_dt) {
                m.apply(&mut s1, &mut s2);
                psi = m.apply_map(psi);
            }
            prev_dt = coefs.dt;
            *f = [psi[0][0], psi[0][1], 0.0];
            *a = coefs.butter(row(a), &mut s1, &mut s2).into();
            psi = coefs.free_step(psi);
        }
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// Early rows made whole: their zero-state backward output plus the free response of the
    /// late half's backward state `end`; the attitudes tilted.
    fn add_free_response(
        end: &[Vector3<f64>; 2],
        a_i: &[[f64; 3]],
        free: &[[f64; 3]],
        out: &mut [[f64; 4]],
        world: Option<World>,
    ) -> () {
        for ((a, f), o) in a_i.iter().zip(free).zip(out.iter_mut()) {
            tilted(&(row(a) + end[0] * f[0] + end[1] * f[1]), o, world);
        }
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// Late rows made whole: the attitude `q_m−1 ⊗ r_k` and the filtered specific force, the
    /// zero-state part turned by `q_m−1` plus the early half's end state through the filtered
    /// entries of `Φ_k`; the attitudes tilted.
    fn finish_late(
        mid: &HalfEnd,
        a_i: &[[f64; 3]],
        phi: &[[f64; 3]],
        out: &mut [[f64; 4]],
        world: Option<World>,
    ) -> () {
        for ((a, f), o) in a_i.iter().zip(phi).zip(out.iter_mut()) {
            *o = compose(&mid.q, &quat(o)).coords.into();
            tilted(&(mid.q * row(a) + mid.s[0] * f[0] + mid.s[1] * f[1]), o, world);
        }
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// 9D, stage 2: the heading loop of the online step alone (the field's gate, its reference
    /// learning and the heading filter, [`super::step::magnetometer`]) on the zero-phase attitudes `base`
    /// (internal ENU) in place of each pass's own inclination: forward from `start`, or
    /// (`backward`) from the last sample on an uninitialised state, each interval with the gyro
    /// sample the online pass would integrate it with. The heading after each sample into `out`
    /// (its pair `(cos ψ/2, sin ψ/2)` and its angle ψ), in forward order.
    fn heading_pass<'a>(
        p: &RobustParams,
        start: &RobustState,
        inputs: &Inputs<'a>,
        mags: &[[f64; 3]],
        base: &[[f64; 4]],
        backward: bool,
        out: &mut [[f64; 3]],
    ) -> () {
        let n = base.len();
        let mut s = *start;
        let mut cache = CoefsCache::new(Coefs::new(p, 0.0));
        // The interval reached by the pass's i-th sample, k: (t_k−1, t_k] forward, (t_k, t_k+1]
        // backward, both with the later gyro sample (as `Reversed`), the other end `other`.
        let reached = |i: usize| {
            if backward {
                (n - 1 - i, (n - i).min(n - 1))
            } else {
                (i, i.saturating_sub(1))
            }
        };
        // A block's fields first (independent samples: their roots, divisions and `atan2`
        // overlap), then the gate and the heading in order; the same operations per sample as
        // the online step's `magnetometer`, bit for bit.
        let mut fields = [Field::default(); HEADING_BLOCK];
        for first in (0..n).step_by(HEADING_BLOCK) {
            let block = first..(first + HEADING_BLOCK).min(n);
            for (i, f) in block.clone().zip(fields.iter_mut()) {
                let (k, other) = reached(i);
                *f = Field::new(p, &(quat(&base[k]) * row(&mags[k])), &row(&inputs.gyro[k.max(other)]));
            }
            for (i, f) in block.zip(fields.iter()) {
                let (k, other) = reached(i);
                if !s.initialized {
                    set_heading(&mut s, 0.0);
                    s.initialized = true;
                    s.heading_pending = true;
                }
                if s.heading_pending {
                    start_heading(&mut s, &(quat(&base[k]) * row(&mags[k])));
                }
                let coefs = cache.for_dt(p, (inputs.t[k] - inputs.t[other]).abs());
                if let Some((gain, err)) = heading_error(p, &coefs, &mut s, f) {
                    turn_heading(&mut s, gain * err);
                }
                out[k] = [s.heading.x, s.heading.y, s.heading_angle];
            }
        }
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// 9D: the heading `h = h_f + w_k wrap(h_b − h_f)` of the two heading passes (`fwd`, `bwd`,
    /// about the vertical of `out`'s zero-phase attitudes, internal ENU) put on `out` and written
    /// in `world`: `Rz(h) = Rz(w_k Δ) ⊗ Rz(h_f)` on the forward pass's half-angle pair, `Δ` the
    /// difference of the passes' angles, wrapped (no `atan2`: it was that of the pair
    /// `Rz(h_b) ⊗ Rz(h_f)⁻¹`, the same to rounding).
    fn fuse_headings(
        world: World,
        fwd: &[[f64; 3]],
        bwd: &[[f64; 3]],
        weights: &[f64],
        out: &mut [[f64; 4]],
    ) -> () {
        for (k, o) in out.iter_mut().enumerate() {
            let ([c, s, angle_f], angle_b) = (fwd[k], bwd[k][2]);
            let pair = Vector2::new(c, s);
            let delta = wrap(angle_b - angle_f);
            *o = to_world(world, &yawed(&turn(&pair, weights[k] * delta), &quat(o))).coords.into();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The zero-phase filter in two halves ([`zero_phase`] from [`ZERO_PHASE_SPLIT_FROM`] rows on)
    /// gives the attitudes of one sequential forward and backward pass to rounding, on a record of
    /// uneven steps, odd length and a bias, in both worlds; the record starts tilted and
    /// accelerating, so the early half's end state matters. The tolerance, 2e-9 per quaternion
    /// component, is the filter's: its poles lie within dt/τ of 1, where the direct form's delay
    /// elements are ±the output (±7 m/s² here) and cancel, so rounding is amplified by a few
    /// hundred either way; measured 1.6e-10. The free response of either half's end state left
    /// out gives 1.3, and the early half's backward pass one step's coefficients off 2e-6.
    #[test]
    fn zero_phase_in_two_halves_equals_one_sequential_pass() {
        let n = 3 * ZERO_PHASE_SPLIT_FROM + 1;
        let t: Vec<f64> = (0..n)
            .map(|k| k as f64 / 200.0 + 1e-4 * ((k * 7919) % 13) as f64 / 13.0)
            .collect();
        let wave = |s: f64, a: [f64; 3], w: [f64; 3]| [0, 1, 2].map(|i| a[i] * (w[i] * s + 0.3).sin());
        let gyro: Vec<[f64; 3]> = t.iter().map(|&s| wave(s, [1.3, 0.9, 2.0], [1.1, 0.7, 1.3])).collect();
        let accel: Vec<[f64; 3]> = t
            .iter()
            .map(|&s| {
                let a = wave(s, [3.0, 2.0, 1.0], [0.9, 2.3, 1.7]);
                [a[0] + 1.5, a[1], 9.7 + a[2]]
            })
            .collect();
        let bias = vec![[0.01, -0.02, 0.005]; n];
        let inputs = Inputs {
            t: &t,
            gyro: &gyro,
            accel: &accel,
            mag: None,
        };
        let p = RobustParams::default();
        let q0 = initial_attitude(World::Enu, &row(&accel[0]), None);
        for world in [None, Some(World::Ned)] {
            let (mut a, mut free) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
            let mut one = vec![[0.0; 4]; n];
            forward(&p, q0, &inputs, &bias, &mut a, &mut [], &mut one);
            backward(&p, &inputs, &a, &mut one, world);
            let mut halves = vec![[0.0; 4]; n];
            zero_phase(&p, q0, &inputs, &bias, &mut a, &mut free, &mut halves, world);
            let worst = one
                .iter()
                .zip(&halves)
                .flat_map(|(x, y)| (0..4).map(move |i| (x[i] - y[i]).abs()))
                .fold(0.0, f64::max);
            assert!(worst < 2e-9, "{world:?}: {worst:e}");
            assert!(one != halves, "the halves ran (rounding differs somewhere)");
        }
    }

    /// The backward pass fed in parts of [`REVERSED_PART`] rows gives the track of one run over
    /// the whole reversed record, bit for bit, 6D and 9D, on a record of two and a half parts.
    #[test]
    fn backward_pass_in_parts_equals_one_run() -> Result<()> {
        let n = 2 * REVERSED_PART + REVERSED_PART / 2;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / 285.714).collect();
        let wave = |s: f64, a: [f64; 3], w: [f64; 3]| [0, 1, 2].map(|i| a[i] * (w[i] * s).sin());
        let gyro: Vec<[f64; 3]> = t.iter().map(|&s| wave(s, [0.3, 0.2, 0.5], [1.1, 0.7, 1.3])).collect();
        let accel: Vec<[f64; 3]> = t
            .iter()
            .map(|&s| {
                let a = wave(s, [0.5, 0.4, 0.2], [0.9, 0.3, 1.7]);
                [a[0], a[1], 9.81 + a[2]]
            })
            .collect();
        let mags: Vec<[f64; 3]> = t
            .iter()
            .map(|&s| [20.0 * (0.2 * s).cos(), 20.0 * (0.2 * s).sin(), -40.0])
            .collect();
        let f = Robust::new(RobustParams::default(), World::Enu)?;
        for mag in [None, Some(&mags[..])] {
            let inputs = Inputs {
                t: &t,
                gyro: &gyro,
                accel: &accel,
                mag,
            };
            let mut parts = unposed(n);
            f.run_reversed(&inputs, &mut parts, &Cancel::new())?;
            let mut whole = Reversed::default();
            whole.fill(&inputs, 0..n);
            let mut one = unposed(n);
            let mut out = Outputs {
                q: &mut [],
                bias: &mut one.bias,
                bias_sigma: &mut one.bias_sigma,
                rest: &mut one.rest,
                mag_disturbed: &mut one.mag_disturbed,
            };
            f.run_checked(
                &mut RobustState::default(),
                &whole.inputs(),
                (0, false),
                false,
                &mut out,
                &Cancel::new(),
            )?;
            assert!(parts == one, "9D: {}", mag.is_some());
            assert!(one.bias.iter().any(|b| *b != [0.0; 3]), "the pass ran");
        }
        Ok(())
    }

    /// A cancelled smoother stops in its first stage (both passes poll), on one thread and on
    /// two; an uncancelled flag gives `smooth`'s result.
    #[test]
    #[allow(clippy::unwrap_used)]
    fn a_cancelled_smoother_stops() -> Result<()> {
        let n = 3_000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / 200.0).collect();
        let gyro: Vec<[f64; 3]> = t.iter().map(|&s| [0.3 * (1.1 * s).sin(), 0.2, 0.1]).collect();
        let accel: Vec<[f64; 3]> = t.iter().map(|&s| [0.5 * (0.9 * s).sin(), 0.0, 9.81]).collect();
        let inputs = Inputs {
            t: &t,
            gyro: &gyro,
            accel: &accel,
            mag: None,
        };
        let f = Robust::new(RobustParams::default(), World::Enu)?;
        let cancel = Cancel::new();
        cancel.cancel();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut track = Track::new(n);
            let e = pool
                .install(|| f.smooth_cancellable(&mut RobustState::default(), &inputs, &mut track.outputs(), &cancel))
                .unwrap_err();
            assert!(
                matches!(e, crate::Error::Interrupted { index: 0 }),
                "{threads} threads: {e}"
            );
        }
        let (mut a, mut b) = (Track::new(n), Track::new(n));
        f.smooth(&mut RobustState::default(), &inputs, &mut a.outputs())?;
        f.smooth_cancellable(&mut RobustState::default(), &inputs, &mut b.outputs(), &Cancel::new())?;
        assert_eq!(a, b);
        Ok(())
    }
}
