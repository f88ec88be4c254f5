//! Trajectories in closed form: position, velocity, acceleration, attitude and body rate are all
//! analytic functions of time, so ideal IMU measurements are exact (no finite differences).
//!
//! | motion | position | attitude `R_wb` |
//! |---|---|---|
//! | `Static` | `p₀` | `R₀` |
//! | `ConstantTwist` | `p₀ + R₀ J_l(ωt) v_b t` | `R₀ Exp(ω t)` (screw: body rate ω, body velocity v_b) |
//! | `Helix` | centre + `r (cos Ωt, sin Ωt, 0)` + `(0, 0, c t)` (circle: c = 0) | yaw `Ωt + π/2 sign Ω` (facing along the horizontal velocity) |
//! | `FigureEight` | centre + `(A sin Ωt, B sin 2Ωt, C sin 2Ωt)` | yaw = heading `atan2(ẏ, ẋ)`, roll `φ₀ sin 2Ωt`, pitch `θ₀ sin Ωt` |
//! | `VioEllipse` | centre + `(a cos Kt, b sin Kt, c sin(K₁ K t))` | yaw `Kt`, pitch `θ₀ sin t`, roll `φ₀ cos t` |
//!
//! `VioEllipse` is the trajectory of the VIO teaching simulator (He Yijia's `vio_data_simulation`:
//! a = 15, b = 20, c = 1, K = π/10, K₁ = 10, θ₀ = 0.2, φ₀ = 0.1, centre (5, 5, 5)). Euler angles are
//! intrinsic ZYX (`R = Rz(ψ) Ry(θ) Rx(φ)`, docs/conventions.md); the body rate is `E⁻¹(χ) χ̇`.

use std::array::from_fn;

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::{euler, lie::sincos, so3};

/// The kinematic state at one instant, world frame unless stated.
#[derive(Debug, Clone, PartialEq)]
pub struct Kinematics {
    /// Position \[m\].
    pub position: Vector3<f64>,
    /// Velocity [m/s].
    pub velocity: Vector3<f64>,
    /// Acceleration [m/s²].
    pub acceleration: Vector3<f64>,
    /// `R_wb`.
    pub rotation: Rotation3<f64>,
    /// Angular velocity in the body frame [rad/s].
    pub body_rate: Vector3<f64>,
}

impl Kinematics {
    /// Ideal accelerometer reading: specific force `Rᵀ (a − g)` in the body frame [m/s²].
    pub fn specific_force(&self, gravity: &Vector3<f64>) -> Vector3<f64> {
        self.rotation.matrix().transpose() * (self.acceleration - gravity)
    }
}

/// A trajectory with closed-form derivatives (module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// At rest.
    Static {
        /// `p₀` \[m\].
        position: Vector3<f64>,
        /// `R₀`.
        rotation: Rotation3<f64>,
    },
    /// Constant body rate and body-frame velocity (a screw motion).
    ConstantTwist {
        /// `p₀` \[m\].
        position: Vector3<f64>,
        /// `R₀`.
        rotation: Rotation3<f64>,
        /// `v_b` [m/s], body frame.
        body_velocity: Vector3<f64>,
        /// `ω` [rad/s], body frame.
        body_rate: Vector3<f64>,
    },
    /// Horizontal circle of radius `radius` at `angular_rate` Ω, climbing at `climb_rate`.
    Helix {
        /// Centre of the circle at t = 0 \[m\].
        center: Vector3<f64>,
        /// `r` \[m\].
        radius: f64,
        /// Ω [rad/s], positive counter-clockwise seen from above.
        angular_rate: f64,
        /// `c` [m/s].
        climb_rate: f64,
    },
    /// Gerono-style figure eight with banking and pitching.
    FigureEight {
        /// Centre \[m\].
        center: Vector3<f64>,
        /// `(A, B, C)` \[m\].
        amplitude: Vector3<f64>,
        /// Ω [rad/s]: one eight every 2π/Ω seconds.
        angular_rate: f64,
        /// Roll amplitude φ₀ \[rad\].
        roll: f64,
        /// Pitch amplitude θ₀ \[rad\].
        pitch: f64,
    },
    /// The VIO teaching ellipse (module docs).
    VioEllipse {
        /// Centre \[m\].
        center: Vector3<f64>,
        /// `(a, b, c)` \[m\].
        amplitude: Vector3<f64>,
        /// K [rad/s].
        angular_rate: f64,
        /// K₁: height oscillations per revolution.
        height_frequency: f64,
        /// Roll amplitude φ₀ \[rad\].
        roll: f64,
        /// Pitch amplitude θ₀ \[rad\].
        pitch: f64,
    },
}

/// The kinds of [`Motion`], by the names the bindings use (`imukit.sim`'s classes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionKind {
    /// [`Motion::Static`]
    Static,
    /// [`Motion::ConstantTwist`]
    ConstantTwist,
    /// [`Motion::Helix`]
    Helix,
    /// [`Motion::FigureEight`]
    FigureEight,
    /// [`Motion::VioEllipse`]
    VioEllipse,
}

crate::named_enum!(
    MotionKind,
    "trajectory",
    [
        Static => "static",
        ConstantTwist => "constant_twist",
        Helix => "helix",
        FigureEight => "figure_eight",
        VioEllipse => "vio_ellipse",
    ]
);

/// Stamps evaluated together by [`Motion::at_lanes`]: the sines and cosines of their angles are
/// taken four at a time ([`sincos::sin_cos_x4`]).
pub const LANES: usize = 4;

impl Motion {
    /// The kinematic state at time `t` \[s\] (one lane of [`Motion::at_lanes`], so equal bit for
    /// bit to what [`super::evaluate`] writes for `t`).
    pub fn at(&self, t: f64) -> Kinematics {
        let [first, ..] = self.at_lanes([t; LANES]);
        first
    }

    /// The kinematic states at four times \[s\], each lane as [`Motion::at`] of its time.
    pub fn at_lanes(&self, t: [f64; LANES]) -> [Kinematics; LANES] {
        match self {
            Motion::Static { position, rotation } => from_fn(|_| Kinematics {
                position: *position,
                velocity: Vector3::zeros(),
                acceleration: Vector3::zeros(),
                rotation: *rotation,
                body_rate: Vector3::zeros(),
            }),
            Motion::ConstantTwist {
                position,
                rotation,
                body_velocity,
                body_rate,
            } => t.map(|t| {
                let phi = body_rate * t;
                let r = rotation * so3::exp(&phi);
                Kinematics {
                    position: position + rotation * (so3::left_jacobian(&phi) * body_velocity) * t,
                    velocity: r * body_velocity,
                    acceleration: r * body_rate.cross(body_velocity),
                    rotation: r,
                    body_rate: *body_rate,
                }
            }),
            Motion::Helix {
                center,
                radius,
                angular_rate: w,
                climb_rate,
            } => {
                let (s, c) = sincos::sin_cos_x4(t.map(|t| w * t));
                // Yaw Ωt ± π/2: its sine ±cos Ωt and cosine ∓sin Ωt, with the sign of Ω.
                let sign = w.signum();
                from_fn(|k| {
                    let (s, c) = (s[k], c[k]);
                    let (sy, cy) = (sign * c, -sign * s);
                    Kinematics {
                        position: center + Vector3::new(radius * c, radius * s, climb_rate * t[k]),
                        velocity: Vector3::new(-radius * w * s, radius * w * c, *climb_rate),
                        acceleration: Vector3::new(-radius * w * w * c, -radius * w * w * s, 0.0),
                        rotation: Rotation3::from_matrix_unchecked(Matrix3::new(
                            cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0,
                        )),
                        body_rate: Vector3::new(0.0, 0.0, *w),
                    }
                })
            }
            Motion::FigureEight {
                center,
                amplitude: amp,
                angular_rate: w,
                roll,
                pitch,
            } => {
                let (s1, c1) = sincos::sin_cos_x4(t.map(|t| w * t));
                let s2 = from_fn(|k| 2.0 * s1[k] * c1[k]);
                let pitch_sc = sincos::sin_cos_x4(s1.map(|s| pitch * s));
                let roll_sc = sincos::sin_cos_x4(s2.map(|s| roll * s));
                from_fn(|k| {
                    let (s1, c1, s2) = (s1[k], c1[k], s2[k]);
                    let c2 = c1 * c1 - s1 * s1;
                    let (w2, w4) = (w * w, 4.0 * w * w);
                    let velocity = Vector3::new(amp.x * w * c1, 2.0 * amp.y * w * c2, 2.0 * amp.z * w * c2);
                    let acceleration = Vector3::new(-amp.x * w2 * s1, -amp.y * w4 * s2, -amp.z * w4 * s2);
                    // Heading of the horizontal velocity, whose direction gives its sine and
                    // cosine; it never vanishes (ẋ = 0 needs cos Ωt = 0, where ẏ = −2BΩ).
                    let (vx, vy, ax, ay) = (velocity.x, velocity.y, acceleration.x, acceleration.y);
                    let speed2 = vx * vx + vy * vy;
                    let speed = speed2.sqrt();
                    let chi_dot = Vector3::new((vx * ay - vy * ax) / speed2, pitch * w * c1, 2.0 * roll * w * c2);
                    let sines = euler::EulerSines {
                        yaw: (vy / speed, vx / speed),
                        pitch: (pitch_sc.0[k], pitch_sc.1[k]),
                        roll: (roll_sc.0[k], roll_sc.1[k]),
                    };
                    Kinematics {
                        position: center + Vector3::new(amp.x * s1, amp.y * s2, amp.z * s2),
                        velocity,
                        acceleration,
                        rotation: sines.rotation(),
                        body_rate: sines.body_rate(&chi_dot),
                    }
                })
            }
            Motion::VioEllipse {
                center,
                amplitude: amp,
                angular_rate: k,
                height_frequency: k1,
                roll,
                pitch,
            } => {
                let kz = k1 * k;
                let (s, c) = sincos::sin_cos_x4(t.map(|t| k * t));
                let (sz, cz) = sincos::sin_cos_x4(t.map(|t| kz * t));
                let (st, ct) = sincos::sin_cos_x4(t);
                let pitch_sc = sincos::sin_cos_x4(st.map(|s| pitch * s));
                let roll_sc = sincos::sin_cos_x4(ct.map(|c| roll * c));
                from_fn(|i| {
                    let (s, c, sz, cz) = (s[i], c[i], sz[i], cz[i]);
                    // Euler angles χ = (Kt, θ₀ sin t, φ₀ cos t).
                    let chi_dot = Vector3::new(*k, pitch * ct[i], -roll * st[i]);
                    let sines = euler::EulerSines {
                        yaw: (s, c),
                        pitch: (pitch_sc.0[i], pitch_sc.1[i]),
                        roll: (roll_sc.0[i], roll_sc.1[i]),
                    };
                    Kinematics {
                        position: center + Vector3::new(amp.x * c, amp.y * s, amp.z * sz),
                        velocity: Vector3::new(-amp.x * k * s, amp.y * k * c, amp.z * kz * cz),
                        acceleration: Vector3::new(-amp.x * k * k * c, -amp.y * k * k * s, -amp.z * kz * kz * sz),
                        rotation: sines.rotation(),
                        body_rate: sines.body_rate(&chi_dot),
                    }
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::names::Named;
    use crate::Error;

    #[test]
    fn every_kind_parses_from_its_name_and_nothing_else_does() {
        for &kind in MotionKind::ALL {
            assert_eq!(kind.name().parse::<MotionKind>().ok(), Some(kind));
        }
        assert!(matches!(
            "circle".parse::<MotionKind>(),
            Err(Error::Parameter { name: "trajectory", .. })
        ));
    }

    #[test]
    fn each_lane_is_the_motion_at_its_own_time() {
        let motion = Motion::FigureEight {
            center: Vector3::new(1.0, 2.0, 3.0),
            amplitude: Vector3::new(4.0, 3.0, 0.5),
            angular_rate: 0.7,
            roll: 0.3,
            pitch: 0.2,
        };
        let t = [0.25, 13.0, 1e4, 7.5];
        let lanes = motion.at_lanes(t);
        for (k, &tk) in t.iter().enumerate() {
            assert_eq!(lanes[k], motion.at(tk));
            assert_eq!(lanes[k], motion.at_lanes([tk, 0.0, -3.0, 1e9])[0]);
        }
    }
}
