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

use nalgebra::{Rotation3, Vector3};

use crate::{euler, so3};

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

/// Attitude and body rate from ZYX Euler angles `χ = [ψ, θ, φ]` and their rates.
fn from_euler(chi: Vector3<f64>, chi_dot: Vector3<f64>) -> (Rotation3<f64>, Vector3<f64>) {
    euler::to_rotation_with_body_rate(&chi, &chi_dot)
}

impl Motion {
    /// The kinematic state at time `t` \[s\].
    pub fn at(&self, t: f64) -> Kinematics {
        match self {
            Motion::Static { position, rotation } => Kinematics {
                position: *position,
                velocity: Vector3::zeros(),
                acceleration: Vector3::zeros(),
                rotation: *rotation,
                body_rate: Vector3::zeros(),
            },
            Motion::ConstantTwist {
                position,
                rotation,
                body_velocity,
                body_rate,
            } => {
                let phi = body_rate * t;
                let r = rotation * so3::exp(&phi);
                Kinematics {
                    position: position + rotation * (so3::left_jacobian(&phi) * body_velocity) * t,
                    velocity: r * body_velocity,
                    acceleration: r * body_rate.cross(body_velocity),
                    rotation: r,
                    body_rate: *body_rate,
                }
            }
            Motion::Helix {
                center,
                radius,
                angular_rate: w,
                climb_rate,
            } => {
                let (s, c) = (w * t).sin_cos();
                let yaw = w * t + std::f64::consts::FRAC_PI_2 * w.signum();
                Kinematics {
                    position: center + Vector3::new(radius * c, radius * s, climb_rate * t),
                    velocity: Vector3::new(-radius * w * s, radius * w * c, *climb_rate),
                    acceleration: Vector3::new(-radius * w * w * c, -radius * w * w * s, 0.0),
                    rotation: Rotation3::from_axis_angle(&Vector3::z_axis(), yaw),
                    body_rate: Vector3::new(0.0, 0.0, *w),
                }
            }
            Motion::FigureEight {
                center,
                amplitude: amp,
                angular_rate: w,
                roll,
                pitch,
            } => {
                let (s1, c1) = (w * t).sin_cos();
                let (s2, c2) = (2.0 * s1 * c1, c1 * c1 - s1 * s1);
                let (w2, w4) = (w * w, 4.0 * w * w);
                let velocity = Vector3::new(amp.x * w * c1, 2.0 * amp.y * w * c2, 2.0 * amp.z * w * c2);
                let acceleration = Vector3::new(-amp.x * w2 * s1, -amp.y * w4 * s2, -amp.z * w4 * s2);
                // Heading of the horizontal velocity, whose direction gives its sine and cosine;
                // it never vanishes (ẋ = 0 needs cos Ωt = 0, where ẏ = −2BΩ).
                let (vx, vy, ax, ay) = (velocity.x, velocity.y, acceleration.x, acceleration.y);
                let speed2 = vx * vx + vy * vy;
                let speed = speed2.sqrt();
                let chi_dot = Vector3::new((vx * ay - vy * ax) / speed2, pitch * w * c1, 2.0 * roll * w * c2);
                let sines = euler::EulerSines {
                    yaw: (vy / speed, vx / speed),
                    pitch: (pitch * s1).sin_cos(),
                    roll: (roll * s2).sin_cos(),
                };
                let (rotation, body_rate) = (sines.rotation(), sines.body_rate(&chi_dot));
                Kinematics {
                    position: center + Vector3::new(amp.x * s1, amp.y * s2, amp.z * s2),
                    velocity,
                    acceleration,
                    rotation,
                    body_rate,
                }
            }
            Motion::VioEllipse {
                center,
                amplitude: amp,
                angular_rate: k,
                height_frequency: k1,
                roll,
                pitch,
            } => {
                let (s, c) = (k * t).sin_cos();
                let kz = k1 * k;
                let (sz, cz) = (kz * t).sin_cos();
                let (st, ct) = t.sin_cos();
                let chi = Vector3::new(k * t, pitch * st, roll * ct);
                let chi_dot = Vector3::new(*k, pitch * ct, -roll * st);
                let (rotation, body_rate) = from_euler(chi, chi_dot);
                Kinematics {
                    position: center + Vector3::new(amp.x * c, amp.y * s, amp.z * sz),
                    velocity: Vector3::new(-amp.x * k * s, amp.y * k * c, amp.z * kz * cz),
                    acceleration: Vector3::new(-amp.x * k * k * c, -amp.y * k * k * s, -amp.z * kz * kz * sz),
                    rotation,
                    body_rate,
                }
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
}
