//! Tests of `imukit::allan`: exact agreement with the phase definition on integer data (where
//! every sum is exact), accuracy on long integer random walks against an i128 reference,
//! invariance to a constant offset, thread-count independence, the τ grid, and every error.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(missing_docs)]

use imukit::allan::{allan_variance, octave_clusters, term_count, Estimator, MAX_ABS_SAMPLE};
use imukit::Error;

/// xorshift64*: deterministic inputs without a dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Integer in `[-k, k]`.
    fn int(&mut self, k: i64) -> i64 {
        (self.next() >> 11) as i64 % (2 * k + 1) - k
    }
}

/// The textbook definition on exact integers: phase `x_j = Σ_{i<j} y_i` (τ0 = 1), second
/// differences at stride 1 (overlapping) or m (non-overlapping), `Σ v² / (2 m² n)` in i128.
fn reference(y: &[i64], columns: usize, c: usize, m: usize, estimator: Estimator) -> (f64, usize) {
    let n = y.len() / columns;
    let mut x = vec![0i128; n + 1];
    for j in 0..n {
        x[j + 1] = x[j] + i128::from(y[j * columns + c]);
    }
    let stride = match estimator {
        Estimator::Overlapping => 1,
        Estimator::NonOverlapping => m,
    };
    let (mut sum, mut terms) = (0i128, 0usize);
    let mut k = 0;
    while k + 2 * m <= n {
        let v = x[k + 2 * m] - 2 * x[k + m] + x[k];
        sum += v * v;
        terms += 1;
        k += stride;
    }
    (sum as f64 / (2.0 * (m * m) as f64 * terms as f64), terms)
}

fn as_f64(y: &[i64]) -> Vec<f64> {
    y.iter().map(|&v| v as f64).collect()
}

#[test]
fn equals_the_phase_definition_on_integer_data() {
    let mut rng = Rng(7);
    for columns in 1..=5 {
        let n = 97;
        let y: Vec<i64> = (0..n * columns).map(|_| rng.int(50)).collect();
        let clusters = [1, 2, 3, 5, 8, 13, 24, 31, 48];
        for estimator in [Estimator::Overlapping, Estimator::NonOverlapping] {
            let a = allan_variance(&as_f64(&y), columns, 1.0, &clusters, estimator).unwrap();
            assert_eq!(a.columns, columns);
            for (i, &m) in clusters.iter().enumerate() {
                for c in 0..columns {
                    let (want, terms) = reference(&y, columns, c, m, estimator);
                    assert_eq!(a.terms[i], terms, "{estimator:?} m = {m}");
                    let got = a.variance[i * columns + c];
                    assert!(
                        (got - want).abs() <= 1e-15 * want,
                        "{estimator:?} m={m} c={c}: {got} vs {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn long_random_walk_with_offset_matches_exact_reference() {
    // A random walk of integers with a large offset: its phase reaches 2e14 (ulp 0.03) while the
    // m = 1 differences are ~1e3, so the phase formula in f64 would keep ~5 digits; the sliding
    // TwoSum keeps all of them.
    let mut rng = Rng(11);
    let n = 200_000;
    let mut level = 0i64;
    let y: Vec<i64> = (0..n)
        .map(|_| {
            level += rng.int(1000);
            1_000_000_000 + level + rng.int(30)
        })
        .collect();
    let clusters = octave_clusters(n);
    for estimator in [Estimator::Overlapping, Estimator::NonOverlapping] {
        let a = allan_variance(&as_f64(&y), 1, 200.0, &clusters, estimator).unwrap();
        for (i, &m) in clusters.iter().enumerate() {
            let (want, _) = reference(&y, 1, 0, m, estimator);
            let rel = (a.variance[i] - want).abs() / want;
            assert!(rel < 1e-14, "{estimator:?} m = {m}: relative error {rel:e}");
        }
    }
}

#[test]
fn taus_and_terms() {
    let y = vec![0.5; 40];
    let a = allan_variance(&y, 2, 50.0, &[4, 1, 10], Estimator::Overlapping).unwrap();
    assert_eq!(a.taus, vec![4.0 / 50.0, 1.0 / 50.0, 10.0 / 50.0]);
    assert_eq!(a.terms, vec![13, 19, 1]);
    assert_eq!(a.variance, vec![0.0; 6]);
    let b = allan_variance(&y, 2, 50.0, &[4, 1, 10], Estimator::NonOverlapping).unwrap();
    assert_eq!(b.terms, vec![4, 19, 1]);
    assert_eq!(term_count(20, 10, Estimator::Overlapping), 1);
    assert_eq!(term_count(20, 11, Estimator::Overlapping), 0);
    assert_eq!(term_count(20, 0, Estimator::NonOverlapping), 0);
    assert_eq!(term_count(21, 7, Estimator::NonOverlapping), 2);
}

#[test]
fn octave_grid_stops_at_a_quarter_of_the_record() {
    assert!(octave_clusters(3).is_empty());
    assert_eq!(octave_clusters(4), vec![1]);
    assert_eq!(octave_clusters(31), vec![1, 2, 4]);
    assert_eq!(octave_clusters(32), vec![1, 2, 4, 8]);
    assert_eq!(*octave_clusters(2_160_000).last().unwrap(), 524_288);
}

#[test]
fn constant_offset_does_not_change_the_result() {
    let mut rng = Rng(3);
    let y: Vec<f64> = (0..50_000).map(|_| rng.int(1 << 20) as f64 * 1e-8).collect();
    let shifted: Vec<f64> = y.iter().map(|v| v + 9.81).collect();
    let clusters = octave_clusters(y.len());
    let a = allan_variance(&y, 1, 100.0, &clusters, Estimator::Overlapping).unwrap();
    let b = allan_variance(&shifted, 1, 100.0, &clusters, Estimator::Overlapping).unwrap();
    for (p, q) in a.variance.iter().zip(&b.variance) {
        // Adding 9.81 rounds each sample (to 2e-15 absolute): that, not the estimator, is the limit.
        assert!((p - q).abs() <= 1e-9 * p, "{p} vs {q}");
        assert!(*p > 0.0);
    }
}

#[test]
fn white_noise_gives_sigma_squared_over_m() {
    // Uniform integers in [-k, k] have variance k(k+1)/3; AVAR(m) = σ²/m in expectation with a
    // relative standard error ≈ sqrt(2 / edf), edf ≈ 1.5 N / m for m ≫ 1 (well under 5% here).
    let mut rng = Rng(5);
    let (n, k) = (400_000, 100);
    let y: Vec<f64> = (0..n).map(|_| rng.int(k) as f64).collect();
    let sigma2 = (k * (k + 1)) as f64 / 3.0;
    let clusters = [1, 4, 16, 64];
    let a = allan_variance(&y, 1, 1.0, &clusters, Estimator::Overlapping).unwrap();
    for (i, &m) in clusters.iter().enumerate() {
        let ratio = a.variance[i] * m as f64 / sigma2;
        assert!((ratio - 1.0).abs() < 0.05, "m = {m}: ratio {ratio}");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut rng = Rng(9);
    let y: Vec<f64> = (0..3 * 20_000).map(|_| rng.int(1 << 30) as f64 * 1.37e-7).collect();
    let clusters = octave_clusters(20_000);
    let run = || allan_variance(&y, 3, 200.0, &clusters, Estimator::Overlapping).unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(run);
    let four = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap()
        .install(run);
    assert_eq!(one, four);
}

fn parameter_name(e: Error) -> &'static str {
    match e {
        Error::Parameter { name, .. } => name,
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

#[test]
fn errors_name_the_problem() {
    let y = vec![0.0; 30];
    let ov = Estimator::Overlapping;
    for rate in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(
            parameter_name(allan_variance(&y, 1, rate, &[1], ov).unwrap_err()),
            "rate"
        );
    }
    assert_eq!(
        parameter_name(allan_variance(&[1.0], 1, 1.0, &[1], ov).unwrap_err()),
        "y"
    );
    assert_eq!(parameter_name(allan_variance(&[], 3, 1.0, &[1], ov).unwrap_err()), "y");
    assert_eq!(
        parameter_name(allan_variance(&y, 1, 1.0, &[], ov).unwrap_err()),
        "clusters"
    );
    assert_eq!(
        parameter_name(allan_variance(&y, 1, 1.0, &[0], ov).unwrap_err()),
        "clusters"
    );
    let e = allan_variance(&y, 1, 1.0, &[1, 16], Estimator::NonOverlapping).unwrap_err();
    assert!(e.to_string().contains("m = 16 with N = 30"), "{e}");
    assert_eq!(
        allan_variance(&y, 4, 1.0, &[1], ov).unwrap_err(),
        Error::RowLength { len: 30, row: 4 }
    );
    assert_eq!(
        allan_variance(&y, 0, 1.0, &[1], ov).unwrap_err(),
        Error::RowLength { len: 30, row: 0 }
    );
    let mut bad = vec![0.0; 3 * 100_000];
    bad[3 * 70_123 + 2] = f64::NAN;
    bad[3 * 80_000] = f64::INFINITY;
    assert_eq!(
        allan_variance(&bad, 3, 1.0, &[1], ov).unwrap_err(),
        Error::NonFinite { index: 70_123 }
    );
    let mut big = vec![1.0; 10];
    big[4] = -2.0 * MAX_ABS_SAMPLE;
    assert_eq!(
        allan_variance(&big, 1, 1.0, &[1], ov).unwrap_err(),
        Error::Overflow { index: 4 }
    );
    // The largest accepted magnitude still gives a finite result.
    let edge: Vec<f64> = (0..64)
        .map(|i| if i % 2 == 0 { MAX_ABS_SAMPLE } else { -MAX_ABS_SAMPLE })
        .collect();
    let a = allan_variance(&edge, 1, 1.0, &octave_clusters(64), ov).unwrap();
    assert!(a.variance.iter().all(|v| v.is_finite()));
    let want = 2.0 * MAX_ABS_SAMPLE * MAX_ABS_SAMPLE;
    assert!((a.variance[0] - want).abs() <= 1e-15 * want);
}
