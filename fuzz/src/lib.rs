//! Inputs of the fuzz targets: sample series that are either raw bit patterns (NaN, ±inf,
//! subnormals, huge values, mismatched lengths) or plausible IMU streams (stamps stepping by
//! small, possibly zero or negative amounts; rates and forces scaled over many decades), so that
//! the fuzzer reaches both the validation and the integration paths.

use arbitrary::Arbitrary;

/// One plausible sample: a stamp step and the readings, as integers scaled by [`Series::Scaled`].
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct Sample {
    /// Stamp step in units of 1e-4 s (0: duplicate stamp; negative: going back).
    pub dt: i16,
    /// Body rate, in units of 2^(scale − 10) rad/s.
    pub gyro: [i16; 3],
    /// Specific force, in units of 2^(scale − 10) m/s².
    pub accel: [i16; 3],
}

/// A series of samples.
#[derive(Arbitrary, Debug, Clone)]
pub enum Series {
    /// Arbitrary values and lengths.
    Raw {
        /// Stamps [s].
        t: Vec<f64>,
        /// Flat rates.
        gyro: Vec<f64>,
        /// Flat forces.
        accel: Vec<f64>,
    },
    /// Consistent lengths, finite values.
    Scaled {
        /// First stamp [s].
        t0: f64,
        /// Binary exponent of the reading scale.
        scale: i8,
        /// The samples.
        samples: Vec<Sample>,
    },
}

/// Flat arrays `(t, gyro, accel)` of a series.
pub struct Arrays {
    /// Stamps [s].
    pub t: Vec<f64>,
    /// Flat rates, 3 per sample.
    pub gyro: Vec<f64>,
    /// Flat forces, 3 per sample.
    pub accel: Vec<f64>,
}

impl Series {
    /// The series as flat arrays.
    pub fn arrays(&self) -> Arrays {
        match self {
            Series::Raw { t, gyro, accel } => Arrays {
                t: t.clone(),
                gyro: gyro.clone(),
                accel: accel.clone(),
            },
            Series::Scaled { t0, scale, samples } => {
                let unit = 2f64.powi(i32::from(*scale) - 10);
                let mut time = *t0;
                let mut a = Arrays {
                    t: Vec::with_capacity(samples.len()),
                    gyro: Vec::with_capacity(3 * samples.len()),
                    accel: Vec::with_capacity(3 * samples.len()),
                };
                for s in samples {
                    time += f64::from(s.dt) * 1e-4;
                    a.t.push(time);
                    a.gyro.extend(s.gyro.iter().map(|v| f64::from(*v) * unit));
                    a.accel.extend(s.accel.iter().map(|v| f64::from(*v) * unit));
                }
                a
            }
        }
    }
}

impl Arrays {
    /// imukit's view of the arrays (an error for an empty series).
    pub fn samples(&self) -> imukit::Result<imukit::imu::Samples<'_>> {
        imukit::imu::Samples::new(&self.t, self.gyro.as_chunks().0, self.accel.as_chunks().0)
    }

    /// Whether every value is finite.
    pub fn finite(&self) -> bool {
        finite(&self.t) && finite(&self.gyro) && finite(&self.accel)
    }
}

/// Whether every value is finite.
pub fn finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// Panics (a fuzzer finding) when an `Ok` result from finite input holds a non-finite value.
pub fn assert_finite(what: &str, values: &[f64]) {
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        panic!("{what}: Ok result from finite input holds {v}");
    }
}

/// Panics (a fuzzer finding) when an `Ok` attitude is not a unit quaternion (a zero quaternion
/// is finite but no rotation).
pub fn assert_unit(what: &str, q: &[f64]) {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((norm - 1.0).abs() < 1e-9, "{what}: Ok attitude with |q| = {norm}");
}

/// Noise densities from `[gyro, accel, gyro walk, accel walk]`.
pub fn noise(d: [f64; 4]) -> imukit::imu::Noise {
    let [gyro_density, accel_density, gyro_random_walk, accel_random_walk] = d;
    imukit::imu::Noise {
        gyro_density,
        accel_density,
        gyro_random_walk,
        accel_random_walk,
    }
}

/// A 3-vector from an array.
pub fn vector(v: [f64; 3]) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::from(v)
}

/// The unit quaternion of `[x, y, z, w]` as the bindings make it (`imukit::quat::normalize`, which
/// rescales before squaring), or `None` where they refuse it (zero, non-finite). nalgebra's own
/// `new_normalize` overflows on a component beyond 1e154 and returns a zero "unit" quaternion.
pub fn unit(q: [f64; 4]) -> Option<nalgebra::UnitQuaternion<f64>> {
    let [x, y, z, w] = q;
    imukit::quat::normalize(&nalgebra::Quaternion::new(w, x, y, z)).ok()
}
