//! `imukit::strapdown::integrate` and `imukit::propagate::propagate` on arbitrary series, states,
//! biases, noise and covariances: never a panic; an `Ok` from finite input is finite.
#![no_main]

use arbitrary::Arbitrary;
use imukit::propagate::{covariance_count, propagate, Covariance, Outputs};
use imukit::imu::{Bias, NavState};
use imukit::strapdown::{integrate, Options, Scheme, StatesOut};
use imukit_fuzz::{assert_finite, assert_unit, finite, noise, unit, vector, Series};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    scheme: u8,
    gravity: [f64; 3],
    position: [f64; 3],
    velocity: [f64; 3],
    rotation: [f64; 4],
    bias_gyro: [f64; 3],
    bias_accel: [f64; 3],
    /// `[gyro, accel, gyro walk, accel walk]` densities.
    noise: [f64; 4],
    /// Diagonal of the initial covariance, and one symmetric off-diagonal pair.
    variances: [f64; 15],
    off_diagonal: (u8, u8, f64),
    every: u8,
    store: bool,
    series: Series,
}

const SCHEMES: [Scheme; 4] = [Scheme::LieEuler, Scheme::Midpoint, Scheme::Rk4, Scheme::Exp];

fuzz_target!(|input: Input| {
    let a = input.series.arrays();
    let n = a.t.len();
    let Some(rotation) = unit(input.rotation) else {
        return;
    };
    let initial = NavState {
        position: vector(input.position),
        velocity: vector(input.velocity),
        rotation,
    };
    let bias = Bias {
        gyro: vector(input.bias_gyro),
        accel: vector(input.bias_accel),
    };
    let options = Options {
        scheme: SCHEMES[usize::from(input.scheme) % SCHEMES.len()],
        gravity: vector(input.gravity),
        ..Options::default()
    };
    let noise = noise(input.noise);
    let mut p = Covariance::from_diagonal(&nalgebra::SVector::<f64, 15>::from(input.variances));
    let (i, j, v) = input.off_diagonal;
    let (i, j) = (usize::from(i) % 15, usize::from(j) % 15);
    p[(i, j)] = v;
    p[(j, i)] = v;
    let finite_input = a.finite()
        && finite(initial.position.as_slice())
        && finite(initial.velocity.as_slice())
        && finite(initial.rotation.coords.as_slice())
        && finite(bias.gyro.as_slice())
        && finite(bias.accel.as_slice())
        && finite(options.gravity.as_slice());

    let (mut pv, mut rot) = (vec![0.0; 6 * n], vec![0.0; 4 * n]);
    let out = input.store.then(|| StatesOut {
        position_velocity: pv.as_chunks_mut().0,
        rotation: rot.as_chunks_mut().0,
    });
    if let (Ok(x), true) = (a.samples().and_then(|s| integrate(&s, &initial, &bias, &options, out)), finite_input) {
        assert_finite("strapdown position", x.position.as_slice());
        assert_finite("strapdown velocity", x.velocity.as_slice());
        assert_finite("strapdown rotation", x.rotation.coords.as_slice());
        assert_unit("strapdown rotation", x.rotation.coords.as_slice());
        if input.store {
            assert_finite("strapdown states", &pv);
            rot.chunks_exact(4).for_each(|q| assert_unit("strapdown states", q));
        }
    }

    let every = usize::from(input.every);
    let mut covariances = vec![[0.0; 225]; covariance_count(n, every)];
    let outputs = Outputs {
        states: input.store.then(|| StatesOut {
            position_velocity: pv.as_chunks_mut().0,
            rotation: rot.as_chunks_mut().0,
        }),
        covariances: &mut covariances,
        every,
    };
    let result = a.samples().and_then(|s| propagate(&s, &initial, &p, &bias, &noise, &options, outputs));
    if let (Ok((x, cov)), true) = (result, finite_input && finite(p.as_slice())) {
        assert_finite("propagate position", x.position.as_slice());
        assert_finite("propagate velocity", x.velocity.as_slice());
        assert_finite("propagate rotation", x.rotation.coords.as_slice());
        assert_unit("propagate rotation", x.rotation.coords.as_slice());
        assert_finite("propagate covariance", cov.as_slice());
        assert_finite("propagate covariances", covariances.as_flattened());
        assert_eq!(cov, cov.transpose(), "propagate: covariance not symmetric");
    }
});
