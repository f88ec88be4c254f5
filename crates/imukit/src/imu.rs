//! The IMU vocabulary every algorithm shares: the samples it reads, the biases it subtracts, the
//! noise densities it propagates, the navigation state it integrates, and gravity.
//!
//! | type | content | units |
//! |---|---|---|
//! | [`Samples`] | `t` (n), `gyro` (n × 3), `accel` (n × 3), body frame | s, rad/s, m/s² (specific force) |
//! | [`Bias`] | `gyro`, `accel`, subtracted from the samples | rad/s, m/s² |
//! | [`Noise`] | continuous densities σ_g, σ_a, σ_bg, σ_ba (Kalibr convention) | rad/s/√Hz, m/s²/√Hz, rad/s²/√Hz, m/s³/√Hz |
//! | [`NavState`] | `p`, `v` in the world frame, `q_wb` (body to world, Hamilton) | m, m/s |
//! | [`GRAVITY`] | the default world-frame gravity, z up | m/s² |
//!
//! [`Samples::new`] is the one shape check; the values (finite, strictly increasing time) are
//! checked by [`Samples::validate`] up front or by the integrators in their loops, both naming the
//! first bad sample.

use nalgebra::{UnitQuaternion, Vector3};

use crate::{time, Error, Result};

/// Default gravity in the world frame (z up) [m/s²]; every `gravity` default refers to it.
pub const GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// [`GRAVITY`] as a vector.
pub fn gravity() -> Vector3<f64> {
    Vector3::from(GRAVITY)
}

/// Position, velocity and attitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavState {
    /// Position in the world frame \[m\].
    pub position: Vector3<f64>,
    /// Velocity in the world frame [m/s].
    pub velocity: Vector3<f64>,
    /// Attitude `q_wb` (body to world).
    pub rotation: UnitQuaternion<f64>,
}

/// Constant sensor biases subtracted from the samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bias {
    /// Gyro bias [rad/s].
    pub gyro: Vector3<f64>,
    /// Accelerometer bias [m/s²].
    pub accel: Vector3<f64>,
}

/// Continuous-time noise densities (Kalibr convention).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Noise {
    /// Gyro white noise σ_g [rad/s/√Hz].
    pub gyro_density: f64,
    /// Accelerometer white noise σ_a [m/s²/√Hz].
    pub accel_density: f64,
    /// Gyro bias random walk σ_bg [rad/s²/√Hz].
    pub gyro_random_walk: f64,
    /// Accelerometer bias random walk σ_ba [m/s³/√Hz].
    pub accel_random_walk: f64,
}

impl Noise {
    /// Checks that every density is finite and non-negative.
    pub fn check(&self) -> Result<()> {
        let all = [
            self.gyro_density,
            self.accel_density,
            self.gyro_random_walk,
            self.accel_random_walk,
        ];
        if all.iter().all(|v| v.is_finite() && *v >= 0.0) {
            Ok(())
        } else {
            Err(Error::Parameter {
                name: "noise",
                expected: "finite, non-negative densities",
                got: format!("{all:?}"),
            })
        }
    }
}

/// The samples of one run: times \[s\], body rates [rad/s] and specific forces [m/s²], one row per
/// sample. Built by [`Samples::new`], which checks the shapes; the values are checked later.
#[derive(Debug, Clone, Copy)]
pub struct Samples<'a> {
    pub(crate) t: &'a [f64],
    pub(crate) gyro: &'a [[f64; 3]],
    pub(crate) accel: &'a [[f64; 3]],
}

impl<'a> Samples<'a> {
    /// The samples `t`, `gyro`, `accel`: equal lengths, at least one sample. The error names the
    /// argument at fault.
    pub fn new(t: &'a [f64], gyro: &'a [[f64; 3]], accel: &'a [[f64; 3]]) -> Result<Self> {
        let n = t.len();
        if n == 0 {
            return Err(Error::Parameter {
                name: "t",
                expected: "at least one sample",
                got: "0 samples".into(),
            });
        }
        for (name, data) in [("gyro", gyro), ("accel", accel)] {
            if data.len() != n {
                return Err(Error::RowCount {
                    input: n,
                    output: data.len(),
                }
                .in_argument(name));
            }
        }
        Ok(Self { t, gyro, accel })
    }

    /// Timestamps \[s\].
    pub fn t(&self) -> &'a [f64] {
        self.t
    }

    /// Body rates [rad/s].
    pub fn gyro(&self) -> &'a [[f64; 3]] {
        self.gyro
    }

    /// Specific forces [m/s²].
    pub fn accel(&self) -> &'a [[f64; 3]] {
        self.accel
    }

    /// Number of samples (at least one).
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Never true ([`Samples::new`] refuses no samples); present because `len` is.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Checks every value up front (for callers that must refuse bad input before changing any
    /// state; the integrators check in their loops instead).
    pub fn validate(&self) -> Result<()> {
        if !self.first_ok() || (0..self.t.len() - 1).any(|k| !self.step_ok(k)) {
            return Err(self.value_error());
        }
        Ok(())
    }

    /// The precise error for samples that failed a fast in-loop check: first bad index.
    pub fn value_error(&self) -> Error {
        if let Err(e) = time::check_increasing(self.t) {
            return e.in_argument("t");
        }
        for (name, data) in [("gyro", self.gyro), ("accel", self.accel)] {
            if let Some(index) = data.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
                return Error::NonFinite { index }.in_argument(name);
            }
        }
        Error::Parameter {
            name: "samples",
            expected: "values that failed the in-loop check",
            got: "none found on the second look".into(),
        }
    }

    /// Whether step k (into sample k+1) is usable: positive finite dt, finite samples at k+1.
    #[inline(always)]
    pub fn step_ok(&self, k: usize) -> bool {
        let h = self.t[k + 1] - self.t[k];
        let (g, a) = (self.gyro_at(k + 1), self.accel_at(k + 1));
        // x·0 is 0 for every finite x and NaN for ±inf and NaN; summing the products (not the
        // values) cannot overflow: one branch for six values.
        let zero = (g * 0.0).sum() + (a * 0.0).sum();
        h > 0.0 && h <= f64::MAX && zero == 0.0
    }

    /// Whether sample 0 is usable.
    pub fn first_ok(&self) -> bool {
        self.t[0].is_finite() && self.gyro[0].iter().chain(&self.accel[0]).all(|v| v.is_finite())
    }

    /// Gyro sample k.
    #[inline]
    pub fn gyro_at(&self, k: usize) -> Vector3<f64> {
        Vector3::from(self.gyro[k])
    }

    /// Accelerometer sample k.
    #[inline]
    pub fn accel_at(&self, k: usize) -> Vector3<f64> {
        Vector3::from(self.accel[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_names_the_argument_whose_length_differs() {
        let (t, rows) = ([0.0, 1.0], [[0.0; 3]; 2]);
        assert!(Samples::new(&t, &rows, &rows).is_ok());
        let short = Samples::new(&t, &rows, &rows[..1]).err();
        assert_eq!(short.and_then(|e| e.argument()), Some("accel"));
        let empty = Samples::new(&[], &[], &[]).err();
        assert_eq!(empty.and_then(|e| e.argument()), Some("t"));
    }

    #[test]
    fn validate_names_the_first_bad_sample() {
        let t = [0.0, 1.0, 2.0];
        let mut gyro = [[0.0; 3]; 3];
        gyro[2][1] = f64::NAN;
        let e = Samples::new(&t, &gyro, &[[0.0; 3]; 3]).and_then(|s| s.validate()).err();
        assert_eq!(e.map(|e| (e.argument(), e.index())), Some((Some("gyro"), Some(2))));
    }
}
