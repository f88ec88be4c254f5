//! The error model of navigation over the ellipsoid in the local-level frame that follows the
//! vehicle ([`crate::ellipsoid`]): the continuous-time rates `δẋ = F δx` of the 15 error states
//! that [`crate::propagate`] carries, with the position-error coupling through the curvature
//! (Groves 2013, §14.2.4, the curvilinear-position form; Titterton & Weston 2004, §12.3: the
//! Schuler loop).
//!
//! | item | convention |
//! |---|---|
//! | error state | `[δpos, δv, δθ, δb_a, δb_g]`: `pos = (φ, λ, h)` additive (rad, rad, m), `v` additive (local-level axes at the vehicle), `R = R̂ Exp(δθ)` (right, body), biases additive |
//! | model | `ṗos = P(pos, v)`, `v̇ = R â + g(φ, h) − (2 ω_ie(φ) + ω_en(pos, v)) × v`, `Ṙ = R [ω̂]× − [ω_in]× R`, `ω_in = ω_ie + ω_en` (module docs of [`crate::ellipsoid`]) |
//!
//! Linearised about the estimate (`ω_in`'s own value drops out of `δθ̇` with the right
//! perturbation: `[δθ̇]× = −[ω̂ × δθ]× − [δb_g]× − [R̂ᵀ δω_in]×`):
//!
//! ```text
//! δṗos = ∂P/∂pos δpos + ∂P/∂v δv
//! δv̇   = (∂g/∂pos + [v]× ∂c/∂pos) δpos + ([v]× ∂ω_en/∂v − [c]×) δv − R[â]× δθ − R δb_a + R D δb_g
//! δθ̇   = −R̂ᵀ ∂ω_in/∂pos δpos − R̂ᵀ ∂ω_en/∂v δv − [ω̂]× δθ − δb_g
//! ```
//!
//! with `c = 2 ω_ie + ω_en`, `D` the lever arm's centripetal sensitivity (zero without one;
//! [`crate::propagate`]). The partial derivatives keep the change of the radii of curvature with
//! latitude (`dR_N/dφ`, `dR_E/dφ`) and of normal gravity with latitude and height
//! ([`LocalLevel::gravity_derivatives`]); Groves drops the former, they cost nothing here. The
//! `∂c/∂pos`, `∂ω_in/∂pos` terms carry the Earth rate's turn with latitude; `∂g/∂h = −2g/R`
//! (about) is the vertical channel's instability, `∂ω_en/∂v` with `R[â]×` the Schuler loop
//! (`ω_s = √(g/R)`, 84.4 min).

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::earth::{Axes, LocalLevel, EARTH_RATE, SEMI_MAJOR_AXIS};
use crate::ellipsoid::{radii, transport_rate, E2};
use crate::imu::NavState;
use crate::so3;

/// Continuous-time error rates `F`, 15×15, order `[δpos, δv, δθ, δb_a, δb_g]`.
pub type ErrorRates = SMatrix<f64, 15, 15>;

/// The matrix taking `(north, east, up)` components to `axes` (its own inverse).
fn from_neu(axes: Axes) -> Matrix3<f64> {
    match axes {
        Axes::Enu => Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        Axes::Ned => Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)),
    }
}

/// `(dR_N/dφ, dR_E/dφ)` of [`radii`].
fn radii_derivatives(latitude: f64) -> (f64, f64) {
    let (s, c) = latitude.sin_cos();
    let d = 1.0 - E2 * s * s;
    (
        3.0 * SEMI_MAJOR_AXIS * (1.0 - E2) * E2 * s * c / d.powf(2.5),
        SEMI_MAJOR_AXIS * E2 * s * c / d.powf(1.5),
    )
}

/// The columns `(∂/∂φ, ∂/∂λ = 0, ∂/∂h)` as a 3×3 block.
fn by_position(d_lat: Vector3<f64>, d_height: Vector3<f64>) -> Matrix3<f64> {
    Matrix3::from_columns(&[d_lat, Vector3::zeros(), d_height])
}

/// `F` at the estimate `x` (position `(φ, λ, h)`) with bias-corrected readings `ω̂`, `â` and the
/// lever arm's `D` (zero without one); module docs.
pub fn error_rates(
    axes: Axes,
    x: &NavState,
    w_hat: &Vector3<f64>,
    a_hat: &Vector3<f64>,
    centripetal: &Matrix3<f64>,
) -> ErrorRates {
    let (lat, height) = (x.position.x, x.position.z);
    let t = from_neu(axes);
    let ((rn, re), (drn, dre)) = (radii(lat), radii_derivatives(lat));
    let (rnh, reh) = (rn + height, re + height);
    let v_neu = t * x.velocity;
    let (vn, ve) = (v_neu.x, v_neu.y);
    let (s, c) = lat.sin_cos();
    let tan = s / c;
    let frame = LocalLevel {
        latitude: lat,
        height,
        axes,
    };
    let (w_ie, w_en) = (frame.earth_rate(), transport_rate(axes, lat, height, &x.velocity));
    // Partial derivatives in (north, east, up), then turned into the frame's axes by `t`.
    let d_ie_lat = t * Vector3::new(-EARTH_RATE * s, 0.0, EARTH_RATE * c);
    let d_en_lat = t * Vector3::new(
        -ve * dre / (reh * reh),
        vn * drn / (rnh * rnh),
        ve * (1.0 / (c * c * reh) - tan * dre / (reh * reh)),
    );
    let d_en_h = t * Vector3::new(-ve / (reh * reh), vn / (rnh * rnh), -ve * tan / (reh * reh));
    let d_en_v = t * Matrix3::new(0.0, 1.0 / reh, 0.0, -1.0 / rnh, 0.0, 0.0, 0.0, tan / reh, 0.0) * t;
    let (dg_lat, dg_h) = frame.gravity_derivatives();
    let d_g = by_position(t * Vector3::new(0.0, 0.0, -dg_lat), t * Vector3::new(0.0, 0.0, -dg_h));
    let d_rates_pos = Matrix3::from_columns(&[
        Vector3::new(
            -vn * drn / (rnh * rnh),
            ve * (s / (reh * c * c) - dre / (reh * reh * c)),
            0.0,
        ),
        Vector3::zeros(),
        Vector3::new(-vn / (rnh * rnh), -ve / (reh * reh * c), 0.0),
    ]);
    let d_rates_v = Matrix3::from_diagonal(&Vector3::new(1.0 / rnh, 1.0 / (reh * c), 1.0)) * t;
    let r = *x.rotation.to_rotation_matrix().matrix();
    let v_cross = so3::hat(&x.velocity);
    let blocks = [
        (0, 0, d_rates_pos),
        (0, 1, d_rates_v),
        (1, 0, d_g + v_cross * by_position(d_ie_lat * 2.0 + d_en_lat, d_en_h)),
        (1, 1, v_cross * d_en_v - so3::hat(&(w_ie * 2.0 + w_en))),
        (1, 2, -r * so3::hat(a_hat)),
        (1, 3, -r),
        (1, 4, r * centripetal),
        (2, 0, -r.transpose() * by_position(d_ie_lat + d_en_lat, d_en_h)),
        (2, 1, -r.transpose() * d_en_v),
        (2, 2, -so3::hat(w_hat)),
        (2, 4, -Matrix3::identity()),
    ];
    let mut f = ErrorRates::zeros();
    for (i, j, block) in blocks {
        f.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&block);
    }
    f
}

#[cfg(test)]
mod tests {
    use nalgebra::{SVector, UnitQuaternion};

    use super::*;
    use crate::ellipsoid::derivative;

    /// The error's rate of change when the truth is the estimate `x` perturbed by `d`, from the
    /// model's own derivative: `δṗos`, `δv̇` directly, `δθ̇ = J_r⁻¹(δθ) (Ω_t − Mᵀ Ω_e)` with
    /// `M = R̂ᵀR = Exp(δθ)` and `Ω = 2 q* q̇` each attitude's rate in its body axes.
    fn error_rate(
        axes: Axes,
        x: &NavState,
        w: &Vector3<f64>,
        a: &Vector3<f64>,
        d: &SVector<f64, 15>,
    ) -> SVector<f64, 15> {
        let part = |i: usize| d.fixed_rows::<3>(3 * i).into_owned();
        let truth = NavState {
            position: x.position + part(0),
            velocity: x.velocity + part(1),
            rotation: x.rotation * UnitQuaternion::from_scaled_axis(part(2)),
        };
        let (wt, at) = (w - part(4), a - part(3));
        let rate = |s: &NavState, w: &Vector3<f64>, a: &Vector3<f64>| {
            derivative(axes, (&s.position, &s.velocity, s.rotation.quaternion()), w, a)
        };
        let (et, ee) = (rate(&truth, &wt, &at), rate(x, w, a));
        let body_rate =
            |s: &NavState, dq: &nalgebra::Quaternion<f64>| (s.rotation.quaternion().conjugate() * dq * 2.0).imag();
        let m = (x.rotation.inverse() * truth.rotation).to_rotation_matrix();
        let theta =
            so3::right_jacobian_inv(&part(2)) * (body_rate(&truth, &et.2) - m.transpose() * body_rate(x, &ee.2));
        let mut out = SVector::<f64, 15>::zeros();
        out.fixed_rows_mut::<3>(0).copy_from(&(et.0 - ee.0));
        out.fixed_rows_mut::<3>(3).copy_from(&(et.1 - ee.1));
        out.fixed_rows_mut::<3>(6).copy_from(&theta);
        out
    }

    #[test]
    fn error_rates_are_the_central_differences_of_the_model() {
        // 250 m/s at 52° N, climbing, with a turned body: every block is non-zero.
        for axes in [Axes::Enu, Axes::Ned] {
            let x = NavState {
                position: Vector3::new(0.9, 0.2, 3000.0),
                velocity: Vector3::new(180.0, -170.0, 12.0),
                rotation: UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.2, 1.1)),
            };
            let (w, a) = (Vector3::new(0.02, -0.01, 0.05), Vector3::new(0.5, -0.3, 9.7));
            let f = error_rates(axes, &x, &w, &a, &Matrix3::zeros());
            // Steps per component: 1e-5 rad (64 m) in latitude, 1 m in height, 1e-3 m/s, 1e-6 rad.
            let steps = [
                1e-5, 1e-5, 1.0, 1e-3, 1e-3, 1e-3, 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4, 1e-6, 1e-6, 1e-6,
            ];
            for (j, step) in steps.iter().enumerate() {
                let mut d = SVector::<f64, 15>::zeros();
                d[j] = *step;
                let column = (error_rate(axes, &x, &w, &a, &d) - error_rate(axes, &x, &w, &a, &(-d))) / (2.0 * step);
                for i in 0..9 {
                    // Relative per entry (they span 1e-13 to 1e1), and 1e-10 of the row's largest.
                    let row = f.row(i).amax();
                    assert!(
                        (f[(i, j)] - column[i]).abs() <= 1e-6 * column[i].abs() + 1e-10 * row,
                        "{axes:?} ({i}, {j}): {} vs {}",
                        f[(i, j)],
                        column[i]
                    );
                }
            }
        }
    }
}
