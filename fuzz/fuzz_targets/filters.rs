//! `imukit::filters`: `Filter::new` with arbitrary gains and options, then `Filter::run` (fresh,
//! from a restored state, continued) and `Filter::update` on arbitrary series: never a panic; an
//! `Ok` from finite input leaves a finite, unit attitude and a finite bias.
#![no_main]

use arbitrary::Arbitrary;
use imukit::filters::{
    AccelRejection, Algorithm, Common, Filter, GainRamp, Inputs, Madgwick, MagRejection, Mahony, RestDetection, State,
    World, STATE_LEN,
};
use imukit_fuzz::{assert_finite, assert_unit, finite, vector, Series};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    madgwick: bool,
    gains: [f64; 2],
    ned: bool,
    gravity: f64,
    ramp: [f64; 2],
    accel_rejection: Option<[f64; 3]>,
    mag_rejection: Option<[f64; 3]>,
    rest: Option<[f64; 4]>,
    restore: Option<[f64; STATE_LEN]>,
    continued: bool,
    mag: Option<Vec<f64>>,
    series: Series,
    dt: f64,
}

fn check(what: &str, s: &State) {
    assert_finite(what, s.q.coords.as_slice());
    assert_finite(what, s.bias.as_slice());
    assert_unit(what, s.q.coords.as_slice());
}

fuzz_target!(|input: Input| {
    let algorithm = if input.madgwick {
        Algorithm::Madgwick(Madgwick { beta: input.gains[0] })
    } else {
        Algorithm::Mahony(Mahony {
            kp: input.gains[0],
            ki: input.gains[1],
        })
    };
    let common = Common {
        world: if input.ned { World::Ned } else { World::Enu },
        gravity: input.gravity,
        ramp: GainRamp {
            duration: input.ramp[0],
            factor: input.ramp[1],
        },
        accel_rejection: input
            .accel_rejection
            .map(|[norm, angle, recovery]| AccelRejection { norm, angle, recovery }),
        mag_rejection: input
            .mag_rejection
            .map(|[norm, dip, recovery]| MagRejection { norm, dip, recovery }),
        rest: input.rest.map(|[gyro, accel, duration, tau]| RestDetection {
            gyro,
            accel,
            duration,
            tau,
        }),
    };
    let Ok(filter) = Filter::new(algorithm, common) else {
        return;
    };
    let mut state = match input.restore {
        Some(a) => match State::from_array(&a) {
            Ok(s) => s,
            Err(_) => return,
        },
        None => State::default(),
    };
    // A restored state is only as finite as what was restored (bias, times).
    let finite_state = finite(&state.to_array());
    let a = input.series.arrays();
    let n = a.t.len();
    let mag = input.mag.as_deref();
    let inputs = Inputs {
        t: &a.t,
        gyro: &a.gyro,
        accel: &a.accel,
        mag,
    };
    let (mut out_q, mut out_bias) = (vec![0.0; 4 * n], vec![0.0; 3 * n]);
    let mut batch_state = state;
    let finite_input = finite_state && a.finite() && mag.is_none_or(finite);
    let result = filter.run(&mut batch_state, &inputs, input.continued, &mut out_q, &mut out_bias);
    if let (Ok(()), true) = (result, finite_input) {
        out_q.chunks_exact(4).for_each(|q| assert_unit("run q", q));
        assert_finite("run bias", &out_bias);
        if n > 0 {
            check("run state", &batch_state);
        }
    }

    // Streaming, sample by sample, the same data with a fixed step.
    for k in 0..n.min(a.gyro.len() / 3).min(a.accel.len() / 3) {
        let row = |x: &[f64]| vector([x[3 * k], x[3 * k + 1], x[3 * k + 2]]);
        let m = mag.filter(|m| m.len() >= 3 * (k + 1)).map(row);
        let ok = filter.update(&mut state, &row(&a.gyro), &row(&a.accel), m.as_ref(), input.dt);
        if ok.is_err() {
            break;
        }
        if finite_state && finite(&[input.dt]) && finite(row(&a.gyro).as_slice()) && finite(row(&a.accel).as_slice()) {
            check("update", &state);
        } else {
            break;
        }
    }
});
