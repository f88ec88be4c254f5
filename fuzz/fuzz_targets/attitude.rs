//! `imukit::attitude::integrate` on arbitrary series, schemes and representations: never a panic;
//! an `Ok` from finite input is finite and unit.
#![no_main]

use arbitrary::Arbitrary;
use imukit::attitude::{integrate, Options, Representation, Scheme};
use imukit_fuzz::{assert_finite, assert_unit, finite, unit, Series};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    scheme: u8,
    representation: u8,
    gimbal_tolerance: f64,
    /// `[x, y, z, w]`, normalised by the caller as the bindings do.
    initial: [f64; 4],
    store: bool,
    series: Series,
}

const SCHEMES: [Scheme; 5] = [
    Scheme::Euler,
    Scheme::Exp,
    Scheme::Rk2,
    Scheme::Rk4,
    Scheme::Magnus,
];
const REPRESENTATIONS: [Representation; 3] = [
    Representation::Quaternion,
    Representation::Matrix,
    Representation::Euler,
];

fuzz_target!(|input: Input| {
    let a = input.series.arrays();
    let Some(initial) = unit(input.initial) else {
        return;
    };
    let options = Options {
        scheme: SCHEMES[usize::from(input.scheme) % SCHEMES.len()],
        representation: REPRESENTATIONS[usize::from(input.representation) % REPRESENTATIONS.len()],
        gimbal_tolerance: input.gimbal_tolerance,
    };
    let mut out = vec![0.0; 4 * a.t.len()];
    let result = integrate(&a.t, a.gyro.as_chunks().0, &initial, &options, input.store.then_some(out.as_chunks_mut().0));
    let finite_input = finite(&a.t) && finite(&a.gyro) && finite(initial.coords.as_slice());
    if let (Ok(q), true) = (result, finite_input) {
        assert_finite("attitude", q.coords.as_slice());
        assert_unit("attitude", q.coords.as_slice());
        if input.store {
            out.chunks_exact(4).for_each(|q| assert_unit("attitude out", q));
        }
    }
});
