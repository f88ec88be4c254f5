//! Memory stays bounded with stream length (issue 9): for every streaming API, the resident set
//! after `long_steps()` more samples (10^7 in `make stability`) is within a small slack of the
//! resident set after a warm-up. One test, so that no other test allocates in this process
//! meanwhile; the streams run one after another and each is measured on its own.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

mod stability_common;

use imukit::attitude;
use imukit::filters::{Filter, Law, Madgwick, Mahony, Options, State};
use imukit::imu::{Bias, NavState, Noise};
use imukit::preint::{self, Preintegrator};
use imukit::propagate::{self, Covariance, Outputs};
use imukit::strapdown;
use nalgebra::{UnitQuaternion, Vector3};
use stability_common::{in_chunks, long_steps, timed, Chunk, CHUNK_STEPS};

/// Growth allowed between the two measurements [KiB]: allocator and page-granularity noise (16
/// KiB at most measured), below what keeping 8 bytes per sample costs at the shortest length
/// (10^5 samples: 781 KiB; the control at the end checks it is seen).
const SLACK_KIB: i64 = 256;

const NOISE: Noise = Noise {
    gyro_density: 1.7e-4,
    accel_density: 2e-3,
    gyro_random_walk: 1.9e-5,
    accel_random_walk: 3e-3,
};

/// Resident set size [KiB] (`VmRSS` of /proc/self/status, the second field of statm in KiB).
fn rss_kib() -> i64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmRSS:")).unwrap();
    line.split_whitespace().nth(1).unwrap().parse().unwrap()
}

/// [`growth`] of streaming `law`'s filter over 9D samples.
fn filter_growth<L: Law>(label: &'static str, law: L) -> (&'static str, i64) {
    let chunk = Chunk::new();
    let filter = Filter::new(law, Options::default()).unwrap();
    let mut state = State::default();
    let mag = Vector3::new(0.2, 0.4, -0.3);
    let grown = growth(label, |m| {
        let s = chunk.samples(m);
        for k in 0..m {
            filter
                .update(&mut state, &s.gyro_at(k), &s.accel_at(k), Some(&mag), 1e-3)
                .unwrap();
        }
    });
    (label, grown)
}

/// Runs `feed(intervals)` for a warm-up chunk, then for `long_steps()` more intervals; returns the
/// growth of the resident set over the second part [KiB].
fn growth(label: &str, mut feed: impl FnMut(usize)) -> i64 {
    feed(CHUNK_STEPS);
    let before = rss_kib();
    let steps = long_steps();
    timed(label, steps, || in_chunks(steps, &mut feed));
    let after = rss_kib();
    println!("{label}: RSS {before} KiB -> {after} KiB ({:+} KiB)", after - before);
    after - before
}

#[test]
fn streaming_apis_do_not_grow_memory() {
    let chunk = Chunk::new();
    let mut results = Vec::new();

    for (label, p) in [
        (
            "preint euler+walk",
            Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE).with_bias_walk(),
        ),
        (
            "preint euler batch",
            Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE),
        ),
        (
            "preint midpoint",
            Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE).with_scheme(preint::Scheme::Midpoint),
        ),
    ] {
        let mut p = p;
        // Each batch continues the last on one clock (the chunk ends with its first sample's
        // readings), as the continuity check demands of consecutive batches.
        let mut start = 0.0;
        results.push((
            label,
            growth(label, |m| {
                let s = chunk.samples(m);
                let end = start + (s.t()[m] - s.t()[0]);
                p.integrate_samples_at(&s, None, [start, end]).unwrap();
                start = end;
            }),
        ));
    }

    // Sample by sample, as a driver loop calls it.
    let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE).with_bias_walk();
    results.push((
        "preint integrate_measurement",
        growth("preint integrate_measurement", |m| {
            let s = chunk.samples(m);
            for k in 0..m {
                p.integrate_measurement(&s.accel_at(k), &s.gyro_at(k), s.t()[k + 1] - s.t()[k]);
            }
        }),
    ));

    results.push(filter_growth("mahony update 9D", Mahony::default()));
    results.push(filter_growth("madgwick update 9D", Madgwick::default()));

    let mut q = UnitQuaternion::identity();
    let options = attitude::Options::default();
    results.push((
        "attitude integrate",
        growth("attitude integrate", |m| {
            let s = chunk.samples(m);
            q = attitude::integrate(s.t(), s.gyro(), &q, &options, None).unwrap();
        }),
    ));

    let mut x = NavState {
        position: Vector3::zeros(),
        velocity: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
    };
    let mut cov = Covariance::zeros();
    let mut store = vec![[0.0; 225]; 2];
    results.push((
        "strapdown propagate",
        growth("strapdown propagate", |m| {
            let outputs = Outputs {
                states: None,
                covariances: &mut store,
                every: m,
            };
            let options = strapdown::Options::default();
            (x, cov) =
                propagate::propagate(&chunk.samples(m), &x, &cov, &Bias::default(), &NOISE, &options, outputs).unwrap();
        }),
    ));

    let grown: Vec<_> = results.iter().filter(|(_, g)| *g > SLACK_KIB).collect();
    assert!(
        grown.is_empty(),
        "resident set grew by more than {SLACK_KIB} KiB: {grown:?}"
    );
    assert_eq!(results.len(), 8);

    // Control: the measurement sees a stream that keeps 8 bytes per sample (≥ 781 KiB over the
    // shortest run, 10^5 samples).
    let mut kept: Vec<f64> = Vec::new();
    let leaked = growth("control: 8 bytes kept per sample", |m| kept.extend(&chunk.t[..m]));
    assert!(leaked > SLACK_KIB, "the control grew by only {leaked} KiB");
    assert_eq!(kept.len(), CHUNK_STEPS + long_steps());
}
