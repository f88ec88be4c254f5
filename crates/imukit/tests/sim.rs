//! Simulator: every closed-form motion's velocity, acceleration and body rate against central
//! differences of its position, velocity and attitude; the sensor model's statistics (white noise,
//! random walk, Gauss–Markov, turn-on bias), its deterministic terms, and reproducibility.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::sim::{evaluate, measure, Motion, SensorModel, Truth, CHUNK};
use imukit::{euler, so3};
use nalgebra::{Matrix3, Rotation3, Vector3};

fn motions() -> Vec<Motion> {
    let r0 = Rotation3::from_euler_angles(0.3, -0.2, 1.1);
    vec![
        Motion::Static {
            position: Vector3::new(1.0, 2.0, 3.0),
            rotation: r0,
        },
        Motion::ConstantTwist {
            position: Vector3::new(1.0, 2.0, 3.0),
            rotation: r0,
            body_velocity: Vector3::new(1.0, -0.5, 0.2),
            body_rate: Vector3::new(0.1, -0.3, 0.5),
        },
        Motion::Helix {
            center: Vector3::new(0.0, 0.0, 1.0),
            radius: 5.0,
            angular_rate: -0.7,
            climb_rate: 0.3,
        },
        Motion::FigureEight {
            center: Vector3::new(0.0, 0.0, 2.0),
            amplitude: Vector3::new(10.0, 5.0, 1.0),
            angular_rate: 0.3,
            roll: 0.3,
            pitch: 0.2,
        },
        Motion::VioEllipse {
            center: Vector3::new(5.0, 5.0, 5.0),
            amplitude: Vector3::new(15.0, 20.0, 1.0),
            angular_rate: std::f64::consts::PI / 10.0,
            height_frequency: 10.0,
            roll: 0.1,
            pitch: 0.2,
        },
    ]
}

#[test]
fn derivatives_match_central_differences() {
    let h = 1e-5;
    for motion in motions() {
        for t in [0.0, 0.7, 3.1, 17.9] {
            let (before, now, after) = (motion.at(t - h), motion.at(t), motion.at(t + h));
            let rel = |a: Vector3<f64>, b: Vector3<f64>| (a - b).norm() / b.norm().max(1.0);
            let v = (after.position - before.position) / (2.0 * h);
            let a = (after.velocity - before.velocity) / (2.0 * h);
            let w = so3::log(&(before.rotation.inverse() * after.rotation)) / (2.0 * h);
            assert!(rel(now.velocity, v) < 1e-8, "{motion:?} velocity at {t}");
            assert!(rel(now.acceleration, a) < 1e-7, "{motion:?} acceleration at {t}");
            assert!(
                rel(now.body_rate, w) < 1e-8,
                "{motion:?} body rate at {t}: {} vs {w}",
                now.body_rate
            );
        }
    }
}

#[test]
fn the_teaching_ellipse_is_the_one_of_the_course() {
    // position (15 cos Kt + 5, 20 sin Kt + 5, sin(10 K t) + 5), Euler (yaw Kt, pitch 0.2 sin t, roll 0.1 cos t)
    let motion = &motions()[4];
    let (t, k) = (2.5_f64, std::f64::consts::PI / 10.0);
    let x = motion.at(t);
    let p = Vector3::new(
        15.0 * (k * t).cos() + 5.0,
        20.0 * (k * t).sin() + 5.0,
        (10.0 * k * t).sin() + 5.0,
    );
    assert!((x.position - p).norm() < 1e-12);
    let r = euler::to_rotation(&Vector3::new(k * t, 0.2 * t.sin(), 0.1 * t.cos()));
    assert!((x.rotation.matrix() - r.matrix()).amax() < 1e-15);
    // specific force at rest-equivalent: Rᵀ(a − g)
    let g = Vector3::new(0.0, 0.0, -9.81);
    assert!((x.specific_force(&g) - r.matrix().transpose() * (x.acceleration - g)).norm() < 1e-12);
}

#[test]
fn evaluate_writes_the_motion_at_every_time() {
    let t: Vec<f64> = (0..10_000).map(|k| k as f64 * 0.01).collect();
    let n = t.len();
    let (mut p, mut v, mut q, mut w, mut a) = (
        vec![0.0; 3 * n],
        vec![0.0; 3 * n],
        vec![0.0; 4 * n],
        vec![0.0; 3 * n],
        vec![0.0; 3 * n],
    );
    let motion = &motions()[3];
    let g = Vector3::new(0.0, 0.0, -9.81);
    let out = Truth {
        position: &mut p,
        velocity: &mut v,
        rotation: &mut q,
        gyro: &mut w,
        accel: &mut a,
    };
    evaluate(motion, &t, &g, out).unwrap();
    for k in [0, 4095, 4096, 9999] {
        let x = motion.at(t[k]);
        assert_eq!(&p[3 * k..3 * k + 3], x.position.as_slice());
        assert_eq!(&w[3 * k..3 * k + 3], x.body_rate.as_slice());
        assert_eq!(&a[3 * k..3 * k + 3], x.specific_force(&g).as_slice());
        let quat = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[4 * k + 3],
            q[4 * k],
            q[4 * k + 1],
            q[4 * k + 2],
        ));
        assert!((quat.to_rotation_matrix().matrix() - x.rotation.matrix()).amax() < 1e-15);
    }
}

fn run(model: &SensorModel, n: usize, h: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * h).collect();
    let ideal = vec![0.0; 3 * n];
    let (mut out, mut bias) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    measure(&t, &ideal, model, seed, 0, &mut out, &mut bias).unwrap();
    (out, bias)
}

#[test]
fn white_noise_has_sigma_over_root_dt() {
    let (h, density) = (0.005, 2e-3);
    let model = SensorModel {
        density,
        ..SensorModel::default()
    };
    let (out, bias) = run(&model, 1_000_000, h, 42);
    assert!(bias.iter().all(|&b| b == 0.0));
    let expected = density / h.sqrt();
    for axis in 0..3 {
        let x: Vec<f64> = out.iter().skip(axis).step_by(3).copied().collect();
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let sd = (x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / x.len() as f64).sqrt();
        assert!((sd / expected - 1.0).abs() < 0.02, "axis {axis}: {sd} vs {expected}");
        assert!(mean.abs() < 5.0 * expected / 1000.0, "axis {axis} mean {mean}");
    }
}

#[test]
fn bias_random_walk_variance_grows_as_sigma_squared_t() {
    let (h, walk, n, runs) = (0.01, 3e-3, 400, 1000);
    let model = SensorModel {
        random_walk: walk,
        ..SensorModel::default()
    };
    let mut sum_sq = vec![0.0; n];
    for seed in 0..runs {
        let (out, bias) = run(&model, n, h, seed);
        assert_eq!(out, bias); // no white noise: the reading is the bias
        for k in 0..n {
            sum_sq[k] += (0..3).map(|a| bias[3 * k + a].powi(2)).sum::<f64>();
        }
    }
    // pooled over 3 axes × 1000 runs: relative standard error √(2/3000) = 2.6%
    for k in [n / 4, n / 2, n - 1] {
        let var = sum_sq[k] / (3.0 * runs as f64);
        let expected = walk * walk * k as f64 * h;
        assert!((var / expected - 1.0).abs() < 0.05, "k {k}: {var} vs {expected}");
    }
}

#[test]
fn chunks_join_and_the_thread_count_does_not_matter() {
    let model = SensorModel {
        density: 1e-3,
        random_walk: 1e-2,
        gauss_markov_sigma: 0.05,
        gauss_markov_tau: 2.0,
        turn_on_sigma: 0.1,
        ..SensorModel::default()
    };
    let n = 2 * CHUNK + 777;
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run(&model, n, 0.005, 7))
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(one, two);
    assert_eq!(run(&model, n, 0.005, 7), one);
    assert_ne!(run(&model, n, 0.005, 8).0, one.0);
    // no jump at the chunk seams: the biggest bias step there is like the others
    let bias = &one.1;
    let step = |k: usize| {
        (0..3)
            .map(|a| (bias[3 * (k + 1) + a] - bias[3 * k + a]).abs())
            .fold(0.0, f64::max)
    };
    // per-step std: walk σ_w √h plus Gauss–Markov σ √(1 − e^{−2h/τ}); a mis-joined chunk jumps by
    // the walk over a whole chunk, σ_w √(CHUNK h) ≈ 0.18
    let per_step = 1e-2 * 0.005f64.sqrt() + 0.05 * (1.0 - (-2.0 * 0.005 / 2.0f64).exp()).sqrt();
    for seam in [CHUNK - 1, 2 * CHUNK - 1] {
        assert!(step(seam) < 6.0 * per_step, "jump {} at the seam {seam}", step(seam));
    }
}

#[test]
fn gauss_markov_is_stationary_with_exponential_correlation() {
    let (h, sigma, tau) = (0.01, 0.2, 0.5);
    let model = SensorModel {
        gauss_markov_sigma: sigma,
        gauss_markov_tau: tau,
        ..SensorModel::default()
    };
    let (_, bias) = run(&model, 2_000_000, h, 3);
    let x: Vec<f64> = bias.iter().step_by(3).copied().collect();
    let var = x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
    assert!((var / (sigma * sigma) - 1.0).abs() < 0.05, "variance {var}");
    for lag in [10usize, 50] {
        let c = x.iter().zip(&x[lag..]).map(|(a, b)| a * b).sum::<f64>() / (x.len() - lag) as f64 / var;
        let expected = (-(lag as f64) * h / tau).exp();
        assert!((c - expected).abs() < 0.03, "lag {lag}: {c} vs {expected}");
    }
}

#[test]
fn turn_on_bias_is_drawn_once_per_run() {
    let model = SensorModel {
        turn_on_sigma: 0.3,
        ..SensorModel::default()
    };
    let firsts: Vec<f64> = (0..2000).map(|seed| run(&model, 10, 0.01, seed).1[0]).collect();
    let sd = (firsts.iter().map(|v| v * v).sum::<f64>() / firsts.len() as f64).sqrt();
    assert!((sd / 0.3 - 1.0).abs() < 0.05, "turn-on sd {sd}");
    let (_, bias) = run(&model, 10, 0.01, 5);
    assert!(bias.chunks(3).all(|b| b == &bias[0..3])); // constant within the run
}

#[test]
fn scale_misalignment_bias_saturation_and_quantisation() {
    let model = SensorModel {
        matrix: Matrix3::new(1.01, 0.002, 0.0, 0.0, 0.99, -0.003, 0.001, 0.0, 1.0),
        bias: Vector3::new(0.1, -0.2, 0.3),
        range: 4.0,
        resolution: 0.01,
        ..SensorModel::default()
    };
    let t = [0.0, 0.01, 0.02];
    let ideal = [1.0, 2.0, 3.0, 10.0, -10.0, 0.0, 0.123, 0.456, -0.789];
    let (mut out, mut bias) = ([0.0; 9], [0.0; 9]);
    measure(&t, &ideal, &model, 1, 1, &mut out, &mut bias).unwrap();
    for k in 0..3 {
        let u = Vector3::from_column_slice(&ideal[3 * k..3 * k + 3]);
        let expected = (model.matrix * u + model.bias).map(|v| (v.clamp(-4.0, 4.0) / 0.01).round() * 0.01);
        assert_eq!(&out[3 * k..3 * k + 3], expected.as_slice());
        assert_eq!(&bias[3 * k..3 * k + 3], model.bias.as_slice());
    }
    assert_eq!(out[3], 4.0); // saturated
    let bad = SensorModel {
        density: -1.0,
        ..SensorModel::default()
    };
    let e = measure(&t, &ideal, &bad, 1, 1, &mut out, &mut bias).unwrap_err();
    assert!(e.to_string().starts_with("density must be finite and ≥ 0"), "{e}");
    let mut nan = ideal;
    nan[4] = f64::NAN;
    let e = measure(&t, &nan, &SensorModel::default(), 1, 1, &mut out, &mut bias).unwrap_err();
    assert!(e.to_string().starts_with("ideal: element 1"), "{e}");
}

#[test]
fn a_motion_beyond_float64_names_its_first_sample_whatever_the_chunk() {
    // z = c t leaves float64 beyond t = 1.797 s, at row 7364 (in the second chunk of evaluate's
    // 4096 rows, while every chunk after it is wholly non-finite).
    let t: Vec<f64> = (0..10_000).map(|k| k as f64 / 4096.0).collect();
    let n = t.len();
    let motion = Motion::Helix {
        center: Vector3::zeros(),
        radius: 1.0,
        angular_rate: 0.5,
        climb_rate: 1e308,
    };
    let mut buffers = [
        vec![0.0; 3 * n],
        vec![0.0; 3 * n],
        vec![0.0; 4 * n],
        vec![0.0; 3 * n],
        vec![0.0; 3 * n],
    ];
    let [p, v, q, w, a] = &mut buffers;
    let out = Truth {
        position: p,
        velocity: v,
        rotation: q,
        gyro: w,
        accel: a,
    };
    let err = evaluate(&motion, &t, &Vector3::new(0.0, 0.0, -9.81), out).unwrap_err();
    assert_eq!(err.argument(), Some("trajectory"));
    let first = t.iter().position(|&x| !(1e308 * x).is_finite()).unwrap();
    assert!(first > 4096 && first < 8192);
    assert_eq!(err.index(), Some(first));
}

#[test]
fn measure_names_the_first_bad_ideal_row_before_any_overflow() {
    let n = 3 * CHUNK;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let mut ideal = vec![0.0; 3 * n];
    ideal[3 * (2 * CHUNK + 5) + 1] = f64::NAN;
    let mut bias = vec![0.0; 3 * n];
    let model = SensorModel {
        density: 1e307,
        ..SensorModel::default()
    };
    // Every reading overflows (σ/√h = 1e308): the non-finite ideal row is still what is named.
    let err = imukit::sim::measure_in_place(&t, &mut ideal.clone(), &model, 1, 0, &mut bias).unwrap_err();
    assert_eq!((err.argument(), err.index()), (Some("ideal"), Some(2 * CHUNK + 5)));
    ideal[3 * (2 * CHUNK + 5) + 1] = 0.0;
    let err = imukit::sim::measure_in_place(&t, &mut ideal, &model, 1, 0, &mut bias).unwrap_err();
    assert_eq!(err.argument(), Some("density"));
    assert!(err.index().is_some_and(|k| k < CHUNK));
}

#[test]
fn measure_names_the_first_bad_stamp_and_ideal_value_whatever_the_block() {
    // The checks search blocks of 65,536 values on every core: the error must still name the
    // first offender, and a non-finite stamp before a repeated one (as `time::check_increasing`).
    let n = 3 * CHUNK;
    let good: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let model = SensorModel::default();
    let run = |t: &[f64], ideal: &[f64]| {
        let (mut values, mut bias) = (ideal.to_vec(), vec![0.0; 3 * n]);
        imukit::sim::measure_in_place(t, &mut values, &model, 1, 0, &mut bias).unwrap_err()
    };
    let zeros = vec![0.0; 3 * n];
    let mut t = good.clone();
    (t[3 * CHUNK - 5], t[CHUNK + 3]) = (t[3 * CHUNK - 6], t[CHUNK + 2]);
    let err = run(&t, &zeros);
    assert_eq!((err.argument(), err.index()), (Some("t"), Some(CHUNK + 3)), "{err}");
    assert!(err.to_string().contains("must increase strictly"), "{err}");
    t[2 * CHUNK + 1] = f64::NAN;
    let err = run(&t, &zeros);
    assert_eq!((err.argument(), err.index()), (Some("t"), Some(2 * CHUNK + 1)), "{err}");
    // A repeat across a block's edge: the pair (t[k − 1], t[k]) of a block's first k.
    let mut t = good.clone();
    t[2 * CHUNK] = t[2 * CHUNK - 1];
    assert_eq!(run(&t, &zeros).index(), Some(2 * CHUNK));
    let mut ideal = zeros.clone();
    (ideal[3 * (2 * CHUNK) + 2], ideal[3 * (CHUNK + 1)]) = (f64::INFINITY, f64::NAN);
    let err = run(&good, &ideal);
    assert_eq!((err.argument(), err.index()), (Some("ideal"), Some(CHUNK + 1)), "{err}");
}
