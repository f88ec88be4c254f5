//! Keyframe windows: each window equals a preintegration of the sample stream with the boundary
//! points inserted (held sample in euler, linear interpolation in midpoint), merged windows
//! equal one preintegration of that stream, and the result does not depend on the thread count.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::imu::Samples;
use imukit::preint::{preintegrate_windows, Preintegrator, Scheme};
use imukit_testing::preint::{samples, H, NOISE};
use nalgebra::Vector3;

struct Stream {
    t: Vec<f64>,
    gyro: Vec<f64>,
    accel: Vec<f64>,
}

impl Stream {
    fn new() -> Self {
        let data = samples();
        Self {
            t: (0..data.len()).map(|k| 0.3 + k as f64 * H).collect(),
            gyro: data.iter().flat_map(|(_, w)| w.iter().copied()).collect(),
            accel: data.iter().flat_map(|(a, _)| a.iter().copied()).collect(),
        }
    }
    fn samples(&self) -> Samples<'_> {
        Samples::new(&self.t, self.gyro.as_chunks().0, self.accel.as_chunks().0).unwrap()
    }
    fn at(&self, k: usize) -> (f64, Vector3<f64>, Vector3<f64>) {
        let s = self.samples();
        (self.t[k], s.accel_at(k), s.gyro_at(k))
    }
}

/// The stream as points `(t, accel, gyro)` with `b` inserted by the scheme's signal model.
fn with_boundaries(stream: &Stream, b: &[f64], scheme: Scheme) -> Vec<(f64, Vector3<f64>, Vector3<f64>)> {
    let mut points: Vec<_> = (0..stream.t.len()).map(|k| stream.at(k)).collect();
    for &x in b {
        if stream.t.contains(&x) {
            continue;
        }
        let k = stream.t.iter().rposition(|&t| t < x).unwrap();
        let ((t0, a0, w0), (t1, a1, w1)) = (stream.at(k), stream.at(k + 1));
        let s = (x - t0) / (t1 - t0);
        let point = match scheme {
            Scheme::Euler => (x, a0, w0),
            Scheme::Midpoint => (x, a0 + (a1 - a0) * s, w0 + (w1 - w0) * s),
        };
        points.push(point);
    }
    points.sort_by(|p, q| p.0.total_cmp(&q.0));
    points
}

fn template(scheme: Scheme) -> Preintegrator {
    Preintegrator::new(Vector3::new(0.01, 0.0, -0.02), Vector3::new(0.1, -0.1, 0.05), NOISE).with_scheme(scheme)
}

/// One preintegration of `points` between times lo and hi.
fn reference(points: &[(f64, Vector3<f64>, Vector3<f64>)], lo: f64, hi: f64, scheme: Scheme) -> Preintegrator {
    let mut p = template(scheme);
    let inside: Vec<_> = points.iter().filter(|(t, _, _)| *t >= lo && *t <= hi).collect();
    if scheme == Scheme::Midpoint {
        p.integrate_measurement(&inside[0].1, &inside[0].2, 0.0);
    }
    for pair in inside.windows(2) {
        let ((t0, a0, w0), (t1, a1, w1)) = (pair[0], pair[1]);
        match scheme {
            Scheme::Euler => p.integrate_measurement(a0, w0, t1 - t0),
            Scheme::Midpoint => p.integrate_measurement(a1, w1, t1 - t0),
        }
    }
    p
}

#[test]
fn windows_equal_preintegrations_of_the_stream_with_the_boundaries_inserted() {
    let stream = Stream::new();
    // on a sample, between samples, on the first and last samples
    let b = [
        stream.t[0],
        0.3 + 10.4 * H,
        stream.t[50],
        0.3 + 133.77 * H,
        stream.t[199],
    ];
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let template = template(scheme);
        let windows = preintegrate_windows(&stream.samples(), &b, &template).unwrap();
        assert_eq!(windows.len(), b.len() - 1);
        let points = with_boundaries(&stream, &b, scheme);
        for (m, w) in windows.iter().enumerate() {
            let expected = reference(&points, b[m], b[m + 1], scheme);
            assert!((w.delta_t - (b[m + 1] - b[m])).abs() < 1e-14);
            let gap = (w.delta_position - expected.delta_position).amax();
            assert!(
                gap < 1e-15,
                "{scheme:?} window {m}: {gap:e}, dt {} vs {}",
                w.delta_t,
                expected.delta_t
            );
            assert!((w.covariance() - expected.covariance()).amax() <= 1e-15 * expected.covariance().amax());
        }
        // the windows tile the stream: merged, they are one preintegration of it
        let merged = windows[1..]
            .iter()
            .fold(windows[0].clone(), |acc, w| acc.merge(w).unwrap());
        let whole = reference(&points, b[0], b[4], scheme);
        assert!((merged.delta_position - whole.delta_position).amax() < 1e-13);
        let err = (merged.covariance() - whole.covariance()).amax() / whole.covariance().amax();
        // Midpoint: each window gives an inserted boundary sample the white-noise variance σ²/h of
        // its own interval beside it (unequal on both sides); the merge keeps the earlier window's,
        // the interval before it, as the whole stream does.
        assert!(err < 1e-12, "{scheme:?} merged covariance off by {err:e}");
        // with boundaries on samples the midpoint windows tile exactly as well
        let on_samples = [stream.t[0], stream.t[37], stream.t[120], stream.t[199]];
        let windows = preintegrate_windows(&stream.samples(), &on_samples, &template).unwrap();
        let merged = windows[1..]
            .iter()
            .fold(windows[0].clone(), |acc, w| acc.merge(w).unwrap());
        let whole = reference(&with_boundaries(&stream, &[], scheme), b[0], b[4], scheme);
        let err = (merged.covariance() - whole.covariance()).amax() / whole.covariance().amax();
        assert!(err < 1e-12, "{scheme:?} merged covariance off by {err:e}");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let stream = Stream::new();
    let b: Vec<f64> = (0..40).map(|m| 0.3 + m as f64 * 4.9 * H).collect();
    let template = template(Scheme::Midpoint);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| preintegrate_windows(&stream.samples(), &b, &template).unwrap())
    };
    assert_eq!(on(1), on(2));
}

#[test]
fn bad_boundaries_are_refused_with_their_name() {
    let stream = Stream::new();
    let template = template(Scheme::Euler);
    let last = *stream.t.last().unwrap();
    for b in [
        vec![0.4],
        vec![0.4, 0.4],
        vec![0.5, 0.4],
        vec![0.2, 0.4],
        vec![0.4, last + 1e-9],
        vec![0.4, f64::NAN],
    ] {
        let e = preintegrate_windows(&stream.samples(), &b, &template).unwrap_err();
        assert!(e.to_string().starts_with("boundaries must be"), "{b:?}: {e}");
    }
    let mut bad = Stream::new();
    bad.gyro[31] = f64::NAN;
    let e = preintegrate_windows(&bad.samples(), &[0.3, 0.5], &template).unwrap_err();
    assert!(e.to_string().contains("gyro"), "{e}");
}

#[test]
fn the_record_kernel_writes_the_windows_row_major_bit_for_bit() {
    use imukit::preint::{preintegrate_windows_into, WindowsOut};
    let stream = Stream::new();
    let s = stream.samples();
    let b = [
        stream.t[3] + 0.4 * H,
        stream.t[40],
        stream.t[90] + 0.7 * H,
        stream.t[150],
    ];
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let t = template(scheme).with_bias_walk();
        let states = preintegrate_windows(&s, &b, &t).unwrap();
        let m = b.len() - 1;
        let (mut r, mut v, mut p, mut dt) = (
            vec![[[0.0; 3]; 3]; m],
            vec![[0.0; 3]; m],
            vec![[0.0; 3]; m],
            vec![0.0; m],
        );
        let (mut cov, mut jac, mut c15) = (vec![[[0.0; 9]; 9]; m], vec![[[0.0; 6]; 9]; m], vec![[[0.0; 15]; 15]; m]);
        let out = WindowsOut {
            delta_rotation: &mut r,
            delta_velocity: &mut v,
            delta_position: &mut p,
            delta_t: &mut dt,
            covariance: &mut cov,
            bias_jacobian: &mut jac,
            covariance_combined: Some(&mut c15),
        };
        preintegrate_windows_into(&s, None, &b, &t, out).unwrap();
        for (k, w) in states.iter().enumerate() {
            assert_eq!(r[k], rows_of(&w.delta_rotation));
            assert_eq!(v[k], <[f64; 3]>::from(w.delta_velocity));
            assert_eq!(p[k], <[f64; 3]>::from(w.delta_position));
            assert_eq!(dt[k], w.delta_t);
            assert_eq!(cov[k], rows_of(&w.covariance()));
            assert_eq!(jac[k], rows_of(&w.bias_jacobian()));
            assert_eq!(c15[k], rows_of(&w.covariance_combined().unwrap()));
        }
        // A buffer of the wrong length is refused, not indexed past.
        let mut short = vec![0.0; m - 1];
        let out = WindowsOut {
            delta_rotation: &mut r,
            delta_velocity: &mut v,
            delta_position: &mut p,
            delta_t: &mut short,
            covariance: &mut cov,
            bias_jacobian: &mut jac,
            covariance_combined: None,
        };
        let err = preintegrate_windows_into(&s, None, &b, &t, out).unwrap_err();
        assert_eq!(
            err,
            imukit::Error::RowCount {
                input: m,
                output: m - 1
            }
        );
    }
}

/// A matrix as its rows.
fn rows_of<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> [[f64; C]; R] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
}
