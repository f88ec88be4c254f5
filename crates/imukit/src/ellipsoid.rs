//! Navigation over the WGS-84 ellipsoid in a local-level frame that follows the vehicle (the
//! "transport" frame of Groves 2013, §5.4; Titterton & Weston 2004, §3.5).
//!
//! | item | convention |
//! |---|---|
//! | state | position `(φ, λ, h)`: geodetic latitude \[rad\], longitude \[rad\], height \[m\] (the [`NavState`]'s `position` holds them); `v` the velocity relative to the Earth in the local-level axes at the vehicle; `q = q_nb` |
//! | axes | ENU or NED ([`Axes`]), the frame at the vehicle's own position |
//! | radii | meridian `R_N = a(1 − e²)/(1 − e² sin²φ)^{3/2}`, transverse `R_E = a/√(1 − e² sin²φ)` (Groves eqs. 2.105, 2.106) |
//! | position rates | `φ̇ = v_N/(R_N + h)`, `λ̇ = v_E/((R_E + h) cos φ)`, `ḣ = v_U` (Groves eq. 5.56) |
//! | transport rate | `ω_en` = north `v_E/(R_E + h)`, east `−v_N/(R_N + h)`, up `v_E tan φ/(R_E + h)` (Groves eq. 5.44) |
//! | model | `Ṙ = R [ω̂]× − [ω_ie + ω_en]× R`, `v̇ = R â + g(φ, h) − (2 ω_ie + ω_en) × v` with `ω_ie(φ)` and the normal gravity `g(φ, h)` of [`LocalLevel`] at the vehicle (Groves eqs. 5.46, 5.54) |
//!
//! [`integrate`] solves the model with RK4 (mid-step readings from the local cubic, as
//! [`Scheme::Rk4`] in strapdown) or the explicit midpoint rule (mid-step readings the mean of the
//! two samples, as [`Scheme::Midpoint`]); the other schemes are strapdown's closed forms for a fixed
//! frame and are refused here. [`sensor_readings`] is the simulator's inverse: the readings of a
//! trajectory whose velocity, acceleration and attitude are given in the moving frame. The axes are
//! undefined at the poles (`tan φ`, `1/cos φ`): a state that reaches them is refused.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::earth::{Axes, LocalLevel, FLATTENING, SEMI_MAJOR_AXIS};
use crate::imu::{Bias, NavState, Samples};
use crate::interp::{Cubic, StepInterpolator};
use crate::strapdown::{Scheme, StatesOut};
use crate::{quat, Cancel, Error, Result};

/// First eccentricity squared `e² = f (2 − f)`.
pub(crate) const E2: f64 = FLATTENING * (2.0 - FLATTENING);

/// Checks that a frame at `latitude` \[rad\] can follow the vehicle: strictly inside ±π/2, as
/// north and east (and `tan φ`, `1/cos φ` in the rates) are undefined at the poles.
pub fn check_origin(latitude: f64) -> Result<()> {
    if latitude.abs() < std::f64::consts::FRAC_PI_2 {
        Ok(())
    } else {
        Err(Error::Parameter {
            name: "latitude",
            expected:
                "inside ±π/2 for a frame that follows the vehicle (the local-level axes are undefined at the poles)",
            got: format!("{latitude}"),
        })
    }
}

/// Meridian and transverse radii of curvature `(R_N, R_E)` at latitude φ \[m\] (module docs).
pub fn radii(latitude: f64) -> (f64, f64) {
    let d = 1.0 - E2 * latitude.sin().powi(2);
    (
        SEMI_MAJOR_AXIS * (1.0 - E2) / (d * d.sqrt()),
        SEMI_MAJOR_AXIS / d.sqrt(),
    )
}

/// `(north, east, up)` components of a vector in `axes`.
pub(crate) fn north_east_up(axes: Axes, v: &Vector3<f64>) -> (f64, f64, f64) {
    match axes {
        Axes::Enu => (v.y, v.x, v.z),
        Axes::Ned => (v.x, v.y, -v.z),
    }
}

/// The vector in `axes` with these north, east and up components.
pub(crate) fn from_north_east_up(axes: Axes, north: f64, east: f64, up: f64) -> Vector3<f64> {
    match axes {
        Axes::Enu => Vector3::new(east, north, up),
        Axes::Ned => Vector3::new(north, east, -up),
    }
}

/// The frame's rates at a point: `ω_ie`, `ω_en`, gravity, and `(φ̇, λ̇, ḣ)` for velocity `v`.
struct Rates {
    earth: Vector3<f64>,
    transport: Vector3<f64>,
    gravity: Vector3<f64>,
    position: Vector3<f64>,
}

impl Rates {
    fn at(axes: Axes, position: &Vector3<f64>, v: &Vector3<f64>) -> Self {
        let (lat, h) = (position.x, position.z);
        let frame = LocalLevel {
            latitude: lat,
            height: h,
            axes,
        };
        let (rn, re) = radii(lat);
        let (vn, ve, vu) = north_east_up(axes, v);
        let (east_arc, north_arc) = (ve / (re + h), vn / (rn + h));
        Self {
            earth: frame.earth_rate(),
            transport: from_north_east_up(axes, east_arc, -north_arc, east_arc * lat.tan()),
            gravity: frame.gravity(),
            position: Vector3::new(north_arc, east_arc / lat.cos(), vu),
        }
    }
}

/// `ω_en` in `axes` at latitude φ, height h, for velocity `v` (module docs).
pub fn transport_rate(axes: Axes, latitude: f64, height: f64, v: &Vector3<f64>) -> Vector3<f64> {
    Rates::at(axes, &Vector3::new(latitude, 0.0, height), v).transport
}

/// Time derivative `(ṗ, v̇, q̇)` of the state with body rate `w` and specific force `f` (module docs;
/// `q` unnormalised inside a step, `R(q/|q|)`).
pub(crate) fn derivative(
    axes: Axes,
    (pos, v, q): (&Vector3<f64>, &Vector3<f64>, &Quaternion<f64>),
    w: &Vector3<f64>,
    f: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>, Quaternion<f64>) {
    let r = Rates::at(axes, pos, v);
    let turn = Quaternion::from_imag(r.earth + r.transport);
    let dq = (quat::multiply(q, &Quaternion::from_imag(*w)) - quat::multiply(&turn, q)) * 0.5;
    let rot = UnitQuaternion::new_normalize(*q);
    let dv = quat::rotate_unit(&rot, f) + r.gravity - (r.earth * 2.0 + r.transport).cross(v);
    (r.position, dv, dq)
}

/// Integrates the samples over the ellipsoid from `initial` (position `(φ, λ, h)`, its latitude and
/// height those of `start`, whose axes it takes) with `scheme` (rk4 or midpoint), writing every
/// state to `out` when given; returns the final state.
pub fn integrate(
    samples: &Samples<'_>,
    initial: &NavState,
    bias: &Bias,
    start: &LocalLevel,
    scheme: Scheme,
    mut out: Option<StatesOut<'_>>,
    cancel: &Cancel,
) -> Result<NavState> {
    if let Some(out) = out.as_mut() {
        out.check(samples.t.len())?;
        out.store(0, initial);
    }
    run(samples, initial, bias, start, scheme, |k, _, next| {
        if let Some(out) = out.as_mut() {
            out.store(k + 1, next);
        }
        cancel.check(k)
    })
}

/// [`integrate`]'s loop: calls `visit(k, state_k, state_k+1)` after each step (the covariance
/// propagation of [`crate::propagate`] rides on it, so its mean is this one).
pub(crate) fn run(
    samples: &Samples<'_>,
    initial: &NavState,
    bias: &Bias,
    start: &LocalLevel,
    scheme: Scheme,
    mut visit: impl FnMut(usize, &NavState, &NavState) -> Result<()>,
) -> Result<NavState> {
    let n = samples.t.len();
    crate::strapdown::check_parameters(initial, bias, &crate::strapdown::Options::default())?;
    if !matches!(scheme, Scheme::Rk4 | Scheme::Midpoint) {
        return Err(Error::Parameter {
            name: "scheme",
            expected: "rk4 or midpoint with a frame that follows the vehicle",
            got: scheme.name().into(),
        });
    }
    let axes = start.axes;
    let (lat, h) = (initial.position.x, initial.position.z);
    // One starting point: the frame's, which the state repeats (1e-12 rad is 6 µm, 1e-6 m the
    // height a float carries at 1000 km).
    if (lat - start.latitude).abs() > 1e-12 || (h - start.height).abs() > 1e-6 {
        return Err(Error::Parameter {
            name: "initial.position",
            expected: "(latitude, longitude, height) starting at the frame's latitude and height",
            got: format!(
                "latitude {lat}, height {h} for a frame at {}, {}",
                start.latitude, start.height
            ),
        });
    }
    check_origin(lat).map_err(|e| e.in_argument("frame"))?;
    if !samples.first_ok() {
        return Err(samples.value_error());
    }
    let mid_gyro = StepInterpolator::new(Cubic::new(samples.t, samples.gyro.as_flattened()), [0.5]);
    let mid_accel = StepInterpolator::new(Cubic::new(samples.t, samples.accel.as_flattened()), [0.5]);
    let mut x = *initial;
    for k in 0..n - 1 {
        if !samples.step_ok(k) {
            return Err(samples.value_error());
        }
        let h = samples.t[k + 1] - samples.t[k];
        let reading = |w: Vector3<f64>, a: Vector3<f64>| (w - bias.gyro, a - bias.accel);
        let (w0, a0) = reading(samples.gyro_at(k), samples.accel_at(k));
        let (w1, a1) = reading(samples.gyro_at(k + 1), samples.accel_at(k + 1));
        let (wm, am) = if scheme == Scheme::Rk4 {
            let ([wm], [am]) = (mid_gyro.at(k), mid_accel.at(k));
            reading(wm, am)
        } else {
            ((w0 + w1) * 0.5, (a0 + a1) * 0.5)
        };
        let (p, v, q) = (x.position, x.velocity, x.rotation.into_inner());
        let f = |s: f64, d: &(Vector3<f64>, Vector3<f64>, Quaternion<f64>), w: &Vector3<f64>, a: &Vector3<f64>| {
            derivative(axes, (&(p + d.0 * s), &(v + d.1 * s), &(q + d.2 * s)), w, a)
        };
        let zero = (Vector3::zeros(), Vector3::zeros(), Quaternion::new(0.0, 0.0, 0.0, 0.0));
        let k1 = f(0.0, &zero, &w0, &a0);
        let k2 = f(0.5 * h, &k1, &wm, &am);
        let (dp, dv, dq) = if scheme == Scheme::Rk4 {
            let k3 = f(0.5 * h, &k2, &wm, &am);
            let k4 = f(h, &k3, &w1, &a1);
            let c = 1.0 / 6.0;
            (
                (k1.0 + k2.0 * 2.0 + k3.0 * 2.0 + k4.0) * c,
                (k1.1 + k2.1 * 2.0 + k3.1 * 2.0 + k4.1) * c,
                (k1.2 + k2.2 * 2.0 + k3.2 * 2.0 + k4.2) * c,
            )
        } else {
            k2
        };
        let next = NavState {
            position: p + dp * h,
            velocity: v + dv * h,
            rotation: UnitQuaternion::new_normalize(q + dq * h),
        };
        let finite = next.position.iter().chain(next.velocity.iter()).all(|c| c.is_finite());
        if !(finite && next.position.x.abs() < std::f64::consts::FRAC_PI_2) {
            let name = culprit(samples, initial, bias);
            return Err(Error::Overflow { index: k + 1 }.in_argument(name));
        }
        visit(k, &x, &next)?;
        x = next;
    }
    Ok(x)
}

/// The input to blame when the track overflows or reaches a pole: `t` for a span beyond 1e6 s (11
/// days: the arc covered, not an input, is then what is too large); else the largest of the angles
/// each input turns the state through over the span T: `|ω| T`, `|b_g| T` (attitude), `|v₀| T / a`
/// and `|a_m| T² / a`, `|b_a| T² / a` (arcs over the Earth, `a` its radius).
fn culprit(samples: &Samples<'_>, initial: &NavState, bias: &Bias) -> &'static str {
    use crate::strapdown::largest;
    let span = samples.t[samples.t.len() - 1] - samples.t[0];
    if span > 1e6 {
        return "t";
    }
    let arc = span * span / SEMI_MAJOR_AXIS;
    let terms = [
        ("imu", largest(samples.gyro) * span),
        ("bias", bias.gyro.amax() * span),
        ("velocity", initial.velocity.amax() * span / SEMI_MAJOR_AXIS),
        ("imu", largest(samples.accel) * arc),
        ("bias", bias.accel.amax() * arc),
    ];
    terms.iter().fold(terms[0], |m, t| if t.1 > m.1 { *t } else { m }).0
}

/// The trajectory's motion at the sample times, as the simulator evaluates it in the moving frame:
/// `position` (its up component gives the height), `velocity` `v`, `rotation` `R_nb` quaternions
/// `[x, y, z, w]`; `mid_position` / `mid_velocity` at the step mid-points (one row fewer).
#[derive(Debug, Clone, Copy)]
pub struct Track<'a> {
    /// Sample times \[s\].
    pub t: &'a [f64],
    /// Positions of the motion \[m\] (only the vertical part is used, as the height change).
    pub position: &'a [[f64; 3]],
    /// Velocities [m/s] in the moving frame.
    pub velocity: &'a [[f64; 3]],
    /// Positions at the step mid-points.
    pub mid_position: &'a [[f64; 3]],
    /// Velocities at the step mid-points.
    pub mid_velocity: &'a [[f64; 3]],
    /// `R_nb` quaternions `[x, y, z, w]`.
    pub rotation: &'a [[f64; 4]],
}

/// The readings and the geodetic track of a motion flown over the ellipsoid from `start`
/// `(φ, λ, h)` in `axes`. `gyro` enters as the body rate relative to the moving frame and leaves as
/// `ω_nb + Rᵀ (ω_ie + ω_en)`; `accel` enters as `Rᵀ v̇` (the motion's specific force without
/// gravity) and leaves as `Rᵀ (v̇ − g(φ, h) + (2 ω_ie + ω_en) × v)`. `(φ, λ)` follow the position rates
/// by RK4 on the exact velocities at the sample and mid-step times (`h` is exact); written to
/// `geodetic`.
pub fn sensor_readings(
    axes: Axes,
    start: &Vector3<f64>,
    track: &Track<'_>,
    gyro: &mut [[f64; 3]],
    accel: &mut [[f64; 3]],
    geodetic: &mut [[f64; 3]],
) -> Result<()> {
    let n = track.t.len();
    for (name, len) in [
        ("position", track.position.len()),
        ("velocity", track.velocity.len()),
        ("rotation", track.rotation.len()),
        ("gyro", gyro.len()),
        ("accel", accel.len()),
        ("geodetic", geodetic.len()),
        ("mid_position", track.mid_position.len() + 1),
        ("mid_velocity", track.mid_velocity.len() + 1),
    ] {
        if len != n {
            return Err(Error::RowCount { input: n, output: len }.in_argument(name));
        }
    }
    LocalLevel::new(start.x, start.z, axes)
        .and_then(|_| check_origin(start.x))
        .map_err(|e| e.in_argument("frame"))?;
    let up0 = north_east_up(axes, &Vector3::from(track.position[0])).2;
    let height = |p: &[f64; 3]| start.z + north_east_up(axes, &Vector3::from(*p)).2 - up0;
    let rates = |lat_lon: &Vector3<f64>, p: &[f64; 3], v: &[f64; 3]| {
        let pos = Vector3::new(lat_lon.x, lat_lon.y, height(p));
        (pos, Rates::at(axes, &pos, &Vector3::from(*v)))
    };
    let mut here = Vector3::new(start.x, start.y, 0.0);
    for k in 0..n {
        let (pos, r) = rates(&here, &track.position[k], &track.velocity[k]);
        let [qx, qy, qz, qw] = track.rotation[k];
        // Rᵀ: world (moving frame) to body.
        let rot = UnitQuaternion::new_normalize(Quaternion::new(qw, qx, qy, qz)).inverse();
        let v = Vector3::from(track.velocity[k]);
        let w = Vector3::from(gyro[k]) + rot * (r.earth + r.transport);
        let a = Vector3::from(accel[k]) + rot * ((r.earth * 2.0 + r.transport).cross(&v) - r.gravity);
        gyro[k] = w.into();
        accel[k] = a.into();
        geodetic[k] = pos.into();
        if !(pos.x.abs() < std::f64::consts::FRAC_PI_2 && w.iter().chain(a.iter()).all(|c| c.is_finite())) {
            return Err(Error::Overflow { index: k }.in_argument("trajectory"));
        }
        if k + 1 < n {
            // RK4 on (φ, λ) with the exact velocities at t_k, the mid-point and t_{k+1}.
            let h = track.t[k + 1] - track.t[k];
            let (pm, vm) = (&track.mid_position[k], &track.mid_velocity[k]);
            let d =
                |s: f64, from: &Vector3<f64>, p: &[f64; 3], v: &[f64; 3]| rates(&(here + from * s), p, v).1.position;
            let d1 = r.position;
            let d2 = d(0.5 * h, &d1, pm, vm);
            let d3 = d(0.5 * h, &d2, pm, vm);
            let d4 = d(h, &d3, &track.position[k + 1], &track.velocity[k + 1]);
            here += (d1 + d2 * 2.0 + d3 * 2.0 + d4) * (h / 6.0);
            here.z = 0.0;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radii_match_the_published_values_at_the_equator_and_the_pole() {
        // R_E(0) = a, R_N(0) = a(1 − e²) = b²/a; at the pole both are a²/b.
        let b = SEMI_MAJOR_AXIS * (1.0 - FLATTENING);
        let (rn, re) = radii(0.0);
        assert!((re - SEMI_MAJOR_AXIS).abs() < 1e-6 && (rn - b * b / SEMI_MAJOR_AXIS).abs() < 1e-6);
        let (rn, re) = radii(std::f64::consts::FRAC_PI_2);
        let polar = SEMI_MAJOR_AXIS * SEMI_MAJOR_AXIS / b;
        assert!((rn - polar).abs() < 1e-6 && (re - polar).abs() < 1e-6);
        // 6,335,439 m and 6,378,137 m at the equator, 6,399,594 m at the poles (Groves table 2.1)
        assert!((radii(0.0).0 - 6_335_439.327).abs() < 1e-2);
        assert!((polar - 6_399_593.626).abs() < 1e-2);
    }

    #[test]
    fn transport_rate_is_the_same_vector_in_enu_and_ned() {
        let lat = 0.7;
        let (ve, vn, vu) = (250.0, -30.0, 2.0);
        let enu = transport_rate(Axes::Enu, lat, 1000.0, &Vector3::new(ve, vn, vu));
        let ned = transport_rate(Axes::Ned, lat, 1000.0, &Vector3::new(vn, ve, -vu));
        assert_eq!((enu.x, enu.y, enu.z), (ned.y, ned.x, -ned.z));
        let (_, re) = radii(lat);
        assert!((enu.z - ve * lat.tan() / (re + 1000.0)).abs() < 1e-18);
    }
}
