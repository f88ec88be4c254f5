//! The covariance of a preintegration with a lever arm, complete: the gyro noise that the
//! conversion to the body origin (`extrinsics::to_body`) puts into the corrected accelerometer,
//! besides the direct gyro and accelerometer noise.
//!
//! | item | convention |
//! |---|---|
//! | readings | the body origin's, `ω_k = R(ω_s − b_g)`, `a_k = R(a_s − b_a) − α_k × r − ω_k × (ω_k × r)`, `α_k = Σ_j w_kj ω_j` over `j ∈ {k−1, k, k+1}` (the conversion's difference weights: central inside, one-sided at the batch's ends) |
//! | noise | `η_k = R n_g,k`, `ñ_k = R n_a,k`: white, isotropic, the sensor's variances (`R` is a rotation); the accelerometer's is `ν_k = ñ_k + Σ_j M_kj η_j` with `M_kj = w_kj [r]× − δ_kj D(ω_k)`, `D(ω) = ∂(ω×(ω×r))/∂ω = −[ω×r]× − [ω]×[r]×` (Titterton & Weston 3.48, Groves 2.165) |
//! | variance | of a sample's noise, `σ² s / h` with `h` the interval it is held over (lie_euler; the one before for the last sample) or the one it ends (midpoint; the one after for the first sample), `s` the saturation factor² where clipped: a property of the sample, so that windows of one batch agree |
//! | step | the kernel's own linearisation `δx' = F δx + Σ B_s (η_s, ν_s)` (`Preintegrator::step_matrices`, `midpoint_step_matrices`), with `ν` expanded: the noise of sample k enters the steps of samples k−1, k, k+1 (k±2 in the midpoint scheme), so it is correlated process noise |
//! | propagation | exact, by carrying `C_z = Cov(δx, z)` for each noise `z` still to enter (an augmented state, kept as its cross blocks): `Σ' = F Σ Fᵀ + Σ_z (F C_z B_zᵀ + B_z C_zᵀ Fᵀ + q_z B_z B_zᵀ)`, `C_z' = F C_z + q_z B_z` |
//! | edges | the crosses with the noises a neighbouring window shares, the gyro noise of samples `e−1, e, e+1` and the accelerometer noise of `e` at each edge sample `e`, so that [`LeverNoise::merge`] adds `Cov(δx_ij, δx_jk) = J_1 (Σ_z C_z,ij q_z⁻¹ C_z,jkᵀ) J_2ᵀ`: merging is exact |
//! | bias | the sensor's biases (constant over the window: α's difference cancels them): `∂ω/∂b_g = −R`, `∂a_k/∂b_g = D(ω_k) R`, `∂a/∂b_a = −R`; Jacobian `J' = F J + G_b`, and with the bias walk its cross covariance and variances as the kernel's `BiasWalk` |
//!
//! The no-lever-arm kernels are untouched: this runs beside them, on the dense step matrices, for
//! windows whose edges are samples.

use nalgebra::{Matrix3, SMatrix, Vector3};
use rayon::prelude::*;

use super::merge::composition;
use super::{clipped_at, BiasJacobian, ClipMask, Covariance15, Covariance9, Preintegrator, Scheme};
use crate::error::{Error, Result};
use crate::extrinsics::{alpha_weights, centripetal_sensitivity, SensorPose};
use crate::imu::Samples;
use crate::so3;

/// 9×3 block: a noise's input, or the cross covariance of the state error with it.
type Block = SMatrix<f64, 9, 3>;

/// A noise of the batch: sample index and sensor (`true`: gyro).
type Key = (usize, bool);

/// The cross covariance of a window's error with one noise at its edge, and that noise's variance.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Edge {
    cross: Block,
    var: f64,
}

const NO_EDGE: Edge = Edge {
    cross: Block::from_array_storage(nalgebra::ArrayStorage([[0.0; 9]; 3])),
    var: 0.0,
};

/// The edge noises, in this order: gyro of samples `e − 1`, `e`, `e + 1`, accelerometer of `e`.
const EDGE_KEYS: [(isize, bool); 4] = [(-1, true), (0, true), (1, true), (0, false)];

/// The lever-arm-complete error statistics of one window (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LeverNoise {
    scheme: Scheme,
    delta_rotation: Matrix3<f64>,
    delta_velocity: Vector3<f64>,
    delta_position: Vector3<f64>,
    delta_t: f64,
    covariance: Covariance9,
    jac: BiasJacobian,
    /// `Cov(δx, δb)` (9×6) and the bias variances `[gyro, accel]`, with the bias walk.
    walk: Option<(BiasJacobian, [f64; 2])>,
    intervals: usize,
    start: [Edge; 4],
    end: [Edge; 4],
}

/// What a window's pass reads of the batch.
struct Batch<'a> {
    samples: &'a Samples<'a>,
    clipped: Option<&'a ClipMask<'a>>,
    arm: Vector3<f64>,
    template: &'a Preintegrator,
}

impl Batch<'_> {
    /// `[M_k,k−1, M_kk, M_k,k+1]` (module docs).
    fn noise_map(&self, k: usize) -> [Matrix3<f64>; 3] {
        let (lo, hi, w) = alpha_weights(self.samples.t(), k);
        let arm = so3::hat(&self.arm) * w;
        let mut out = [Matrix3::zeros(); 3];
        out[lo + 1 - k] -= arm;
        out[hi + 1 - k] += arm;
        out[1] -= self.centripetal(k);
        out
    }

    /// `D(ω_k)` (the conversion's own derivative, `extrinsics::centripetal_sensitivity`).
    fn centripetal(&self, k: usize) -> Matrix3<f64> {
        centripetal_sensitivity(&self.samples.gyro_at(k), &self.arm)
    }

    /// The variance of noise `key` (module docs).
    fn variance(&self, (k, gyro): Key) -> f64 {
        let t = self.samples.t();
        let last = t.len() - 1;
        let held = match self.template.scheme {
            Scheme::Euler => k.min(last - 1),
            Scheme::Midpoint => k.max(1) - 1,
        };
        let h = t[held + 1] - t[held];
        let p = &self.template;
        let f2 = p.saturation_noise_factor * p.saturation_noise_factor;
        let flags = clipped_at(self.clipped, k);
        let (density, flagged) = if gyro {
            (p.noise.gyro_density, flags.gyro)
        } else {
            (p.noise.accel_density, flags.accel)
        };
        density * density / h * if flagged { f2 } else { 1.0 }
    }
}

/// The noise inputs of one step, summed per noise, and its response to the sensor's biases.
struct Inputs {
    noise: Vec<(Key, Block)>,
    bias: BiasJacobian,
}

impl Inputs {
    fn new() -> Self {
        Self {
            noise: Vec::with_capacity(6),
            bias: BiasJacobian::zeros(),
        }
    }

    fn add(&mut self, key: (isize, bool), n: usize, b: Block) {
        let Ok(k) = usize::try_from(key.0) else { return };
        if k >= n {
            return;
        }
        match self.noise.iter_mut().find(|(z, _)| *z == (k, key.1)) {
            Some((_, sum)) => *sum += b,
            None => self.noise.push(((k, key.1), b)),
        }
    }

    /// Sample `k`'s inputs: its gyro through `bg`, its accelerometer through `ba` (with the gyro
    /// noise of k−1, k, k+1 that the conversion puts there); the biases through `−R` on each
    /// sensor and the centripetal `D(ω_k) R` on the accelerometer (module docs).
    fn sample(&mut self, batch: &Batch<'_>, k: usize, bg: &Block, ba: &Block, r: &Matrix3<f64>) {
        let n = batch.samples.len();
        let ki = k as isize;
        for (j, m) in batch.noise_map(k).iter().enumerate() {
            self.add((ki + j as isize - 1, true), n, ba * m);
        }
        self.add((ki, true), n, *bg);
        self.add((ki, false), n, *ba);
        // The kernels' inputs are +∂x/∂reading (lie_euler) or −∂x/∂reading (midpoint: its noise
        // is subtracted); the noise's sign does not matter to a covariance, the bias's does.
        let sign = match batch.template.scheme {
            Scheme::Euler => 1.0,
            Scheme::Midpoint => -1.0,
        };
        let mut cols = self.bias.fixed_columns_mut::<3>(0);
        cols += (ba * batch.centripetal(k) - bg) * r * sign;
        let mut cols = self.bias.fixed_columns_mut::<3>(3);
        cols -= ba * r * sign;
    }
}

/// `(B_g, B_a)` of a dense 9×6 midpoint input.
fn split(b: &SMatrix<f64, 9, 6>) -> (Block, Block) {
    (b.fixed_columns::<3>(0).into(), b.fixed_columns::<3>(3).into())
}

impl LeverNoise {
    /// The window of samples `first..=last` of `samples` (the body origin's readings of the whole
    /// batch, biases removed, from a sensor at `pose`; `clipped`: its saturation flags),
    /// preintegrated as `template` (empty, zero bias) does.
    pub fn window(
        samples: &Samples<'_>,
        clipped: Option<&ClipMask<'_>>,
        pose: &SensorPose,
        (first, last): (usize, usize),
        template: &Preintegrator,
    ) -> Result<Self> {
        samples.validate()?;
        if let Some(mask) = clipped {
            mask.check(samples.len())?;
        }
        if !(first < last && last < samples.len()) {
            return Err(Error::Parameter {
                name: "window",
                expected: "two sample indices, the first before the second",
                got: format!("{first}..={last} of {} samples", samples.len()),
            });
        }
        let batch = Batch {
            samples,
            clipped,
            arm: pose.lever_arm,
            template,
        };
        let mut p = template.clone();
        let mut out = Self::empty(template);
        let mut pending: Vec<(Key, Block)> = Vec::new();
        let t = samples.t();
        if template.scheme == Scheme::Midpoint {
            p.integrate_measurement(&samples.accel_at(first), &samples.gyro_at(first), 0.0);
        }
        for k in first..last {
            let h = t[k + 1] - t[k];
            let mut inputs = Inputs::new();
            let f = match template.scheme {
                Scheme::Euler => {
                    let (a, w) = (samples.accel_at(k), samples.gyro_at(k));
                    let m = p.step_matrices(&a, &w, h);
                    inputs.sample(&batch, k, &m.c, &m.b, &pose.rotation);
                    p.integrate_measurement(&a, &w, h);
                    m.a
                }
                Scheme::Midpoint => {
                    let (a, w) = (samples.accel_at(k + 1), samples.gyro_at(k + 1));
                    let Some(m) = p.midpoint_step_matrices(&a, &w, h) else {
                        return Err(Error::Overflow { index: k });
                    };
                    let ((g0, a0), (g1, a1)) = (split(&m.b0), split(&m.b1));
                    inputs.sample(&batch, k, &g0, &a0, &pose.rotation);
                    inputs.sample(&batch, k + 1, &g1, &a1, &pose.rotation);
                    p.integrate_measurement(&a, &w, h);
                    m.a
                }
            };
            out.step(&batch, &f, &inputs, &mut pending, h);
            // Noises that no later step takes are done, unless they are the start's edge.
            pending.retain(|((z, _), _)| *z >= k || *z <= first + 1);
        }
        let edge = |e: usize| {
            EDGE_KEYS.map(|(o, gyro)| {
                let Some(k) = e.checked_add_signed(o).filter(|&k| k < samples.len()) else {
                    return NO_EDGE;
                };
                let cross = pending
                    .iter()
                    .find(|(z, _)| *z == (k, gyro))
                    .map_or(Block::zeros(), |(_, c)| *c);
                Edge {
                    cross,
                    var: batch.variance((k, gyro)),
                }
            })
        };
        (out.start, out.end) = (edge(first), edge(last));
        (out.delta_rotation, out.delta_velocity, out.delta_position, out.delta_t) =
            (p.delta_rotation, p.delta_velocity, p.delta_position, p.delta_t);
        out.intervals = last - first;
        if !out.is_finite() {
            return Err(Error::Overflow { index: last });
        }
        Ok(out)
    }

    /// [`LeverNoise::window`] between each pair of consecutive `boundaries` (stamps of `samples`,
    /// strictly increasing; a stamp between samples is refused: the edge noises are samples'),
    /// the windows in parallel.
    pub fn windows(
        samples: &Samples<'_>,
        clipped: Option<&ClipMask<'_>>,
        pose: &SensorPose,
        boundaries: &[f64],
        template: &Preintegrator,
    ) -> Result<Vec<Self>> {
        let t = samples.t();
        let index = |b: f64| {
            t.binary_search_by(|x| x.total_cmp(&b)).map_err(|_| Error::Parameter {
                name: "boundaries",
                expected: "sample stamps (with a lever arm a window starts and ends on samples)",
                got: format!("{b} s"),
            })
        };
        let edges = boundaries.iter().map(|&b| index(b)).collect::<Result<Vec<_>>>()?;
        edges
            .par_windows(2)
            .map(|w| Self::window(samples, clipped, pose, (w[0], w[1]), template))
            .collect()
    }

    fn empty(template: &Preintegrator) -> Self {
        Self {
            scheme: template.scheme,
            delta_rotation: Matrix3::identity(),
            delta_velocity: Vector3::zeros(),
            delta_position: Vector3::zeros(),
            delta_t: 0.0,
            covariance: Covariance9::zeros(),
            jac: BiasJacobian::zeros(),
            walk: template
                .covariance_combined()
                .map(|_| (BiasJacobian::zeros(), [0.0; 2])),
            intervals: 0,
            start: [NO_EDGE; 4],
            end: [NO_EDGE; 4],
        }
    }

    /// One step with transition `f` and the noise `inputs` (module docs).
    fn step(&mut self, batch: &Batch<'_>, f: &Covariance9, inputs: &Inputs, pending: &mut Vec<(Key, Block)>, h: f64) {
        let mut cov = f * self.covariance * f.transpose();
        for c in pending.iter_mut() {
            c.1 = f * c.1;
        }
        for (z, b) in &inputs.noise {
            let q = batch.variance(*z);
            let moved = pending.iter_mut().find(|(y, _)| y == z);
            if let Some((_, c)) = &moved {
                let x = c * b.transpose();
                cov += x + x.transpose();
            }
            cov += b * b.transpose() * q;
            match moved {
                Some((_, c)) => *c += b * q,
                None => pending.push((*z, b * q)),
            }
        }
        let g_b = &inputs.bias;
        self.jac = f * self.jac + g_b;
        if let Some((cross, var)) = self.walk.as_mut() {
            let noise = &batch.template.noise;
            let v = SMatrix::<f64, 6, 6>::from_diagonal(&nalgebra::Vector6::new(
                var[0], var[0], var[0], var[1], var[1], var[1],
            ));
            let y = f * *cross;
            let x = y * g_b.transpose();
            cov += x + x.transpose() + g_b * v * g_b.transpose();
            *cross = y + g_b * v;
            var[0] += noise.gyro_random_walk * noise.gyro_random_walk * h;
            var[1] += noise.accel_random_walk * noise.accel_random_walk * h;
        }
        self.covariance = (cov + cov.transpose()) * 0.5;
    }

    /// This window (i → j) followed by `next` (j → k), of the same batch: the error composes as
    /// `J_1 δx_ij + J_2 δx_jk` (`merge.rs`), plus the correlation through the noises both windows
    /// take at j (module docs). Exact; the bias walk is not merged (as the kernel's merge).
    pub fn merge(&self, next: &LeverNoise) -> Result<LeverNoise> {
        if self.scheme != next.scheme {
            return Err(Error::Parameter {
                name: "next",
                expected: "a window of the same scheme",
                got: format!("{:?} after {:?}", next.scheme, self.scheme),
            });
        }
        let r = self.delta_rotation;
        let (j1, j2) = composition(
            &r,
            (
                &next.delta_rotation,
                &next.delta_velocity,
                &next.delta_position,
                next.delta_t,
            ),
        );
        let mut shared = Covariance9::zeros();
        for (e, s) in self.end.iter().zip(&next.start) {
            if e.var > 0.0 {
                shared += e.cross * s.cross.transpose() / e.var;
            }
        }
        let x = j1 * shared * j2.transpose();
        let cov = j1 * self.covariance * j1.transpose() + j2 * next.covariance * j2.transpose() + x + x.transpose();
        // An edge noise of the merged window may also be an edge noise of the other part when a
        // part is short: its cross, found by the noise's offset from that part's edge.
        let other = |edges: &[Edge; 4], (o, gyro): (isize, bool), shift: isize| {
            EDGE_KEYS
                .iter()
                .position(|&key| key == (o + shift, gyro))
                .map_or(Block::zeros(), |m| edges[m].cross)
        };
        let (c1, c2) = (self.intervals as isize, next.intervals as isize);
        let mut out = LeverNoise {
            delta_rotation: r * next.delta_rotation,
            delta_velocity: self.delta_velocity + r * next.delta_velocity,
            delta_position: self.delta_position + self.delta_velocity * next.delta_t + r * next.delta_position,
            delta_t: self.delta_t + next.delta_t,
            covariance: (cov + cov.transpose()) * 0.5,
            jac: j1 * self.jac + j2 * next.jac,
            walk: None,
            intervals: self.intervals + next.intervals,
            ..self.clone()
        };
        for (m, &key) in EDGE_KEYS.iter().enumerate() {
            out.start[m].cross = j1 * self.start[m].cross + j2 * other(&next.start, key, -c1);
            out.end[m] = Edge {
                cross: j2 * next.end[m].cross + j1 * other(&self.end, key, c2),
                var: next.end[m].var,
            };
        }
        Ok(out)
    }

    /// Covariance of `[δθ, δv, δp]` (9×9), body frame.
    pub fn covariance(&self) -> Covariance9 {
        self.covariance
    }

    /// `∂(θ, v, p)/∂(b_g, b_a)` (9×6) of the sensor's biases.
    pub fn bias_jacobian(&self) -> BiasJacobian {
        self.jac
    }

    /// Covariance of `[δθ, δv, δp, δb_g, δb_a]` (15×15) with the bias walk, when the template
    /// tracked it (and the window was not merged).
    pub fn covariance_combined(&self) -> Option<Covariance15> {
        let (cross, var) = self.walk.as_ref()?;
        let mut out = Covariance15::zeros();
        out.fixed_view_mut::<9, 9>(0, 0).copy_from(&self.covariance);
        out.fixed_view_mut::<9, 6>(0, 9).copy_from(cross);
        out.fixed_view_mut::<6, 9>(9, 0).copy_from(&cross.transpose());
        for i in 0..3 {
            out[(9 + i, 9 + i)] = var[0];
            out[(12 + i, 12 + i)] = var[1];
        }
        Some(out)
    }

    /// The complete state as a flat list (matrices column-major): scheme (0 lie_euler, 1
    /// midpoint), ΔR, Δv, Δp, Δt, covariance, Jacobian, bias walk (flag, cross, variances),
    /// intervals, then the start and end edges (each: cross, variance).
    pub fn state_words(&self) -> Vec<f64> {
        let mut w = vec![if self.scheme == Scheme::Midpoint { 1.0 } else { 0.0 }];
        let (cross, var) = self.walk.unwrap_or((BiasJacobian::zeros(), [0.0; 2]));
        for part in [
            self.delta_rotation.as_slice(),
            self.delta_velocity.as_slice(),
            self.delta_position.as_slice(),
            &[self.delta_t],
            self.covariance.as_slice(),
            self.jac.as_slice(),
            &[if self.walk.is_some() { 1.0 } else { 0.0 }],
            cross.as_slice(),
            &var,
            &[self.intervals as f64],
        ] {
            w.extend_from_slice(part);
        }
        for e in self.start.iter().chain(&self.end) {
            w.extend_from_slice(e.cross.as_slice());
            w.push(e.var);
        }
        w
    }

    /// The window whose [`LeverNoise::state_words`] are `words`; another length is an
    /// [`Error::RowCount`].
    pub fn from_state_words(words: &[f64]) -> Result<Self> {
        const LEN: usize = 1 + 9 + 3 + 3 + 1 + 81 + 54 + 1 + 54 + 2 + 1 + 8 * 28;
        if words.len() != LEN {
            return Err(Error::RowCount {
                input: LEN,
                output: words.len(),
            });
        }
        let mut at = 0;
        let mut take = |n: usize| {
            at += n;
            &words[at - n..at]
        };
        let scheme = if take(1)[0] != 0.0 {
            Scheme::Midpoint
        } else {
            Scheme::Euler
        };
        let delta_rotation = Matrix3::from_column_slice(take(9));
        let delta_velocity = Vector3::from_column_slice(take(3));
        let delta_position = Vector3::from_column_slice(take(3));
        let delta_t = take(1)[0];
        let covariance = Covariance9::from_column_slice(take(81));
        let jac = BiasJacobian::from_column_slice(take(54));
        let walked = take(1)[0] != 0.0;
        let cross = BiasJacobian::from_column_slice(take(54));
        let var = [take(1)[0], take(1)[0]];
        // A count of intervals: exact in f64.
        let intervals = take(1)[0] as usize;
        let mut edge = || Edge {
            cross: Block::from_column_slice(take(27)),
            var: take(1)[0],
        };
        let start = [edge(), edge(), edge(), edge()];
        let end = [edge(), edge(), edge(), edge()];
        Ok(Self {
            scheme,
            delta_rotation,
            delta_velocity,
            delta_position,
            delta_t,
            covariance,
            jac,
            walk: walked.then_some((cross, var)),
            intervals,
            start,
            end,
        })
    }

    fn is_finite(&self) -> bool {
        self.covariance.iter().chain(self.jac.iter()).all(|v| v.is_finite())
            && self
                .start
                .iter()
                .chain(&self.end)
                .all(|e| e.cross.iter().all(|v| v.is_finite()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imu::Noise;

    type Readings = (Vec<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>);

    /// `n` samples at 200 Hz (stamps jittered by `jitter` of a step), rates ~1 rad/s.
    fn readings(n: usize, jitter: f64) -> Readings {
        let t = (0..n)
            .map(|k| 0.005 * (k as f64 + jitter * (0.37 * k as f64).sin()))
            .collect();
        let gyro = (0..n)
            .map(|k| {
                let s = k as f64 * 0.005;
                [(1.3 * s).sin(), 0.8 * (2.1 * s + 1.0).cos(), 0.5 + s]
            })
            .collect();
        let accel = (0..n)
            .map(|k| [(k as f64).sin(), (0.7 * k as f64).cos() * 2.0, 9.81])
            .collect();
        (t, gyro, accel)
    }

    fn template(scheme: Scheme) -> Preintegrator {
        let noise = Noise {
            gyro_density: 2e-3,
            accel_density: 2e-2,
            gyro_random_walk: 1e-4,
            accel_random_walk: 1e-3,
        };
        Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise).with_scheme(scheme)
    }

    fn pose(arm: [f64; 3]) -> Result<SensorPose> {
        SensorPose::new(*so3::exp(&Vector3::new(0.3, -0.2, 1.1)).matrix(), Vector3::from(arm))
    }

    fn relative(a: &Covariance9, b: &Covariance9) -> f64 {
        (a - b).amax() / b.amax()
    }

    #[test]
    fn without_an_arm_it_is_the_kernel() -> Result<()> {
        // lie_euler on jittered stamps, midpoint on uniform ones (its first sample's variance
        // takes the interval before it here, the one after in the kernel: module docs)
        for (scheme, jitter) in [(Scheme::Euler, 0.2), (Scheme::Midpoint, 0.0)] {
            let (t, gyro, accel) = readings(60, jitter);
            let samples = Samples::new(&t, &gyro, &accel)?;
            let p = pose([0.0; 3])?;
            let tpl = template(scheme).with_bias_walk();
            let ours = LeverNoise::window(&samples, None, &p, (5, 50), &tpl)?;
            let mut kernel = tpl.clone();
            if scheme == Scheme::Midpoint {
                kernel.integrate_measurement(&samples.accel_at(5), &samples.gyro_at(5), 0.0);
            }
            for k in 5..50 {
                let j = if scheme == Scheme::Euler { k } else { k + 1 };
                kernel.integrate_measurement(&samples.accel_at(j), &samples.gyro_at(j), t[k + 1] - t[k]);
            }
            assert!(relative(&ours.covariance(), &kernel.covariance()) < 1e-12);
            // the bias columns are the sensor's: the body ones times R
            let jac = kernel.bias_jacobian();
            let mut mapped = jac;
            for c in [0, 3] {
                let m = jac.fixed_columns::<3>(c) * p.rotation;
                mapped.fixed_columns_mut::<3>(c).copy_from(&m);
            }
            assert!((ours.bias_jacobian() - mapped).amax() < 1e-12 * mapped.amax());
            let c = kernel.covariance_combined().ok_or(Error::Overflow { index: 0 })?;
            let ours_c = ours.covariance_combined().ok_or(Error::Overflow { index: 0 })?;
            let mut t15 = Covariance15::identity();
            t15.fixed_view_mut::<3, 3>(9, 9).copy_from(&p.rotation);
            t15.fixed_view_mut::<3, 3>(12, 12).copy_from(&p.rotation);
            let d = ours_c - t15.transpose() * c * t15;
            assert!(d.amax() < 1e-12 * c.amax());
        }
        Ok(())
    }

    #[test]
    fn merged_windows_are_one_pass_and_the_edge_correlation_matters() -> Result<()> {
        let (t, gyro, accel) = readings(40, 0.2);
        let samples = Samples::new(&t, &gyro, &accel)?;
        let p = pose([0.3, -0.1, 0.15])?;
        for scheme in [Scheme::Euler, Scheme::Midpoint] {
            let tpl = template(scheme);
            let whole = LeverNoise::window(&samples, None, &p, (2, 37), &tpl)?;
            // short parts (1 and 2 intervals) share edge noises with both neighbours
            for cuts in [vec![2, 20, 37], vec![2, 3, 5, 6, 20, 36, 37], vec![2, 4, 5, 37]] {
                let mut merged = LeverNoise::window(&samples, None, &p, (cuts[0], cuts[1]), &tpl)?;
                for w in cuts[1..].windows(2) {
                    merged = merged.merge(&LeverNoise::window(&samples, None, &p, (w[0], w[1]), &tpl)?)?;
                }
                assert!(
                    relative(&merged.covariance(), &whole.covariance()) < 1e-10,
                    "{scheme:?} {cuts:?}"
                );
                let jac = (merged.bias_jacobian() - whole.bias_jacobian()).amax();
                assert!(jac < 1e-10 * whole.bias_jacobian().amax());
                for (a, b) in merged
                    .end
                    .iter()
                    .chain(&merged.start)
                    .zip(whole.end.iter().chain(&whole.start))
                {
                    assert!((a.cross - b.cross).amax() < 1e-10 * whole.covariance().amax());
                }
            }
            // without the correlation through the cut the merge is off by far more
            let (a, b) = (
                LeverNoise::window(&samples, None, &p, (2, 20), &tpl)?,
                LeverNoise::window(&samples, None, &p, (20, 37), &tpl)?,
            );
            let cut = LeverNoise {
                end: [NO_EDGE; 4],
                ..a.clone()
            };
            assert!(relative(&cut.merge(&b)?.covariance(), &whole.covariance()) > 1e-4);
            let words = LeverNoise::from_state_words(&a.state_words())?;
            assert_eq!(words, a);
        }
        Ok(())
    }
}
