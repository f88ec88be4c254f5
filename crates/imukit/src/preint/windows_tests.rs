//! The lanes (`lanes.rs`, the AVX paths) against the per-window kernel and against a dense
//! reference. Under `IMUKIT_SIMD=baseline` there are no lanes: the lane-only checks return early and
//! `run_block` is the per-window kernel.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use nalgebra::{Matrix3, SMatrix, Vector3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::{bundled, lanes, run_block, span, window, Span};
use crate::imu::{Noise, Samples};
use crate::preint::{ClipMask, Covariance9, Preintegrator, Scheme};
use crate::simd;
use crate::so3;

const NOISE: Noise = Noise {
    gyro_density: 1.7e-4,
    accel_density: 2e-3,
    gyro_random_walk: 2e-5,
    accel_random_walk: 3e-3,
};

/// A jittered 200 Hz stream of `n` samples turning on all axes.
fn stream(n: usize) -> (Vec<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(20);
    let t: Vec<f64> = (0..n)
        .map(|k| 0.3 + k as f64 * 0.005 + rng.random::<f64>() * 1e-3)
        .collect();
    let gyro = t
        .iter()
        .map(|&s| {
            [
                0.9 * (1.1 * s).sin() + 0.3,
                0.6 * (0.7 * s).cos(),
                1.5 * (1.3 * s).sin() - rng.random::<f64>(),
            ]
        })
        .collect();
    let accel = t
        .iter()
        .map(|&s| {
            [
                0.5 * (0.9 * s).sin(),
                0.4 * (0.3 * s).cos() + rng.random::<f64>(),
                9.81 + (1.7 * s).sin(),
            ]
        })
        .collect();
    (t, gyro, accel)
}

/// Boundaries whose windows hold 1, 2, 3, 4, 5, 7, 8, 9, 17, 1, 2, 40, … intervals (1, 2, L − 1 and
/// L + 1 for both lane widths), some on sample times and some between samples.
fn boundaries(t: &[f64]) -> Vec<f64> {
    // A one-interval window between samples starts on a sample (m % 3 == 1) or is on one.
    let lengths = [1, 2, 3, 4, 5, 7, 8, 9, 17, 1, 2, 40, 3, 5, 9, 1, 7, 30, 6, 1, 2, 11];
    let mut b = vec![t[2] + 0.0025];
    let mut k0 = 2; // the sample held at the last boundary
    for (m, len) in lengths.iter().enumerate() {
        // On a sample, the window ends at t[k0 + len]; between samples, after t[k0 + len − 1].
        if m % 3 == 0 {
            k0 += len;
            b.push(t[k0]);
        } else {
            k0 += len - 1;
            b.push(t[k0] + 0.0025);
        }
    }
    b
}

fn template() -> Preintegrator {
    Preintegrator::new(Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.05, 0.02, -0.1), NOISE)
}

/// `a` equals `b` bit for bit: the lanes fuse where the per-window kernel of the same path fuses.
fn assert_same(a: &Preintegrator, b: &Preintegrator) {
    if a != b {
        let fields = [
            ("rotation", a.delta_rotation == b.delta_rotation),
            ("velocity", a.delta_velocity == b.delta_velocity),
            ("position", a.delta_position == b.delta_position),
            ("covariance", a.covariance == b.covariance),
            ("jac", a.jac == b.jac),
            ("ends", a.ends == b.ends),
            ("bias walk", a.bias_walk == b.bias_walk),
            ("boundary", a.boundary == b.boundary),
        ];
        panic!("path {:?}: equal fields {fields:?}", simd::path());
    }
}

/// The template's scheme for each run of the comparisons.
const SCHEMES: [Scheme; 2] = [Scheme::Euler, Scheme::Midpoint];

/// Every template the lanes run: each scheme, without and with the bias walk (`combined`).
fn templates() -> Vec<Preintegrator> {
    SCHEMES
        .into_iter()
        .flat_map(|s| [template().with_scheme(s), template().with_scheme(s).with_bias_walk()])
        .collect()
}

#[test]
fn lanes_equal_the_per_window_kernel_on_windows_of_mixed_lengths() {
    let (t, gyro, accel) = stream(400);
    let samples = Samples::new(&t, &gyro, &accel).unwrap();
    let b = boundaries(&t);
    let spans: Vec<Span> = b.windows(2).map(|w| span(&t, w[0], w[1])).collect();
    let steps: Vec<usize> = spans.iter().map(|s| s.steps).collect();
    for len in [1, 2, 3, 5, 7, 9] {
        assert!(steps.contains(&len), "{steps:?}");
    }
    for template in templates() {
        let reference: Vec<Preintegrator> = b
            .windows(2)
            .map(|w| window(&samples, None, w[0], w[1], &template))
            .collect();
        // The windows grouped by length (as `preintegrate_windows` runs them), all 22 and the
        // first 21: a last bundle of two and of one, which runs on the per-window kernel.
        assert_eq!((bundled(22, Scheme::Euler), bundled(21, Scheme::Euler)), (22, 20));
        for edges in [&b[..], &b[..b.len() - 1]] {
            let grouped = run_block(&samples, None, edges, &template);
            assert_eq!(grouped.len(), edges.len() - 1);
            for (m, want) in reference.iter().take(edges.len() - 1).enumerate() {
                assert_same(&grouped[m], want);
            }
        }
        let Some(k) = lanes::lanes() else {
            continue;
        };
        // … and bundled in order, so that lanes of very different lengths run in lockstep.
        let in_order: Vec<Preintegrator> = spans
            .chunks(lanes::WIDTH)
            .flat_map(|bundle| lanes::run(&samples, bundle, &template, k))
            .collect();
        for (m, want) in reference.iter().enumerate() {
            let mut lane = in_order[m].clone();
            lane.boundary = want.boundary;
            assert_same(&lane, want);
        }
    }
}

#[test]
fn a_last_bundle_of_one_window_or_of_two_midpoint_windows_runs_alone() {
    let euler: Vec<usize> = (0..=9).map(|n| bundled(n, Scheme::Euler)).collect();
    let midpoint: Vec<usize> = (0..=9).map(|n| bundled(n, Scheme::Midpoint)).collect();
    assert_eq!(euler, [0, 0, 2, 3, 4, 4, 6, 7, 8, 8]);
    assert_eq!(midpoint, [0, 0, 0, 3, 4, 4, 4, 7, 8, 8]);
}

#[test]
fn a_clipped_sample_keeps_its_windows_on_the_per_window_kernel() {
    // A flag on the sample just after a boundary between samples: the euler window before it
    // does not read it, the midpoint window's end point is interpolated towards it and is flagged.
    let (t, gyro, accel) = stream(400);
    let samples = Samples::new(&t, &gyro, &accel).unwrap();
    let b = boundaries(&t);
    let hi = b[2]; // between samples (boundaries m % 3 != 0 are)
    let next = t.partition_point(|&x| x <= hi);
    assert!(t[next - 1] < hi && hi < t[next]);
    let mut flags = vec![false; t.len()];
    flags[next] = true;
    let mask = ClipMask {
        gyro: &flags,
        accel: &vec![false; t.len()],
    };
    for scheme in SCHEMES {
        let template = template()
            .with_scheme(scheme)
            .with_saturation_noise_factor(10.0)
            .unwrap();
        let reference: Vec<Preintegrator> = b
            .windows(2)
            .map(|w| window(&samples, Some(&mask), w[0], w[1], &template))
            .collect();
        let grouped = run_block(&samples, Some(&mask), &b, &template);
        for (m, want) in reference.iter().enumerate() {
            assert_same(&grouped[m], want);
        }
        // The flag changes the window ending at `hi` in the midpoint scheme only.
        let unflagged = window(&samples, None, b[1], b[2], &template);
        assert_eq!(reference[1] == unflagged, scheme == Scheme::Euler, "{scheme:?}");
    }
}

/// Forster's update with dense 9×9 matrices (`Preintegrator::step_matrices`, the module docs'
/// equations): `Σ ← A Σ Aᵀ + B Σ_a Bᵀ + C Σ_g Cᵀ`, `J ← A J − [C, B]`.
fn dense(
    samples: &Samples<'_>,
    span: &Span,
    p0: &Preintegrator,
) -> (Matrix3<f64>, Vector3<f64>, Covariance9, SMatrix<f64, 9, 6>) {
    let mut at = p0.clone();
    let (mut v, mut p) = (Vector3::zeros(), Vector3::zeros());
    let mut cov = Covariance9::zeros();
    let mut jac = SMatrix::<f64, 9, 6>::zeros();
    for j in 0..span.steps {
        let (a, w, h) = span.interval(samples, j);
        let s = at.step_matrices(&a, &w, h);
        let var = |d: f64| d * d / h;
        cov = s.a * cov * s.a.transpose()
            + s.b * s.b.transpose() * var(NOISE.accel_density)
            + s.c * s.c.transpose() * var(NOISE.gyro_density);
        let mut g = SMatrix::<f64, 9, 6>::zeros();
        g.fixed_view_mut::<9, 3>(0, 0).copy_from(&-s.c);
        g.fixed_view_mut::<9, 3>(0, 3).copy_from(&-s.b);
        jac = s.a * jac + g;
        let ra = at.delta_rotation * (a - at.bias_accel);
        p += v * h + ra * (0.5 * h * h);
        v += ra * h;
        at.delta_rotation *= so3::exp(&((w - at.bias_gyro) * h)).matrix();
    }
    (at.delta_rotation, p, cov, jac)
}

#[test]
fn lanes_match_a_dense_reference() {
    let (t, gyro, accel) = stream(400);
    let samples = Samples::new(&t, &gyro, &accel).unwrap();
    let b = boundaries(&t);
    let spans: Vec<Span> = b.windows(2).map(|w| span(&t, w[0], w[1])).collect();
    let Some(k) = lanes::lanes() else {
        return;
    };
    let lanes_out: Vec<Preintegrator> = spans
        .chunks(lanes::WIDTH)
        .flat_map(|bundle| lanes::run(&samples, bundle, &template(), k))
        .collect();
    let rel = |x: &[f64], y: &[f64]| {
        let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        x.iter().zip(y).fold(0.0_f64, |m, (p, q)| m.max((p - q).abs())) / scale
    };
    for (got, s) in lanes_out.iter().zip(&spans) {
        let (r, p, cov, jac) = dense(&samples, s, &template());
        let errors = [
            rel(got.delta_rotation.as_slice(), r.as_slice()),
            rel(got.delta_position.as_slice(), p.as_slice()),
            rel(got.covariance().as_slice(), cov.as_slice()),
            rel(got.bias_jacobian().as_slice(), jac.as_slice()),
        ];
        assert!(errors.iter().all(|&e| e < 1e-12), "{} intervals: {errors:?}", s.steps);
    }
}
