//! `imukit::preint`: `Preintegrator::integrate_samples` (twice, continuing), `merge`, and
//! `preintegrate_windows` on arbitrary series, biases, noise and boundaries: never a panic; an
//! `Ok` from finite input leaves every delta, covariance and Jacobian finite.
#![no_main]

use arbitrary::Arbitrary;
use imukit::preint::{preintegrate_windows, Preintegrator, Scheme};
use imukit_fuzz::{assert_finite, finite, noise, vector, Series};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    midpoint: bool,
    bias_walk: bool,
    bias_gyro: [f64; 3],
    bias_accel: [f64; 3],
    noise: [f64; 4],
    first: Series,
    second: Series,
    /// Window boundaries as fractions of the first series' span (or raw times when out of [0, 1]).
    boundaries: Vec<f64>,
}

fn check(what: &str, p: &Preintegrator) {
    assert_finite(what, p.delta_rotation.as_slice());
    assert_finite(what, p.delta_velocity.as_slice());
    assert_finite(what, p.delta_position.as_slice());
    assert_finite(what, &[p.delta_t]);
    assert_finite(what, p.covariance().as_slice());
    assert_finite(what, p.bias_jacobian().as_slice());
    if let Some(c) = p.covariance_combined() {
        assert_finite(what, c.as_slice());
    }
}

fuzz_target!(|input: Input| {
    let noise = noise(input.noise);
    let mut template =
        Preintegrator::new(vector(input.bias_gyro), vector(input.bias_accel), noise).with_scheme(if input.midpoint {
            Scheme::Midpoint
        } else {
            Scheme::Euler
        });
    if input.bias_walk {
        template = template.with_bias_walk();
    }
    let finite_setup = finite(template.bias_gyro.as_slice())
        && finite(template.bias_accel.as_slice())
        && finite(&input.noise)
        && input.noise.iter().all(|v| *v >= 0.0);
    let first = input.first.arrays();
    let second = input.second.arrays();

    let mut p = template.clone();
    if first.samples().and_then(|s| p.integrate_samples(&s)).is_ok() && finite_setup && first.finite() {
        check("integrate_samples", &p);
        let mut q = template.clone();
        if second.samples().and_then(|s| q.integrate_samples(&s)).is_ok() && second.finite() {
            check("integrate_samples (second)", &q);
            if let Ok(m) = p.merge(&q) {
                check("merge", &m);
            }
        }
        if second.samples().and_then(|s| p.integrate_samples(&s)).is_ok() && second.finite() {
            check("integrate_samples (continued)", &p);
        }
    }

    if let (Some(lo), Some(hi)) = (first.t.first(), first.t.last()) {
        let boundaries: Vec<f64> = input
            .boundaries
            .iter()
            .map(|f| {
                if (0.0..=1.0).contains(f) {
                    lo + (hi - lo) * f
                } else {
                    *f
                }
            })
            .collect();
        let result = first.samples().and_then(|s| preintegrate_windows(&s, &boundaries, &template));
        if let (Ok(windows), true) = (result, finite_setup && first.finite()) {
            assert_eq!(windows.len() + 1, boundaries.len());
            for w in &windows {
                check("preintegrate_windows", w);
            }
        }
    }
});
