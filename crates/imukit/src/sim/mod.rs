//! IMU simulation: trajectories in closed form ([`Motion`]), their exact ideal measurements
//! ([`evaluate`]: body rate and specific force `Rᵀ(a − g)`), and a seeded sensor error model
//! ([`measure`], [`SensorModel`]: white noise, bias random walk, Gauss–Markov, constant and
//! turn-on bias, scale factor and misalignment, saturation, quantisation).

mod motion;
mod sensor;

pub use motion::{Kinematics, Motion, MotionKind, LANES};
pub use sensor::{measure, measure_in_place, measure_in_place_cancellable, SensorModel, CHUNK};

use nalgebra::{UnitQuaternion, Vector3};
use rayon::prelude::*;

use crate::error::{Cancel, Error, Result};

/// Output buffers of [`evaluate`], flat row-major: `position`, `velocity`, `gyro` (body rate) and
/// `accel` (specific force) `3N`, `rotation` `4N` as `[x, y, z, w]` quaternions of `R_wb`.
pub struct Truth<'a> {
    /// Positions \[m\].
    pub position: &'a mut [f64],
    /// Velocities [m/s].
    pub velocity: &'a mut [f64],
    /// `R_wb` quaternions `[x, y, z, w]`.
    pub rotation: &'a mut [f64],
    /// Ideal gyro readings [rad/s].
    pub gyro: &'a mut [f64],
    /// Ideal accelerometer readings [m/s²].
    pub accel: &'a mut [f64],
}

/// Evaluates `motion` at the times `t` (finite) into `out`, in parallel. A motion whose values
/// leave float64 at some sample (huge amplitudes or rates) is an [`Error::NonFinite`] naming the
/// first such sample, in the argument `trajectory`.
pub fn evaluate(motion: &Motion, t: &[f64], gravity: &Vector3<f64>, out: Truth<'_>) -> Result<()> {
    evaluate_cancellable(motion, t, gravity, out, &Cancel::new())
}

/// Whether every value is finite: `v · 0` is 0 for a finite `v` and NaN otherwise, and a NaN
/// stays in a sum. Eight independent sums, so the pass is not one chain of dependent additions
/// (the rows are still in cache).
pub(crate) fn all_finite(values: &[f64]) -> bool {
    let mut lanes = [0.0; 8];
    let blocks = values.chunks_exact(8);
    let rest = blocks.remainder();
    for block in blocks {
        for (lane, v) in lanes.iter_mut().zip(block) {
            *lane += v * 0.0;
        }
    }
    lanes.iter().chain(rest).all(|v| v.is_finite())
}

/// [`evaluate`], stopping with [`Error::Interrupted`] when `cancel` is set (polled per chunk of
/// 4096 rows).
pub fn evaluate_cancellable(
    motion: &Motion,
    t: &[f64],
    gravity: &Vector3<f64>,
    out: Truth<'_>,
    cancel: &Cancel,
) -> Result<()> {
    let n = t.len();
    for (name, len, width) in [
        ("position", out.position.len(), 3),
        ("velocity", out.velocity.len(), 3),
        ("rotation", out.rotation.len(), 4),
        ("gyro", out.gyro.len(), 3),
        ("accel", out.accel.len(), 3),
    ] {
        if len != width * n {
            return Err(Error::RowCount {
                input: n,
                output: len / width,
            }
            .in_argument(name));
        }
    }
    if let Some(k) = t.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite { index: k }.in_argument("t"));
    }
    const ROWS: usize = 4096;
    // Each chunk reports its first row with a value beyond float64, so the error names the first
    // such sample whatever the thread count.
    let bad: Vec<Option<usize>> = t
        .par_chunks(ROWS)
        .zip(out.position.par_chunks_mut(3 * ROWS))
        .zip(out.velocity.par_chunks_mut(3 * ROWS))
        .zip(out.rotation.par_chunks_mut(4 * ROWS))
        .zip(out.gyro.par_chunks_mut(3 * ROWS))
        .zip(out.accel.par_chunks_mut(3 * ROWS))
        .enumerate()
        .map(|(c, (((((ts, p), v), q), w), a))| {
            cancel.check(0)?;
            truth_rows(motion, gravity, ts, p, v, q, w, a);
            if [&*p, &*v, &*q, &*w, &*a].iter().all(|x| all_finite(x)) {
                return Ok(None);
            }
            let row = (0..ts.len()).find(|&i| {
                let rows = [&p[3 * i..3 * i + 3], &v[3 * i..3 * i + 3], &q[4 * i..4 * i + 4]];
                !rows
                    .iter()
                    .chain([&w[3 * i..3 * i + 3], &a[3 * i..3 * i + 3]].iter())
                    .all(|x| all_finite(x))
            });
            Ok(row.map(|i| c * ROWS + i))
        })
        .collect::<Result<_>>()?;
    match bad.into_iter().flatten().next() {
        Some(index) => Err(Error::NonFinite { index }.in_argument("trajectory")),
        None => Ok(()),
    }
}

crate::simd_dispatch! {
    /// One chunk of [`evaluate_cancellable`]: the truth at each stamp of `ts` into the rows of
    /// position `p`, velocity `v`, rotation `q`, body rate `w` and specific force `a`, per
    /// instruction-set path (the same operations on each: equal bit for bit).
    #[allow(clippy::too_many_arguments)] // one chunk's five output rows
    fn truth_rows(
        motion: &Motion,
        gravity: &Vector3<f64>,
        ts: &[f64],
        p: &mut [f64],
        v: &mut [f64],
        q: &mut [f64],
        w: &mut [f64],
        a: &mut [f64],
    ) -> () {
        // Four stamps at a time; the last lanes of a short block repeat its last stamp, and
        // each lane depends on its stamp alone (Motion::at_lanes).
        for (b, block) in ts.chunks(LANES).enumerate() {
            let stamps = std::array::from_fn(|k| block[k.min(block.len() - 1)]);
            for (j, x) in motion.at_lanes(stamps).iter().take(block.len()).enumerate() {
                let i = b * LANES + j;
                p[3 * i..3 * i + 3].copy_from_slice(x.position.as_slice());
                v[3 * i..3 * i + 3].copy_from_slice(x.velocity.as_slice());
                let quat = UnitQuaternion::from_rotation_matrix(&x.rotation);
                q[4 * i..4 * i + 4].copy_from_slice(quat.coords.as_slice());
                w[3 * i..3 * i + 3].copy_from_slice(x.body_rate.as_slice());
                a[3 * i..3 * i + 3].copy_from_slice(x.specific_force(gravity).as_slice());
            }
        }
    }
}

/// Turns the ideal readings of a trajectory given in a world frame that rotates at `earth_rate`
/// (world axes, rad/s; e.g. [`crate::earth::LocalLevel::earth_rate`]) into what the sensor reads,
/// in place: the gyro adds the world's rate seen in the body, `Rᵀ ω`, and the specific force the
/// Coriolis term, `Rᵀ (2 ω × v)` (with the frame's gravity already in `accel`). Rows: `rotation`
/// `[x, y, z, w]` quaternions of `R_wb`, `velocity`, `gyro`, `accel` (the same count).
pub fn in_rotating_world(
    earth_rate: &Vector3<f64>,
    rotation: &[[f64; 4]],
    velocity: &[[f64; 3]],
    gyro: &mut [[f64; 3]],
    accel: &mut [[f64; 3]],
) -> Result<()> {
    let n = rotation.len();
    for (name, len) in [
        ("velocity", velocity.len()),
        ("gyro", gyro.len()),
        ("accel", accel.len()),
    ] {
        if len != n {
            return Err(Error::RowCount { input: n, output: len }.in_argument(name));
        }
    }
    let coriolis = |q: &[f64; 4], v: &[f64; 3], w: &mut [f64; 3], a: &mut [f64; 3]| {
        let r = UnitQuaternion::new_normalize(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]));
        let to_body = |x: Vector3<f64>| r.inverse_transform_vector(&x);
        let dw = to_body(*earth_rate);
        let da = to_body(earth_rate.cross(&Vector3::from(*v)) * 2.0);
        *w = (Vector3::from(*w) + dw).into();
        *a = (Vector3::from(*a) + da).into();
    };
    rotation
        .par_iter()
        .zip(velocity.par_iter())
        .zip(gyro.par_iter_mut().zip(accel.par_iter_mut()))
        .for_each(|((q, v), (w, a))| coriolis(q, v, w, a));
    Ok(())
}
