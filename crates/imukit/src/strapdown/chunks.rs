//! Long integrations in an inertial world, in parallel chunks.
//!
//! Every scheme's step is linear in `p` and `v`, turns with `R` on the left, and adds the constant
//! `g`: from the state `(p_s, v_s, R_s)` at `t_s`, the state at `t_s + τ` is
//!
//! ```text
//! R = R_s R',   v = v_s + g τ + R_s v',   p = p_s + v_s τ + ½ g τ² + R_s p'
//! ```
//!
//! with `(p', v', R')` the same scheme run over the same samples from `(0, 0, I)` without gravity
//! (by induction over the steps of the module table: each adds `R_k`-rotated readings and `g` to
//! `v`, `v h` to `p`, and multiplies `R` on the right). So chunks of at most [`CHUNK`] steps run
//! at once from `(0, 0, I)` (the first from the initial state itself), each chunk's start state
//! follows from the one before in order, and each stored row is then turned into the world by its
//! chunk's start state, again in parallel. The chunks depend on N only, so the result does not
//! depend on the thread count; it differs from one sequential run by rounding (1e-12 relative,
//! tested). A rotating world's turn and Coriolis terms are not of this form: it runs
//! sequentially.

use std::ops::Range;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rayon::prelude::*;

use super::{Options, StatesOut, Stepper};
use crate::imu::{NavState, Samples};
use crate::{quat, Cancel, Result};

/// Most steps per chunk: long enough that the start states' pass is noise.
pub const CHUNK: usize = 1 << 15;

/// Whether a run of `n` samples with `options` goes in chunks: an inertial world and more than
/// two chunks' worth of steps.
pub(super) fn chunked(n: usize, options: &Options) -> bool {
    options.earth_rate == Vector3::zeros() && n > 2 * CHUNK + 1
}

/// The steps of each chunk for `n` samples: the fewest chunks of at most [`CHUNK`] steps, equal
/// to within one step.
fn chunk_steps(n: usize) -> Vec<Range<usize>> {
    let steps = n - 1;
    let m = steps.div_ceil(CHUNK);
    (0..m).map(|c| c * steps / m..(c + 1) * steps / m).collect()
}

/// `x` (a state after `τ` from `(0, 0, I)` without gravity) started from `start` instead, with
/// gravity `g` (module docs); `r` is `start`'s rotation matrix (one per chunk: a matrix turns a
/// vector in 9 multiply-adds, a quaternion in about 30).
#[inline(always)]
fn from_start(start: &NavState, r: &Matrix3<f64>, x: &NavState, tau: f64, g: &Vector3<f64>) -> NavState {
    NavState {
        position: start.position + start.velocity * tau + g * (0.5 * tau * tau) + r * x.position,
        velocity: start.velocity + g * tau + r * x.velocity,
        rotation: UnitQuaternion::new_unchecked(quat::multiply(start.rotation.quaternion(), x.rotation.quaternion())),
    }
}

crate::simd_dispatch! {
    /// The rows of one chunk, stored from `(0, 0, I)` at the time `t0`, turned into the world
    /// from `start` ([`from_start`]); `t` the rows' times. Per instruction-set path (the same
    /// operations: equal bit for bit).
    fn to_world(out: &mut StatesOut<'_>, start: &NavState, t: &[f64], t0: f64, g: &Vector3<f64>) -> () {
        let r = start.rotation.to_rotation_matrix().into_inner();
        for (j, &tk) in t.iter().enumerate() {
            let world = from_start(start, &r, &out.load(j), tk - t0, g);
            out.store(j, &world);
        }
    }
}

/// The rows `[first, first + len)` of `out`, as their own output.
struct Rows<'a> {
    first: usize,
    out: Option<StatesOut<'a>>,
}

/// Integrates `samples` (N > 2 [`CHUNK`] + 1, an inertial world, row 0 already stored) from
/// `initial` in chunks, storing rows 1… in `out`; the state at the last sample.
pub(super) fn integrate(
    samples: &Samples<'_>,
    initial: &NavState,
    stepper: (&Stepper<'_>, &Stepper<'_>),
    out: Option<StatesOut<'_>>,
    cancel: &Cancel,
) -> Result<NavState> {
    let (with_gravity, without) = stepper;
    let chunks = chunk_steps(samples.t.len());
    let rows = split(out, &chunks);
    let identity = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
    };
    let mut parts: Vec<(Rows<'_>, NavState)> = chunks
        .par_iter()
        .zip(rows)
        .enumerate()
        .map(|(c, (steps, mut rows))| {
            let (stepper, x0) = if c == 0 {
                (with_gravity, *initial)
            } else {
                (without, identity)
            };
            let end = stepper.run_steps(x0, steps.clone(), |k, _, next| {
                if let Some(out) = rows.out.as_mut() {
                    out.store(k + 1 - rows.first, next);
                }
                cancel.check(k)
            })?;
            Ok((rows, end))
        })
        .collect::<Result<_>>()?;
    let g = with_gravity.options.gravity;
    let t = samples.t;
    // Each chunk's start state, in order: the first chunk's end is in the world already.
    let mut starts = Vec::with_capacity(chunks.len());
    let mut state = parts[0].1;
    for (steps, (_, end)) in chunks.iter().zip(&parts).skip(1) {
        starts.push(state);
        let r = state.rotation.to_rotation_matrix().into_inner();
        state = from_start(&state, &r, end, t[steps.end] - t[steps.start], &g);
    }
    parts
        .par_iter_mut()
        .skip(1)
        .zip(starts.par_iter().zip(&chunks[1..]))
        .for_each(|((rows, _), (start, steps))| {
            if let Some(out) = rows.out.as_mut() {
                to_world(out, start, &t[steps.start + 1..=steps.end], t[steps.start], &g);
            }
        });
    Ok(state)
}

/// `out`'s rows 1… cut at the chunks' ends: chunk `[a, b)` writes rows `a + 1 ..= b`.
fn split<'a>(out: Option<StatesOut<'a>>, chunks: &[Range<usize>]) -> Vec<Rows<'a>> {
    let Some(out) = out else {
        return chunks
            .iter()
            .map(|s| Rows {
                first: s.start + 1,
                out: None,
            })
            .collect();
    };
    let (mut pv, mut q) = (&mut out.position_velocity[1..], &mut out.rotation[1..]);
    let mut rows = Vec::with_capacity(chunks.len());
    for steps in chunks {
        let (pv_c, pv_rest) = std::mem::take(&mut pv).split_at_mut(steps.len());
        let (q_c, q_rest) = std::mem::take(&mut q).split_at_mut(steps.len());
        (pv, q) = (pv_rest, q_rest);
        rows.push(Rows {
            first: steps.start + 1,
            out: Some(StatesOut {
                position_velocity: pv_c,
                rotation: q_c,
            }),
        });
    }
    rows
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use crate::imu::Bias;
    use crate::strapdown::{integrate_cancellable, Scheme};

    /// `n` samples of a turning, accelerating body at 200 Hz with jittered stamps.
    fn stream(n: usize) -> (Vec<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let t: Vec<f64> = (0..n)
            .map(|k| k as f64 * 0.005 + 1e-4 * (k as f64 * 0.37).sin())
            .collect();
        let gyro = t
            .iter()
            .map(|s| [0.3 * (1.1 * s).sin(), 0.2 * (0.7 * s).cos(), 0.5 * (1.3 * s).sin()]);
        let accel = t
            .iter()
            .map(|s| [0.5 * (0.9 * s).sin(), 0.4 * (0.3 * s).cos(), 9.81 + 0.2 * s.cos()]);
        (t.clone(), gyro.collect(), accel.collect())
    }

    /// Every stored row of the chunked run within 1e-12 relative of one sequential run (four
    /// schemes), and bit for bit the same on one and two threads.
    #[test]
    fn chunks_equal_one_sequential_run_and_ignore_the_thread_count() {
        let n = 2 * CHUNK + 1235;
        let (t, gyro, accel) = stream(n);
        let samples = Samples::new(&t, &gyro, &accel).expect("valid samples");
        let initial = NavState {
            position: Vector3::new(1.0, -2.0, 0.5),
            velocity: Vector3::new(0.3, 0.1, -0.2),
            rotation: UnitQuaternion::from_euler_angles(0.2, -0.1, 0.7),
        };
        let bias = Bias {
            gyro: Vector3::new(0.01, -0.02, 0.005),
            accel: Vector3::new(0.1, 0.0, -0.1),
        };
        for scheme in [Scheme::LieEuler, Scheme::Midpoint, Scheme::Rk4, Scheme::Exp] {
            let options = Options {
                scheme,
                ..Options::default()
            };
            assert!(chunked(n, &options));
            let rows = |threads: usize| {
                let (mut pv, mut q) = (vec![[0.0; 6]; n], vec![[0.0; 4]; n]);
                let out = StatesOut {
                    position_velocity: &mut pv,
                    rotation: &mut q,
                };
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                let end = pool
                    .install(|| integrate_cancellable(&samples, &initial, &bias, &options, Some(out), &Cancel::new()))
                    .expect("integrates");
                (pv, q, end)
            };
            let (pv, q, end) = rows(2);
            assert!(rows(1) == (pv.clone(), q.clone(), end), "{scheme:?}: thread count");
            let mut sequential = vec![initial; n];
            let last = Stepper::new(samples, bias, options)
                .run(initial, |k, _, next| {
                    sequential[k + 1] = *next;
                    Ok(())
                })
                .expect("integrates");
            let scale = sequential
                .iter()
                .fold(0.0_f64, |m, x| m.max(x.position.amax()).max(x.velocity.amax()));
            let mut worst = 0.0_f64;
            for (k, x) in sequential.iter().enumerate() {
                let p = &pv[k];
                let dp = (Vector3::new(p[0], p[1], p[2]) - x.position).amax();
                let dv = (Vector3::new(p[3], p[4], p[5]) - x.velocity).amax();
                let dq = UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q[k][3], q[k][0], q[k][1], q[k][2]))
                    .angle_to(&x.rotation);
                worst = worst.max(dp.max(dv) / scale).max(dq);
            }
            assert!(worst < 1e-12, "{scheme:?}: rows off by {worst:e} relative");
            assert!(
                (end.position - last.position).amax() < 1e-12 * scale,
                "{scheme:?}: end state"
            );
            // Chunked for real: not the sequential run bit for bit.
            assert_ne!(end.position, last.position, "{scheme:?}");
        }
    }
}
