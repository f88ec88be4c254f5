//! `imukit::filters`: `Filter::new` with arbitrary gains and options, then `Filter::run` (fresh,
//! from a restored state, continued) and `Filter::update` on arbitrary series: never a panic; an
//! `Ok` from finite input leaves a finite, unit attitude and a finite bias.
#![no_main]

use arbitrary::Arbitrary;
use imukit::filters::{
    AccelLowPass, AccelRejection, CommonState, Filter, GainRamp, Inputs, Law, Madgwick, MagRejection, Mahony, Options,
    RestDetection, State, World,
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
    accel_lowpass: Option<f64>,
    accel_rejection: Option<[f64; 5]>,
    mag_rejection: Option<[f64; 3]>,
    rest: Option<[f64; 5]>,
    mag_hold_s: f64,
    restore: Option<Restore>,
    continued: bool,
    mag: Option<Vec<f64>>,
    series: Series,
    dt: f64,
}

/// A stored state: quaternion `xyzw`, bias, `initialized`, then the clocks and the field reference.
#[derive(Arbitrary, Debug)]
struct Restore {
    xyzw: [f64; 4],
    bias: [f64; 3],
    initialized: bool,
    scalars: [f64; 8],
}

impl Restore {
    fn state(&self) -> imukit::Result<CommonState> {
        let [time, ramp_elapsed, accel_rejected, mag_rejected, rest, mag_norm, mag_dip_sin, mag_dip_cos] = self.scalars;
        CommonState {
            bias: vector(self.bias),
            initialized: self.initialized,
            time,
            ramp_elapsed,
            accel_rejected,
            mag_rejected,
            rest,
            mag_norm,
            mag_dip_sin,
            mag_dip_cos,
            ..CommonState::default()
        }
        .restored(self.xyzw)
    }
}

fn check(what: &str, s: &CommonState) {
    assert_finite(what, s.q.coords.as_slice());
    assert_finite(what, s.bias.as_slice());
    assert_unit(what, s.q.coords.as_slice());
}

fuzz_target!(|input: Input| {
    let options = Options {
        world: if input.ned { World::Ned } else { World::Enu },
        gravity: input.gravity,
        gain_ramp: GainRamp {
            duration_s: input.ramp[0],
            factor: input.ramp[1],
        },
        acc_lowpass: input.accel_lowpass.map(|tau_s| AccelLowPass { tau_s }),
        acc_rejection: input
            .accel_rejection
            .map(|[norm, angle_rad, recovery_s, filtered_norm, drift_s]| AccelRejection {
                norm,
                angle_rad,
                recovery_s,
                filtered_norm,
                drift_s,
            }),
        mag_rejection: input
            .mag_rejection
            .map(|[norm_fraction, dip_rad, recovery_s]| MagRejection {
                norm_fraction,
                dip_rad,
                recovery_s,
            }),
        rest_detection: input.rest.map(|[gyro, accel, duration_s, tau_s, max_bias]| RestDetection {
            gyro,
            accel,
            duration_s,
            tau_s,
            max_bias,
        }),
        mag_hold_s: input.mag_hold_s,
    };
    if input.madgwick {
        let [beta, full_rate_angle_rad] = input.gains;
        drive(
            Madgwick {
                beta,
                full_rate_angle_rad,
            },
            options,
            &input,
        );
    } else {
        let [kp, ki] = input.gains;
        drive(Mahony { kp, ki }, options, &input);
    }
});

fn drive<L: Law>(law: L, options: Options, input: &Input) {
    let Ok(filter) = Filter::new(law, options) else {
        return;
    };
    let mut state: State<L> = match &input.restore {
        Some(r) => match r.state() {
            Ok(s) => State::from(s),
            Err(_) => return,
        },
        None => State::default(),
    };
    // A restored state is only as finite as what was restored (bias, times).
    let finite_state = input
        .restore
        .as_ref()
        .is_none_or(|r| finite(&r.bias) && finite(&r.scalars));
    let a = input.series.arrays();
    let n = a.t.len();
    let gyro = a.gyro.as_chunks::<3>().0;
    let accel = a.accel.as_chunks::<3>().0;
    let mag = input.mag.as_deref().map(|m| m.as_chunks::<3>().0);
    let inputs = Inputs {
        t: &a.t,
        gyro,
        accel,
        mag,
    };
    let (mut out_q, mut out_bias) = (vec![[0.0; 4]; n], vec![[0.0; 3]; n]);
    let mut batch_state = state;
    let finite_input = finite_state && a.finite() && input.mag.as_deref().is_none_or(finite);
    let result = filter.run(&mut batch_state, &inputs, input.continued, &mut out_q, &mut out_bias);
    if let (Ok(()), true) = (result, finite_input) {
        out_q.iter().for_each(|q| assert_unit("run q", q));
        assert_finite("run bias", out_bias.as_flattened());
        if n > 0 {
            check("run state", &batch_state.common);
        }
    }

    // Streaming, sample by sample, the same data with a fixed step.
    for k in 0..n.min(gyro.len()).min(accel.len()) {
        let m = mag.and_then(|m| m.get(k)).map(|&m| vector(m));
        let ok = filter.update(&mut state, &vector(gyro[k]), &vector(accel[k]), m.as_ref(), input.dt);
        if ok.is_err() {
            break;
        }
        if finite_state && finite(&[input.dt]) && finite(&gyro[k]) && finite(&accel[k]) {
            check("update", &state.common);
        } else {
            break;
        }
    }
}
