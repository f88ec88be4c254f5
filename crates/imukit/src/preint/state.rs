//! The complete state of a [`Preintegrator`] as a flat list of numbers, and back: what a copy in
//! another process (Python's pickle, a checkpoint) needs to continue exactly where this one is,
//! including the parts that are not public (covariance blocks, Jacobian, bias walk, the midpoint
//! scheme's end samples and their noise correlations, the projection counter).
//!
//! Layout (all f64; matrices column-major): scheme (3 lie_euler, 2 midpoint), b_g (3), b_a (3),
//! noise (4: densities, random walks), saturation factor, ΔR (9), Δv (3), Δp (3), Δt, covariance
//! blocks (6 × 9), Jacobian (54), bias walk (flag, cross 54, var_g, var_a), first and last
//! midpoint samples (each: flag, accel 3, gyro 3, var flag, var 2, scale 2), start cross
//! covariance (54), the last sample's pending input (54, then in midpoint states its `h/2`),
//! intervals since the last projection, then the continuity ends (first and last, each: flag,
//! time flag, t, accel 3, gyro 3; absent in states written before them: unknown).
//!
//! States hold their blocks as the schemes do: in frame i (`δφ = ΔR δθ`; `mod.rs`), the midpoint
//! covariance without the last sample's noise (`midpoint.rs`). Euler states of earlier versions
//! (scheme 0) held the blocks in the body frame at j; they load, converted to frame i at their
//! stored `ΔR` (the θ rows and columns premultiplied by it), and continue as an uninterrupted run
//! does up to rounding. Midpoint states of earlier versions (scheme 1) held their blocks in the
//! body frame with the last sample's noise included, and are refused: the pending input cannot be
//! recovered from them.

use nalgebra::{Matrix3, Vector3};

use super::blocks::{Cross, Input, ZERO_CROSS};
use super::midpoint::Sample;
use super::{BiasWalk, End, Ends, Preintegrator, Scheme};
use crate::error::{Error, Result};
use crate::imu::Noise;
use crate::mat3::M3;

/// The scheme words: midpoint's is 2 and euler's 3 since their blocks moved to frame i; euler's
/// was 0 before (module docs).
const EULER: f64 = 3.0;
const EULER_BODY_FRAME: f64 = 0.0;
const MIDPOINT: f64 = 2.0;

/// Appends numbers to the flat state.
struct Writer(Vec<f64>);

impl Writer {
    fn all(&mut self, x: &[f64]) {
        self.0.extend_from_slice(x);
    }
    fn cross(&mut self, c: &Cross) {
        for m in c.iter().flatten() {
            self.all(m.matrix().as_slice());
        }
    }
    fn flag(&mut self, b: bool) {
        self.0.push(if b { 1.0 } else { 0.0 });
    }
    fn sample(&mut self, s: &Option<Sample>) {
        self.flag(s.is_some());
        let s = s.unwrap_or(Sample {
            accel: Vector3::zeros(),
            gyro: Vector3::zeros(),
            var: None,
            scale: [1.0; 2],
        });
        self.all(s.accel.as_slice());
        self.all(s.gyro.as_slice());
        self.flag(s.var.is_some());
        self.all(&s.var.unwrap_or([0.0; 2]));
        self.all(&s.scale);
    }
}

/// Reads numbers from the flat state in order.
struct Reader<'a>(&'a [f64]);

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[f64; N]> {
        let Some((head, rest)) = self.0.split_first_chunk::<N>() else {
            return Err(Error::RowCount {
                input: N,
                output: self.0.len(),
            });
        };
        self.0 = rest;
        Ok(*head)
    }
    fn one(&mut self) -> Result<f64> {
        Ok(self.take::<1>()?[0])
    }
    fn flag(&mut self) -> Result<bool> {
        Ok(self.one()? != 0.0)
    }
    fn vector(&mut self) -> Result<Vector3<f64>> {
        Ok(Vector3::from(self.take::<3>()?))
    }
    fn matrix(&mut self) -> Result<Matrix3<f64>> {
        Ok(Matrix3::from_column_slice(&self.take::<9>()?))
    }
    fn cross(&mut self) -> Result<Cross> {
        let mut c = ZERO_CROSS;
        for m in c.iter_mut().flatten() {
            *m = M3::of(&self.matrix()?);
        }
        Ok(c)
    }
    fn sample(&mut self) -> Result<Option<Sample>> {
        let present = self.flag()?;
        let (accel, gyro) = (self.vector()?, self.vector()?);
        let has_var = self.flag()?;
        let (var, scale) = (self.take::<2>()?, self.take::<2>()?);
        Ok(present.then_some(Sample {
            accel,
            gyro,
            var: has_var.then_some(var),
            scale,
        }))
    }
}

impl Preintegrator {
    /// The complete state as a flat list (module docs); [`Preintegrator::from_state_words`] reads
    /// it back into an equal preintegrator.
    pub fn state_words(&self) -> Vec<f64> {
        let mut w = Writer(Vec::with_capacity(512));
        w.all(&[match self.scheme {
            Scheme::Euler => EULER,
            Scheme::Midpoint => MIDPOINT,
        }]);
        w.all(self.bias_gyro.as_slice());
        w.all(self.bias_accel.as_slice());
        let n = &self.noise;
        w.all(&[n.gyro_density, n.accel_density, n.gyro_random_walk, n.accel_random_walk]);
        w.all(&[self.saturation_noise_factor]);
        w.all(self.delta_rotation.as_slice());
        w.all(self.delta_velocity.as_slice());
        w.all(self.delta_position.as_slice());
        w.all(&[self.delta_t]);
        for m in &self.covariance {
            w.all(m.matrix().as_slice());
        }
        w.cross(&self.jac);
        w.flag(self.bias_walk.is_some());
        let walk = self.bias_walk.clone().unwrap_or(BiasWalk {
            cross: ZERO_CROSS,
            var_gyro: 0.0,
            var_accel: 0.0,
        });
        w.cross(&walk.cross);
        w.all(&[walk.var_gyro, walk.var_accel]);
        w.sample(&self.ends.first);
        w.sample(&self.ends.last);
        w.cross(&self.ends.start_cross);
        w.cross(&self.ends.pending.cross());
        if self.scheme == Scheme::Midpoint {
            w.all(&[self.ends.pending.half_h]);
        }
        w.all(&[f64::from(self.since_projection)]);
        for end in [self.boundary.first, self.boundary.last] {
            w.flag(end.is_some());
            let e = end.unwrap_or(End {
                t: None,
                accel: Vector3::zeros(),
                gyro: Vector3::zeros(),
            });
            w.flag(e.t.is_some());
            w.all(&[e.t.unwrap_or(0.0)]);
            w.all(e.accel.as_slice());
            w.all(e.gyro.as_slice());
        }
        w.0
    }

    /// The preintegrator whose [`Preintegrator::state_words`] are `words`; a list of another
    /// length is an [`Error::RowCount`] (the values are taken as they are: they come from
    /// `state_words`).
    pub fn from_state_words(words: &[f64]) -> Result<Self> {
        let mut r = Reader(words);
        let word = r.one()?;
        let scheme = match word {
            EULER | EULER_BODY_FRAME => Scheme::Euler,
            MIDPOINT => Scheme::Midpoint,
            other => {
                return Err(Error::Parameter {
                    name: "words",
                    expected: "a state of this version (scheme word 3 or, earlier, 0: lie_euler; 2: midpoint)",
                    got: if other == 1.0 {
                        "a midpoint state of an earlier version (scheme word 1), whose blocks cannot be converted"
                            .into()
                    } else {
                        format!("scheme word {other}")
                    },
                })
            }
        };
        let (bias_gyro, bias_accel) = (r.vector()?, r.vector()?);
        let [gyro_density, accel_density, gyro_random_walk, accel_random_walk] = r.take::<4>()?;
        let noise = Noise {
            gyro_density,
            accel_density,
            gyro_random_walk,
            accel_random_walk,
        };
        let mut p = Preintegrator::new(bias_gyro, bias_accel, noise).with_scheme(scheme);
        p.saturation_noise_factor = r.one()?;
        p.delta_rotation = r.matrix()?;
        (p.delta_velocity, p.delta_position) = (r.vector()?, r.vector()?);
        p.delta_t = r.one()?;
        for m in p.covariance.iter_mut() {
            *m = M3::of(&r.matrix()?);
        }
        p.jac = r.cross()?;
        let walk = r.flag()?;
        let cross = r.cross()?;
        let [var_gyro, var_accel] = r.take::<2>()?;
        p.bias_walk = walk.then_some(BiasWalk {
            cross,
            var_gyro,
            var_accel,
        });
        (p.ends.first, p.ends.last) = (r.sample()?, r.sample()?);
        p.ends.start_cross = r.cross()?;
        let pending = r.cross()?;
        let half_h = if scheme == Scheme::Midpoint { r.one()? } else { 0.0 };
        p.ends.pending = Input::of_cross(&pending, half_h);
        // A count below PROJECT_EVERY (16): exact in f64, and saturating on anything else.
        p.since_projection = r.one()? as u32;
        if !r.0.is_empty() {
            let mut end = || -> Result<Option<End>> {
                let present = r.flag()?;
                let t = r.flag()?.then_some(r.one()?);
                let (accel, gyro) = (r.vector()?, r.vector()?);
                Ok(present.then_some(End { t, accel, gyro }))
            };
            p.boundary = Ends {
                first: end()?,
                last: end()?,
            };
        }
        if !r.0.is_empty() {
            return Err(Error::RowCount {
                input: words.len() - r.0.len(),
                output: words.len(),
            });
        }
        Ok(if word == EULER_BODY_FRAME { p.in_own_frame() } else { p })
    }
}
