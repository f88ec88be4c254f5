//! Preintegration throughput: 10^6 samples at 200 Hz with the 9×9 covariance and the bias
//! Jacobians (criterion reports elements/s): euler streamed on one core (the figure),
//! euler as a batch (parallel chunks, all cores), euler with the 15×15 bias-walk covariance, and
//! midpoint.
#![allow(clippy::unwrap_used)] // a benchmark on fixed, valid inputs

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imukit::imu::{Noise, Samples};
use imukit::preint::{Preintegrator, Scheme};
use nalgebra::Vector3;
use std::hint::black_box;

const N: usize = 1_000_000;

fn preint(c: &mut Criterion) {
    let samples: Vec<(Vector3<f64>, Vector3<f64>)> = (0..N)
        .map(|k| {
            let s = k as f64 * 0.005;
            (
                Vector3::new(0.5 * (0.9 * s).sin(), 0.4 * (0.3 * s).cos(), 9.81),
                Vector3::new(0.3 * (1.1 * s).sin(), 0.2 * (0.7 * s).cos(), 0.5 * (1.3 * s).sin()),
            )
        })
        .collect();
    let noise = Noise {
        gyro_density: 1.7e-4,
        accel_density: 2e-3,
        gyro_random_walk: 1.9e-5,
        accel_random_walk: 3e-3,
    };
    let mut group = c.benchmark_group("preintegrate_1e6");
    group.throughput(Throughput::Elements(N as u64));
    group.sample_size(10);
    group.bench_function("euler", |b| {
        b.iter(|| {
            let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise);
            for (a, w) in black_box(&samples) {
                p.integrate_measurement(a, w, 0.005);
            }
            p.delta_t
        })
    });
    let t: Vec<f64> = (0..N).map(|k| k as f64 * 0.005).collect();
    let gyro: Vec<f64> = samples.iter().flat_map(|(_, w)| w.iter().copied()).collect();
    let accel: Vec<f64> = samples.iter().flat_map(|(a, _)| a.iter().copied()).collect();
    let batch = Samples::new(&t, gyro.as_chunks().0, accel.as_chunks().0).unwrap();
    for (name, scheme, combined) in [
        ("euler_batch_parallel", Scheme::Euler, false),
        ("euler_combined", Scheme::Euler, true),
        ("midpoint", Scheme::Midpoint, false),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), noise).with_scheme(scheme);
                let mut p = if combined { p.with_bias_walk() } else { p };
                p.integrate_samples(black_box(&batch)).map(|()| p.delta_t)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, preint);
criterion_main!(benches);
