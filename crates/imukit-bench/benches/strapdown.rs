//! Strapdown throughput on 10^6 samples: every state stored; and with the 15×15 error-state
//! covariance propagated every sample and stored every 100 (criterion reports elements/s).
#![allow(clippy::unwrap_used)] // a benchmark on fixed, valid inputs

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use imukit::imu::{Bias, NavState, Noise, Samples};
use imukit::propagate::{covariance_count, propagate, Covariance, Outputs};
use imukit::strapdown::{integrate, Options, Scheme, StatesOut};
use nalgebra::{UnitQuaternion, Vector3};
use std::hint::black_box;

const N: usize = 1_000_000;

fn inputs() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..N).map(|k| k as f64 * 0.005).collect();
    let gyro = t
        .iter()
        .flat_map(|&s| [0.3 * (1.1 * s).sin(), 0.2 * (0.7 * s).cos(), 0.5 * (1.3 * s).sin()])
        .collect();
    let accel = t
        .iter()
        .flat_map(|&s| {
            [
                0.5 * (0.9 * s).sin(),
                0.4 * (0.3 * s).cos(),
                9.81 + 0.2 * (1.7 * s).sin(),
            ]
        })
        .collect();
    (t, gyro, accel)
}

fn strapdown(c: &mut Criterion) {
    let (t, gyro, accel) = inputs();
    let samples = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    let initial = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
    };
    let (mut pv, mut rot) = (vec![0.0; 6 * N], vec![0.0; 4 * N]);
    let mut group = c.benchmark_group("strapdown_1e6");
    group.throughput(Throughput::Elements(N as u64));
    group.sample_size(10);
    for scheme in [Scheme::LieEuler, Scheme::Midpoint, Scheme::Rk4, Scheme::Exp] {
        let options = Options {
            scheme,
            ..Options::default()
        };
        group.bench_with_input(BenchmarkId::new("integrate", scheme.name()), &options, |b, options| {
            b.iter(|| {
                let out = StatesOut {
                    position_velocity: pv.as_chunks_mut().0,
                    rotation: rot.as_chunks_mut().0,
                };
                integrate(black_box(&samples), &initial, &Bias::default(), options, Some(out))
            })
        });
    }
    let noise = Noise {
        gyro_density: 1.7e-4,
        accel_density: 2e-3,
        gyro_random_walk: 1.9e-5,
        accel_random_walk: 3e-3,
    };
    let p0 = Covariance::identity() * 1e-4;
    let mut covariances = vec![[0.0; 225]; covariance_count(N, 100)];
    group.bench_function("propagate_cov_every_100/midpoint", |b| {
        b.iter(|| {
            let outputs = Outputs {
                states: Some(StatesOut {
                    position_velocity: pv.as_chunks_mut().0,
                    rotation: rot.as_chunks_mut().0,
                }),
                covariances: &mut covariances,
                every: 100,
            };
            propagate(
                black_box(&samples),
                &initial,
                &p0,
                &Bias::default(),
                &noise,
                &Options::default(),
                outputs,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, strapdown);
criterion_main!(benches);
