//! `Preintegrator::state_words` / `from_state_words`: the complete state survives the round trip
//! (equal, and continuing equally: the midpoint scheme's end samples and noise correlations, the
//! bias walk and the projection counter included); a list of another length is refused.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use imukit::preint::{Clipped, Preintegrator, Scheme};
use imukit_testing::preint::{samples, H, NOISE};
use nalgebra::Vector3;

#[test]
fn the_state_round_trips_and_continues_bit_for_bit() {
    let data = samples();
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        for walk in [false, true] {
            let mut p = Preintegrator::new(Vector3::new(0.01, 0.0, -0.02), Vector3::new(0.1, 0.0, 0.0), NOISE)
                .with_scheme(scheme)
                .with_saturation_noise_factor(20.0)
                .unwrap();
            if walk {
                p = p.with_bias_walk();
            }
            let (head, tail) = data.split_at(37); // 37: mid-way between two projections
            for (k, (a, w)) in head.iter().enumerate() {
                let h = if scheme == Scheme::Midpoint && k == 0 { 0.0 } else { H };
                let clipped = Clipped {
                    gyro: k == 5,
                    accel: k == 36,
                };
                p.try_integrate_measurement(a, w, h, clipped).unwrap();
            }
            let mut back = Preintegrator::from_state_words(&p.state_words()).unwrap();
            assert_eq!(back, p);
            for (a, w) in tail {
                p.integrate_measurement(a, w, H);
                back.integrate_measurement(a, w, H);
            }
            assert_eq!(back, p);
            let words = p.state_words();
            assert!(Preintegrator::from_state_words(&words[1..]).is_err());
            assert!(Preintegrator::from_state_words(&[words.clone(), vec![0.0]].concat()).is_err());
        }
    }
}

/// A midpoint state of the earlier layout (scheme word 1: body-frame blocks, no pending input) is
/// refused, not misread; so is an unknown scheme word.
#[test]
fn states_of_the_earlier_midpoint_layout_are_refused() {
    let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), NOISE).with_scheme(Scheme::Midpoint);
    for (k, (a, w)) in samples().iter().take(5).enumerate() {
        p.integrate_measurement(a, w, if k == 0 { 0.0 } else { H });
    }
    let mut words = p.state_words();
    assert_eq!(words[0], 2.0);
    for scheme in [1.0, 4.0] {
        words[0] = scheme;
        let message = Preintegrator::from_state_words(&words).unwrap_err().to_string();
        assert!(message.contains("scheme word"), "{message}");
    }
}
