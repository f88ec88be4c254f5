//! Fixtures of the preintegration tests: a smooth 1 s window, a runner for either scheme, the
//! `[θ, v, p]` chart and a seeded normal generator for the Monte Carlo runs.

use nalgebra::{Matrix3, Rotation3, SVector, Vector3};

use imukit::imu::Noise;
use imukit::preint::{Preintegrator, Scheme};
use imukit::so3;

/// Sample spacing \[s\].
pub const H: f64 = 0.005;
/// Samples in the window.
pub const N: usize = 200;

/// White noise strong enough for a Monte Carlo to resolve, no bias random walk.
pub const NOISE: Noise = Noise {
    gyro_density: 2e-3,
    accel_density: 2e-2,
    gyro_random_walk: 0.0,
    accel_random_walk: 0.0,
};

/// `(accel, gyro)` of a smooth, rotating window (not a consistent trajectory: none is needed).
pub fn samples() -> Vec<(Vector3<f64>, Vector3<f64>)> {
    (0..N)
        .map(|k| {
            let s = k as f64 * H;
            (
                Vector3::new(
                    0.5 * (0.9 * s).sin() + 0.3,
                    0.4 * (0.3 * s).cos(),
                    9.81 + 0.2 * (1.7 * s).sin(),
                ),
                Vector3::new(
                    0.3 * (1.1 * s).sin() + 0.2,
                    0.2 * (0.7 * s).cos() - 0.4,
                    0.5 * (1.3 * s).sin() + 0.6,
                ),
            )
        })
        .collect()
}

/// All of `data` preintegrated at spacing `H` (euler: N intervals; midpoint: N − 1).
pub fn run(
    scheme: Scheme,
    bias: (Vector3<f64>, Vector3<f64>),
    noise: Noise,
    data: &[(Vector3<f64>, Vector3<f64>)],
) -> Preintegrator {
    let mut p = Preintegrator::new(bias.0, bias.1, noise).with_scheme(scheme);
    for (a, w) in data {
        p.integrate_measurement(a, w, H);
    }
    p
}

/// The deltas `(ΔR, Δv, Δp)`.
pub fn deltas(p: &Preintegrator) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    (p.delta_rotation, p.delta_velocity, p.delta_position)
}

/// The first-order bias correction of `p`'s deltas to `(bias_gyro, bias_accel)` (`ΔR Exp(J_θ δb_g)`,
/// `Δv + J_v δb`, `Δp + J_p δb`), the oracle of the quadratic-convergence tests. The library's one
/// implementation is Python's batched `imukit.preint.corrected`; this one is written from the same
/// formula, on the public bias Jacobian.
pub fn corrected(
    p: &Preintegrator,
    bias_gyro: &Vector3<f64>,
    bias_accel: &Vector3<f64>,
) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    let (dbg, dba) = (bias_gyro - p.bias_gyro, bias_accel - p.bias_accel);
    let d = p.bias_jacobian() * SVector::<f64, 6>::new(dbg.x, dbg.y, dbg.z, dba.x, dba.y, dba.z);
    let theta: Vector3<f64> = d.fixed_rows::<3>(0).into();
    (
        p.delta_rotation * so3::exp(&theta).matrix(),
        p.delta_velocity + d.fixed_rows::<3>(3),
        p.delta_position + d.fixed_rows::<3>(6),
    )
}

/// `[θ, v, p]` of `x` relative to `base`: `Log(ΔR_baseᵀ ΔR_x)`, `Δv_x − Δv_base`, `Δp_x − Δp_base`.
pub fn chart(base: &Preintegrator, x: (Matrix3<f64>, Vector3<f64>, Vector3<f64>)) -> SVector<f64, 9> {
    let mut d = SVector::<f64, 9>::zeros();
    let rel = Rotation3::from_matrix_unchecked(base.delta_rotation.transpose() * x.0);
    d.fixed_rows_mut::<3>(0).copy_from(&so3::log(&rel));
    d.fixed_rows_mut::<3>(3).copy_from(&(x.1 - base.delta_velocity));
    d.fixed_rows_mut::<3>(6).copy_from(&(x.2 - base.delta_position));
    d
}

/// xorshift64* + Box–Muller: a seeded normal generator for the Monte Carlo runs.
pub struct Normal(pub u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Three independent standard normal values.
    pub fn vector(&mut self) -> Vector3<f64> {
        Vector3::from_fn(|_, _| (-2.0 * self.uniform().ln()).sqrt() * (std::f64::consts::TAU * self.uniform()).cos())
    }
}
