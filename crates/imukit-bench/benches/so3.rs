//! Criterion benchmarks of the SO(3)/quaternion kernels: one element at a time, and the batch
//! entry points (what the Python bindings call) on 10⁶ rows.
//!
//! `cargo bench -p imukit-bench` (full), `cargo bench -p imukit-bench -- --quick` (short), or
//! `cargo bench -p imukit-bench -- --test` (run each once, as a smoke test).
#![allow(missing_docs)] // criterion_group! generates undocumented public functions
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use imukit::{ffi, quat, so3};
use nalgebra::{Quaternion, Vector3};

const BATCH_ROWS: usize = 1_000_000;

/// Rotation vectors spread over all angles in (0, π), deterministic.
fn rotation_vectors(n: usize) -> Vec<f64> {
    let golden = 0.618_033_988_749_894_9;
    (0..n)
        .flat_map(|i| {
            let t = i as f64;
            let z = 2.0 * ((t * golden) % 1.0) - 1.0;
            let az = std::f64::consts::TAU * ((t * golden * golden) % 1.0);
            let r = (1.0 - z * z).sqrt();
            let angle = std::f64::consts::PI * ((t * 0.754_877_666_246_692_8) % 1.0);
            [angle * r * az.cos(), angle * r * az.sin(), angle * z]
        })
        .collect()
}

fn single_element(c: &mut Criterion) {
    let mut group = c.benchmark_group("per_element");
    group.throughput(Throughput::Elements(1));
    let phi = Vector3::new(0.3, -1.1, 0.7);
    let r = so3::exp(&phi);
    let q = Quaternion::new(0.5, -0.1, 0.7, 0.3);
    let p = Quaternion::new(-0.2, 0.9, 0.1, 0.4);
    group.bench_function("so3::exp", |b| b.iter(|| so3::exp(black_box(&phi))));
    group.bench_function("so3::log", |b| b.iter(|| so3::log(black_box(&r))));
    group.bench_function("so3::right_jacobian", |b| {
        b.iter(|| so3::right_jacobian(black_box(&phi)))
    });
    group.bench_function("so3::right_jacobian_inv", |b| {
        b.iter(|| so3::right_jacobian_inv(black_box(&phi)))
    });
    group.bench_function("quat::multiply", |b| {
        b.iter(|| quat::multiply(black_box(&q), black_box(&p)))
    });
    group.bench_function("quat::exp", |b| b.iter(|| quat::exp(black_box(&phi))));
    group.finish();
}

fn batch_kernels(c: &mut Criterion) {
    let mut group = c.benchmark_group("batch");
    group.throughput(Throughput::Elements(BATCH_ROWS as u64));
    group.sample_size(20);
    let vectors = rotation_vectors(BATCH_ROWS);
    let mut matrices = vec![0.0; 9 * BATCH_ROWS];
    ffi::so3_exp(&vectors, &mut matrices).unwrap();
    let mut out3 = vec![0.0; 3 * BATCH_ROWS];
    let mut out9 = vec![0.0; 9 * BATCH_ROWS];
    group.bench_with_input(BenchmarkId::new("so3_exp", BATCH_ROWS), &vectors, |b, input| {
        b.iter(|| ffi::so3_exp(black_box(input), black_box(&mut out9)).unwrap());
    });
    group.bench_with_input(BenchmarkId::new("so3_log", BATCH_ROWS), &matrices, |b, input| {
        b.iter(|| ffi::so3_log(black_box(input), black_box(&mut out3)).unwrap());
    });
    group.finish();
}

criterion_group!(benches, single_element, batch_kernels);
criterion_main!(benches);
