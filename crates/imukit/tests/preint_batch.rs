//! Batch preintegration: long batches run as parallel chunks merged in order; they equal
//! sample-by-sample streaming to rounding and do not depend on the thread count. Midpoint batches
//! continue from the last sample or are refused.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::Samples;
use imukit::preint::{Preintegrator, Scheme, CHUNK};
use imukit_testing::preint::NOISE;
use nalgebra::Vector3;

struct Stream {
    t: Vec<f64>,
    gyro: Vec<f64>,
    accel: Vec<f64>,
}

/// `n` samples of a slowly turning, accelerating body at 200 Hz with jittered stamps.
fn stream(n: usize) -> Stream {
    let t: Vec<f64> = (0..n)
        .map(|k| k as f64 * 0.005 + 1e-4 * (k as f64 * 0.37).sin())
        .collect();
    let gyro = t
        .iter()
        .flat_map(|s| [0.3 * (1.1 * s).sin(), 0.2 * (0.7 * s).cos(), 0.5 * (1.3 * s).sin()])
        .collect();
    let accel = t
        .iter()
        .flat_map(|s| [0.5 * (0.9 * s).sin(), 0.4 * (0.3 * s).cos(), 9.81])
        .collect();
    Stream { t, gyro, accel }
}

impl Stream {
    fn samples(&self) -> Samples<'_> {
        Samples::new(&self.t, self.gyro.as_chunks().0, self.accel.as_chunks().0).unwrap()
    }
}

fn fresh(scheme: Scheme) -> Preintegrator {
    Preintegrator::new(Vector3::new(0.01, -0.02, 0.0), Vector3::new(0.1, 0.0, -0.1), NOISE).with_scheme(scheme)
}

/// Sample by sample: euler holds sample k over `[t_k, t_k+1)`; midpoint takes sample 0, then each
/// sample with the interval it ends.
fn streamed(scheme: Scheme, data: &Stream) -> Preintegrator {
    let s = data.samples();
    let mut p = fresh(scheme);
    for k in 0..data.t.len() - 1 {
        match scheme {
            Scheme::Euler => p.integrate_measurement(&s.accel_at(k), &s.gyro_at(k), data.t[k + 1] - data.t[k]),
            Scheme::Midpoint => {
                if k == 0 {
                    p.integrate_measurement(&s.accel_at(0), &s.gyro_at(0), 0.0);
                }
                p.integrate_measurement(&s.accel_at(k + 1), &s.gyro_at(k + 1), data.t[k + 1] - data.t[k]);
            }
        }
    }
    p
}

#[test]
fn parallel_chunks_equal_streaming_and_ignore_the_thread_count() {
    // Midpoint chunks share a sample, which the merge must give the variance of the interval
    // before it (the jittered stamps make the two intervals differ): without that the covariance
    // is 1e-5 relative off.
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        chunks_equal_streaming(scheme);
    }
}

fn chunks_equal_streaming(scheme: Scheme) {
    let data = stream(2 * CHUNK + 1235);
    let s = data.samples();
    let streamed = streamed(scheme, &data);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut p = fresh(scheme);
        pool.install(|| p.integrate_samples(&s)).unwrap();
        p
    };
    let batch = on(2);
    assert_eq!(batch, on(1));
    let rel = |a: f64, b: f64| a / b;
    let dp = (batch.delta_position - streamed.delta_position).amax();
    assert!(
        rel(dp, streamed.delta_position.amax()) < 1e-12,
        "{scheme:?}: Δp off by {dp:e}"
    );
    assert!((batch.delta_rotation - streamed.delta_rotation).amax() < 1e-12);
    let dc = (batch.covariance() - streamed.covariance()).amax();
    assert!(
        rel(dc, streamed.covariance().amax()) < 1e-12,
        "{scheme:?}: covariance off by {dc:e}"
    );
    let dj = (batch.bias_jacobian() - streamed.bias_jacobian()).amax();
    assert!(
        rel(dj, streamed.bias_jacobian().amax()) < 1e-12,
        "{scheme:?}: bias Jacobian off by {dj:e}"
    );
    assert!((batch.delta_t - streamed.delta_t).abs() < 1e-9);
    // it was merged: not bit for bit the streamed result
    assert_ne!(batch.delta_position, streamed.delta_position);
}

#[test]
fn short_and_combined_batches_stream_bit_for_bit() {
    let data = stream(500);
    let s = data.samples();
    for combined in [false, true] {
        let make = || {
            let p = fresh(Scheme::Euler);
            if combined {
                p.with_bias_walk()
            } else {
                p
            }
        };
        let mut streamed = make();
        for k in 0..data.t.len() - 1 {
            streamed.integrate_measurement(&s.accel_at(k), &s.gyro_at(k), data.t[k + 1] - data.t[k]);
        }
        let mut batch = make();
        batch.integrate_samples(&s).unwrap();
        // Everything but the ends the batch records for the continuity rule.
        let math = |p: &Preintegrator| {
            (
                p.delta_rotation,
                p.delta_velocity,
                p.delta_position,
                p.delta_t,
                p.covariance(),
                p.bias_jacobian(),
                p.covariance_combined(),
            )
        };
        assert_eq!(math(&batch), math(&streamed));
    }
}

#[test]
fn batches_of_both_schemes_continue_from_the_last_sample() {
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        continue_from_the_last_sample(scheme);
    }
}

fn continue_from_the_last_sample(scheme: Scheme) {
    let data = stream(300);
    let s = data.samples();
    let mut whole = fresh(scheme);
    whole.integrate_samples(&s).unwrap();
    let part = |lo: usize, hi: usize| {
        Samples::new(
            &data.t[lo..hi],
            data.gyro[3 * lo..3 * hi].as_chunks().0,
            data.accel[3 * lo..3 * hi].as_chunks().0,
        )
        .unwrap()
    };
    let mut two = fresh(scheme);
    two.integrate_samples(&part(0, 101)).unwrap();
    two.integrate_samples(&part(100, 300)).unwrap();
    assert_eq!(two, whole);
    // Disjoint (the euler scheme would drop the interval 99 → 100), repeated, out of order and
    // gapped continuations are refused, with nothing added; so are merges of them.
    let mut first = fresh(scheme);
    first.integrate_samples(&part(0, 100)).unwrap();
    for (lo, hi) in [(100, 300), (0, 100), (0, 50), (150, 300)] {
        let before = first.clone();
        let e = first.integrate_samples(&part(lo, hi)).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("samples must be a continuation starting with the preintegration's last sample"),
            "{e}"
        );
        assert_eq!(first, before); // nothing was added
        let mut next = fresh(scheme);
        next.integrate_samples(&part(lo, hi)).unwrap();
        assert!(first
            .merge(&next)
            .unwrap_err()
            .to_string()
            .starts_with("next must be a continuation"));
    }
    let mut next = fresh(scheme);
    next.integrate_samples(&part(99, 300)).unwrap();
    let merged = first.merge(&next).unwrap();
    assert!((merged.delta_position - whole.delta_position).amax() < 1e-12);
    // The shared sample 99 keeps the variance of its first interval, 98 → 99, in the merge
    // (`next` gave it that of 99 → 100; the stamps are jittered).
    let dc = (merged.covariance() - whole.covariance()).amax();
    assert!(
        dc < 1e-12 * whole.covariance().amax(),
        "{scheme:?}: covariance off by {dc:e}"
    );
    let mut bad = stream(300);
    bad.accel[3 * 200 + 1] = f64::INFINITY;
    let mut p = fresh(scheme);
    assert!(p.integrate_samples(&bad.samples()).is_err());
    assert_eq!(p, fresh(scheme));
}
