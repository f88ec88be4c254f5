//! Sensor extrinsics: the readings of an IMU mounted at a pose in the body frame, turned into the
//! readings the body origin would have (GTSAM's `body_P_sensor`).
//!
//! | item | convention |
//! |---|---|
//! | pose | [`SensorPose`]: `rotation` `R_bs` (sensor axes to body axes) and `lever_arm` `r` (the sensor's origin in body coordinates, metres) |
//! | gyro | `ω_b = R_bs (ω_s − b_g)`: every point of a rigid body turns at the same rate |
//! | accelerometer | `a_b = R_bs (a_s − b_a) − α_b × r − ω_b × (ω_b × r)`: the sensor at `p + R r` feels, besides the body's specific force, the tangential (`α × r`) and centripetal (`ω × (ω × r)`) accelerations of its lever arm (Titterton & Weston 2004, eq. 3.48; Groves 2013, eq. 2.165) |
//! | angular acceleration | estimated from the gyro: `α_k = (ω_{k+1} − ω_{k−1}) / (t_{k+1} − t_{k−1})`, the central difference (second order, exact for a rate quadratic in time on uniform stamps), one-sided at the first and last sample (first order) |
//! | biases | subtracted here, in the sensor frame, before the conversion; the body readings carry none |
//!
//! [`to_sensor`] is the inverse with an exact α, for the simulator. The body readings then integrate as any others; the result is exact for the conversion and as
//! accurate as the α estimate, whose error is `O(h²) α̈ × r` inside a record.

use nalgebra::{Matrix3, Vector3};

use crate::error::{Error, Result};
use crate::imu::{Bias, Samples};

/// The largest lever-arm component accepted \[m\] (about the Earth's radius).
pub const MAX_LEVER_ARM: f64 = 1e7;

/// The sensor's pose in the body frame (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPose {
    /// `R_bs`: sensor axes to body axes (a rotation matrix).
    pub rotation: Matrix3<f64>,
    /// The sensor's origin in body coordinates \[m\].
    pub lever_arm: Vector3<f64>,
}

impl SensorPose {
    /// Checks the values: finite, and `rotation` a rotation to 1e-9 (`|RᵀR − I| ≤ 1e-9`, det > 0).
    pub fn new(rotation: Matrix3<f64>, lever_arm: Vector3<f64>) -> Result<Self> {
        if !rotation.iter().chain(lever_arm.iter()).all(|v| v.is_finite()) {
            return Err(Error::NonFinite { index: 0 }.in_argument("body_from_sensor"));
        }
        let off = (rotation.transpose() * rotation - Matrix3::identity()).amax();
        if off > 1e-9 || rotation.determinant() <= 0.0 {
            return Err(Error::Parameter {
                name: "body_from_sensor",
                expected: "a rotation (|RᵀR − I| ≤ 1e-9, det > 0)",
                got: format!("|RᵀR − I| = {off:e}, det = {}", rotation.determinant()),
            });
        }
        // A lever arm longer than the Earth's radius is no mounting: refused before its
        // `ω×(ω×r)` terms overflow in the preintegration's bias Jacobian.
        if lever_arm.amax() > MAX_LEVER_ARM {
            return Err(Error::Parameter {
                name: "body_from_sensor",
                expected: "a lever arm within ±1e7 m",
                got: format!("{:e} m", lever_arm.amax()),
            });
        }
        Ok(Self { rotation, lever_arm })
    }
}

/// The body-origin readings of `samples` taken by a sensor at `pose`, biases removed (module
/// docs), into `gyro` and `accel` (one row per sample).
pub fn to_body(
    samples: &Samples<'_>,
    bias: &Bias,
    pose: &SensorPose,
    gyro: &mut [[f64; 3]],
    accel: &mut [[f64; 3]],
) -> Result<()> {
    let n = samples.t.len();
    for (name, len) in [("gyro", gyro.len()), ("accel", accel.len())] {
        if len != n {
            return Err(Error::RowCount { input: n, output: len }.in_argument(name));
        }
    }
    if !samples.first_ok() {
        return Err(samples.value_error());
    }
    for k in 0..n - 1 {
        if !samples.step_ok(k) {
            return Err(samples.value_error());
        }
    }
    let r = pose.rotation;
    let rate = |k: usize| r * (samples.gyro_at(k) - bias.gyro);
    for k in 0..n {
        let w = rate(k);
        let alpha = alpha_span(samples.t, k).map_or(Vector3::zeros(), |(lo, hi, dt)| (rate(hi) - rate(lo)) / dt);
        let arm = pose.lever_arm;
        let specific = r * (samples.accel_at(k) - bias.accel);
        let a = specific - alpha.cross(&arm) - w.cross(&w.cross(&arm));
        if !a.iter().all(|v| v.is_finite()) {
            return Err(Error::Overflow { index: k }.in_argument(overflow_culprit(&specific)));
        }
        gyro[k] = w.into();
        accel[k] = a.into();
    }
    Ok(())
}

/// The samples and span of sample `k`'s angular-acceleration difference (module docs):
/// `α_k = (ω_hi − ω_lo) / Δ` with `(lo, hi, Δ)`, central inside, one-sided at the first and last
/// sample; `None` for a single sample (no difference: `α = 0`).
pub fn alpha_span(t: &[f64], k: usize) -> Option<(usize, usize, f64)> {
    let (lo, hi) = (k.saturating_sub(1), (k + 1).min(t.len().saturating_sub(1)));
    (hi > lo).then(|| (lo, hi, t[hi] - t[lo]))
}

/// [`alpha_span`] as the weights of a linear map: `α_k = (ω_hi − ω_lo) · w` with `(lo, hi, w)`;
/// `(k, k, 0)` for a single sample.
pub fn alpha_weights(t: &[f64], k: usize) -> (usize, usize, f64) {
    alpha_span(t, k).map_or((k, k, 0.0), |(lo, hi, dt)| (lo, hi, 1.0 / dt))
}

/// `D(ω) = ∂(ω × (ω × r))/∂ω = −[ω × r]× − [ω]× [r]×`, the centripetal term's sensitivity to the
/// rate (from `δ(ω×(ω×r)) = δω×(ω×r) + ω×(δω×r)`; Titterton & Weston 2004, eq. 3.48): a gyro
/// error `δω` moves the body-origin reading of [`to_body`] by `−D δω`.
pub fn centripetal_sensitivity(rate: &Vector3<f64>, lever_arm: &Vector3<f64>) -> Matrix3<f64> {
    -crate::so3::hat(&rate.cross(lever_arm)) - crate::so3::hat(rate) * crate::so3::hat(lever_arm)
}

/// The input to blame when finite readings overflow in the conversion: the accelerometer when its
/// rotated reading did, else the rate in `ω×(ω×r)` (the lever arm is bounded by
/// [`MAX_LEVER_ARM`]), so that errors name what the user can change.
fn overflow_culprit(specific: &Vector3<f64>) -> &'static str {
    if specific.iter().all(|v| v.is_finite()) {
        "gyro"
    } else {
        "accel"
    }
}

/// The readings a sensor at `pose` takes on a body whose rate, specific force and angular
/// acceleration (body axes, one row per sample) are `gyro`, `accel` and `alpha`, in place: the
/// inverse of [`to_body`] with the α given, `ω_s = R_bsᵀ ω_b`, `f_s = R_bsᵀ (f_b + α × r + ω × (ω × r))`.
pub fn to_sensor(pose: &SensorPose, alpha: &[[f64; 3]], gyro: &mut [[f64; 3]], accel: &mut [[f64; 3]]) -> Result<()> {
    let n = alpha.len();
    for (name, len) in [("gyro", gyro.len()), ("accel", accel.len())] {
        if len != n {
            return Err(Error::RowCount { input: n, output: len }.in_argument(name));
        }
    }
    let (back, arm) = (pose.rotation.transpose(), pose.lever_arm);
    for ((w, a), dw) in gyro.iter_mut().zip(accel.iter_mut()).zip(alpha) {
        let (wb, dw) = (Vector3::from(*w), Vector3::from(*dw));
        *a = (back * (Vector3::from(*a) + dw.cross(&arm) + wb.cross(&wb.cross(&arm)))).into();
        *w = (back * wb).into();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn central_difference_is_exact_for_a_quadratic_rate_and_the_arm_terms_add_up() -> Result<()> {
        // ω_s(t) = (0.1 + 0.2t − 0.3t², 0.5t², −0.4 + t), uniform 10 ms steps; identity rotation
        let t: Vec<f64> = (0..50).map(|k| 0.01 * f64::from(k)).collect();
        let w_of = |s: f64| Vector3::new(0.1 + 0.2 * s - 0.3 * s * s, 0.5 * s * s, -0.4 + s);
        let dw_of = |s: f64| Vector3::new(0.2 - 0.6 * s, s, 1.0);
        let gyro: Vec<[f64; 3]> = t.iter().map(|&s| w_of(s).into()).collect();
        let accel = vec![[0.0, 0.0, 9.81]; t.len()];
        let samples = Samples::new(&t, &gyro, &accel)?;
        let arm = Vector3::new(0.3, -0.1, 0.2);
        let pose = SensorPose::new(Matrix3::identity(), arm)?;
        let (mut gb, mut ab) = (vec![[0.0; 3]; t.len()], vec![[0.0; 3]; t.len()]);
        to_body(&samples, &Bias::default(), &pose, &mut gb, &mut ab)?;
        for k in 1..t.len() - 1 {
            let (w, dw) = (w_of(t[k]), dw_of(t[k]));
            let expected = Vector3::new(0.0, 0.0, 9.81) - dw.cross(&arm) - w.cross(&w.cross(&arm));
            assert!((Vector3::from(ab[k]) - expected).amax() < 1e-12);
            assert_eq!(gb[k], gyro[k]);
        }
        Ok(())
    }

    #[test]
    fn an_overflow_names_the_rate_or_the_lever_arm() -> Result<()> {
        let t = [0.0, 0.01, 0.02];
        let accel = [[0.0, 0.0, 9.81]; 3];
        let (mut gb, mut ab) = ([[0.0; 3]; 3], [[0.0; 3]; 3]);
        for (rate, arm, name) in [(1e200, 0.3, "gyro"), (1e160, 1e6, "gyro")] {
            let gyro = [[rate, 0.0, 0.0], [0.0, rate, 0.0], [0.0, 0.0, rate]];
            let samples = Samples::new(&t, &gyro, &accel)?;
            let pose = SensorPose::new(Matrix3::identity(), Vector3::new(arm, arm, 0.0))?;
            let err = to_body(&samples, &Bias::default(), &pose, &mut gb, &mut ab);
            assert!(matches!(&err, Err(e) if e.argument() == Some(name)), "{err:?}");
        }
        Ok(())
    }

    #[test]
    fn to_sensor_inverts_to_body_for_a_constant_rate() -> Result<()> {
        // constant rate: the central difference's α is exact (zero), so the round trip is exact
        let t: Vec<f64> = (0..5).map(|k| 0.01 * f64::from(k)).collect();
        let (w, f) = ([0.3, -0.2, 1.5], [0.4, 0.1, 9.7]);
        let pose = SensorPose::new(
            *crate::so3::exp(&Vector3::new(0.2, -0.4, 1.0)).matrix(),
            Vector3::new(0.3, -0.1, 0.2),
        )?;
        let (mut gyro, mut accel) = (vec![w; t.len()], vec![f; t.len()]);
        to_sensor(&pose, &vec![[0.0; 3]; t.len()], &mut gyro, &mut accel)?;
        let samples = Samples::new(&t, &gyro, &accel)?;
        let (mut gb, mut ab) = (vec![[0.0; 3]; t.len()], vec![[0.0; 3]; t.len()]);
        to_body(&samples, &Bias::default(), &pose, &mut gb, &mut ab)?;
        for k in 0..t.len() {
            assert!((Vector3::from(gb[k]) - Vector3::from(w)).amax() < 1e-15);
            assert!((Vector3::from(ab[k]) - Vector3::from(f)).amax() < 1e-14);
        }
        Ok(())
    }

    #[test]
    fn centripetal_sensitivity_is_the_derivative_of_the_centripetal_term() {
        let (w, arm) = (Vector3::new(0.7, -1.3, 2.1), Vector3::new(0.3, -0.1, 0.2));
        let c = |w: &Vector3<f64>| w.cross(&w.cross(&arm));
        let d = centripetal_sensitivity(&w, &arm);
        for j in 0..3 {
            let e = Vector3::ith(j, 1e-6);
            let numeric = (c(&(w + e)) - c(&(w - e))) / 2e-6;
            assert!((d.column(j) - numeric).amax() < 1e-9);
        }
    }

    #[test]
    fn a_reflection_and_an_arm_beyond_the_earth_are_refused() {
        assert!(SensorPose::new(Matrix3::identity(), Vector3::new(0.0, 2e7, 0.0)).is_err());
        let flip = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        assert!(SensorPose::new(flip, Vector3::zeros()).is_err());
    }
}
