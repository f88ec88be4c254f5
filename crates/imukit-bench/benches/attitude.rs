//! Gyro integration throughput: 10^6 samples, every attitude stored (criterion reports
//! elements/s; ns/sample is its inverse).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use imukit::attitude::{integrate, Options, Representation, Scheme};
use nalgebra::UnitQuaternion;
use std::hint::black_box;

const N: usize = 1_000_000;

fn inputs() -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..N).map(|k| k as f64 * 0.005).collect();
    let gyro: Vec<f64> = (0..N)
        .flat_map(|k| {
            let s = k as f64 * 0.005;
            [0.3 * (1.1 * s).sin(), 0.2 * (0.7 * s).cos(), 0.5 * (1.3 * s).sin()]
        })
        .collect();
    (t, gyro)
}

fn attitude(c: &mut Criterion) {
    let (t, gyro) = inputs();
    let mut out = vec![0.0; 4 * N];
    let mut group = c.benchmark_group("integrate_attitude_1e6");
    group.throughput(Throughput::Elements(N as u64));
    group.sample_size(10);
    let cases = [
        (Scheme::Exp, Representation::Quaternion),
        (Scheme::Magnus, Representation::Quaternion),
        (Scheme::Rk2, Representation::Quaternion),
        (Scheme::Rk4, Representation::Quaternion),
        (Scheme::Magnus, Representation::Matrix),
        (Scheme::Rk4, Representation::Euler),
    ];
    for (scheme, representation) in cases {
        let options = Options {
            scheme,
            representation,
            ..Options::default()
        };
        let id = BenchmarkId::new(scheme.name(), representation.name());
        group.bench_with_input(id, &options, |b, options| {
            b.iter(|| {
                integrate(
                    black_box(&t),
                    black_box(gyro.as_chunks().0),
                    &UnitQuaternion::identity(),
                    options,
                    Some(out.as_chunks_mut().0),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, attitude);
criterion_main!(benches);
