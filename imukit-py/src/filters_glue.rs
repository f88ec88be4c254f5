//! Attitude-filter bindings. Values cross by field name:
//!
//! | Python (`imukit._core`) | Rust (`imukit::filters`) |
//! |---|---|
//! | `GainRamp`, `AccelLowPass`, `AccelRejection`, `MagRejection`, `RestDetection` (frozen values; omitted or None fields take the Rust `Default`) | the option structs, field for field |
//! | `MahonyGains`, `MadgwickGains` | the laws `Mahony`, `Madgwick` |
//! | `FilterOptions` (`FilterOptions.default()`: `Options::default()`) | `Options` |
//! | `FilterState` (named getters, pickles by name) | `CommonState` + the law's `Extra` by `Fields` names |
//! | `MahonyFilter`, `MadgwickFilter` (one [`filter_class!`] line per law) | `Filter<Mahony>`, `Filter<Madgwick>` |
//!
//! The glue converts only: values are checked by the core when a value class is built (errors
//! name the option as `<option>.<quantity>`), Python types by `imukit.filters`; a number that is
//! not one is a `ParameterError` here, where the conversion fails.

use imukit::filters::{
    AccelLowPass, AccelRejection, CommonState, FieldHold, Fields, Filter, GainRamp, Law, Madgwick, MagRejection,
    Mahony, Options, RestDetection, State, World,
};
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::convert::{empty, Demand, FilterRecord, SampleCopies};
use crate::convert::{real_number, Name};
use crate::threads::Fresh;
use crate::{raise, state_copy, to_py};

/// `x` as a float; None (omitted) keeps `default`. Strings and arrays of several numbers are not
/// numbers: a `ParameterError` naming `name`.
fn real(py: Python<'_>, name: &str, x: Option<&Bound<'_, PyAny>>, default: f64) -> PyResult<f64> {
    x.map_or(Ok(default), |v| real_number(py, name, v))
}

/// A frozen value class mirroring a Rust option struct field for field: keyword (or positional)
/// construction with the Rust `Default` for what is omitted, equality, hash, repr, pickling.
macro_rules! value_class {
    ($(#[$doc:meta])* $py:ident = $rust:ident as $name:literal, errors $prefix:literal { $($field:ident),+ $(,)? }) => {
        $(#[$doc])*
        #[pyclass(name = $name, module = "imukit._core", frozen, get_all, eq, from_py_object)]
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub(crate) struct $py {
            $($field: f64),+
        }

        #[pymethods]
        impl $py {
            #[new]
            #[pyo3(signature = ($($field = None),+))]
            fn new(py: Python<'_>, $($field: Option<&Bound<'_, PyAny>>),+) -> PyResult<Self> {
                let default = $rust::default();
                let value = Self { $($field: real(py, concat!($prefix, stringify!($field)), $field, default.$field)?),+ };
                // Out of its domain a value is refused where it is written, not at the filter's build.
                $rust::from(value).validate().map_err(|e| to_py(py, $name, e))?;
                Ok(value)
            }

            fn __repr__(&self) -> String {
                let fields = [$(format!(concat!(stringify!($field), "={:?}"), self.$field)),+];
                format!(concat!($name, "({})"), fields.join(", "))
            }

            fn __hash__(&self, py: Python<'_>) -> PyResult<isize> {
                PyTuple::new(py, [$(self.$field),+])?.hash()
            }

            fn __getnewargs__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
                PyTuple::new(py, [$(self.$field),+])
            }
        }

        impl From<$py> for $rust {
            fn from(v: $py) -> Self {
                Self { $($field: v.$field),+ }
            }
        }

        impl From<$rust> for $py {
            fn from(v: $rust) -> Self {
                Self { $($field: v.$field),+ }
            }
        }
    };
}

value_class!(
    /// Start-up gain ramp (`imukit::filters::GainRamp`).
    PyGainRamp = GainRamp as "GainRamp", errors "gain_ramp." { duration_s, factor }
);
value_class!(
    /// Accelerometer low pass in the gyro frame (`imukit::filters::AccelLowPass`).
    PyAccelLowPass = AccelLowPass as "AccelLowPass", errors "acc_lowpass." { tau_s }
);
value_class!(
    /// Acceleration rejection (`imukit::filters::AccelRejection`).
    PyAccelRejection = AccelRejection as "AccelRejection", errors "acc_rejection." {
        norm, angle_rad, recovery_s, filtered_norm, drift_s
    }
);
value_class!(
    /// Magnetic rejection (`imukit::filters::MagRejection`).
    PyMagRejection = MagRejection as "MagRejection", errors "mag_rejection." {
        norm_fraction, dip_rad, recovery_s
    }
);
value_class!(
    /// Rest detection (`imukit::filters::RestDetection`).
    PyRestDetection = RestDetection as "RestDetection", errors "rest_detection." {
        gyro, accel, duration_s, tau_s, max_bias
    }
);
value_class!(
    /// Mahony's gains (`imukit::filters::Mahony`).
    PyMahonyGains = Mahony as "MahonyGains", errors "" { kp, ki }
);
value_class!(
    /// Madgwick's gain (`imukit::filters::Madgwick`).
    PyMadgwickGains = Madgwick as "MadgwickGains", errors "" { beta, full_rate_angle_rad }
);

/// The shared options (`imukit::filters::Options`); `None` switches an option off.
#[pyclass(name = "FilterOptions", module = "imukit._core", frozen, get_all, eq, from_py_object)]
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PyFilterOptions {
    world: Name<World>,
    gravity: f64,
    gain_ramp: Option<PyGainRamp>,
    acc_lowpass: Option<PyAccelLowPass>,
    acc_rejection: Option<PyAccelRejection>,
    mag_rejection: Option<PyMagRejection>,
    rest_detection: Option<PyRestDetection>,
    mag_hold_s: f64,
}

#[pymethods]
impl PyFilterOptions {
    /// `mag_hold_s` omitted (an options object pickled before it existed): the core's default.
    #[new]
    #[pyo3(signature = (*, world, gravity, gain_ramp, acc_lowpass, acc_rejection, mag_rejection, rest_detection, mag_hold_s=None))]
    #[allow(clippy::too_many_arguments)] // one keyword per option
    fn new(
        py: Python<'_>,
        world: Name<World>,
        gravity: &Bound<'_, PyAny>,
        gain_ramp: Option<PyGainRamp>,
        acc_lowpass: Option<PyAccelLowPass>,
        acc_rejection: Option<PyAccelRejection>,
        mag_rejection: Option<PyMagRejection>,
        rest_detection: Option<PyRestDetection>,
        mag_hold_s: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        Ok(Self {
            world,
            gravity: real(py, "gravity", Some(gravity), f64::NAN)?,
            gain_ramp,
            acc_lowpass,
            acc_rejection,
            mag_rejection,
            rest_detection,
            mag_hold_s: real(py, "mag_hold_s", mag_hold_s, Options::default().mag_hold_s)?,
        })
    }

    /// `imukit::filters::Options::default()`.
    #[staticmethod]
    fn default() -> Self {
        let o = Options::default();
        Self {
            world: Name(o.world),
            gravity: o.gravity,
            gain_ramp: Some(o.gain_ramp.into()),
            acc_lowpass: o.acc_lowpass.map(Into::into),
            acc_rejection: o.acc_rejection.map(Into::into),
            mag_rejection: o.mag_rejection.map(Into::into),
            rest_detection: o.rest_detection.map(Into::into),
            mag_hold_s: o.mag_hold_s,
        }
    }

    fn __getnewargs_ex__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        let kwargs = PyDict::new(py);
        kwargs.set_item("world", self.world)?;
        kwargs.set_item("gravity", self.gravity)?;
        kwargs.set_item("gain_ramp", self.gain_ramp)?;
        kwargs.set_item("acc_lowpass", self.acc_lowpass)?;
        kwargs.set_item("acc_rejection", self.acc_rejection)?;
        kwargs.set_item("mag_rejection", self.mag_rejection)?;
        kwargs.set_item("rest_detection", self.rest_detection)?;
        kwargs.set_item("mag_hold_s", self.mag_hold_s)?;
        Ok((PyTuple::empty(py), kwargs))
    }
}

impl PyFilterOptions {
    fn options(&self) -> Options {
        Options {
            world: self.world.0,
            gravity: self.gravity,
            // No ramp: zero length (its factor then never applies).
            gain_ramp: self.gain_ramp.map_or(
                GainRamp {
                    duration_s: 0.0,
                    factor: 1.0,
                },
                Into::into,
            ),
            acc_lowpass: self.acc_lowpass.map(Into::into),
            acc_rejection: self.acc_rejection.map(Into::into),
            mag_rejection: self.mag_rejection.map(Into::into),
            rest_detection: self.rest_detection.map(Into::into),
            mag_hold_s: self.mag_hold_s,
        }
    }
}

/// The state of a filter of any law: the common part and the law's own fields by name.
#[pyclass(name = "FilterState", module = "imukit._core", frozen, subclass, eq)]
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PyFilterState {
    common: CommonState,
    extra: Vec<(String, f64)>,
}

impl PyFilterState {
    fn of<L: Law>(s: &State<L>) -> Self {
        let names = <L::Extra as Fields>::NAMES.iter().map(|n| (*n).to_owned());
        Self {
            common: s.common,
            extra: names.zip(s.extra.values()).collect(),
        }
    }

    /// As a state of law `L`; the law's own state starts from its default when this one holds
    /// another law's (a Mahony state continued by Madgwick keeps attitude, bias and gates).
    fn typed<L: Law>(&self) -> State<L> {
        let names = self.extra.iter().map(|(n, _)| n.as_str());
        let values: Vec<f64> = self.extra.iter().map(|(_, v)| *v).collect();
        let extra = if names.eq(<L::Extra as Fields>::NAMES.iter().copied()) {
            <L::Extra as Fields>::from_values(&values).unwrap_or_default()
        } else {
            L::Extra::default()
        };
        State {
            common: self.common,
            extra,
        }
    }

    /// The pre-0.x flat layout `[qx, qy, qz, qw, bx, by, bz, initialized, time, ramp_elapsed,
    /// accel_rejected, mag_rejected, rest, mag_norm, sin δ₀, cos δ₀]` of the deprecated
    /// `FilterState(values)` / `.values`; it is written here only.
    fn flat_values(&self) -> [f64; 16] {
        let s = &self.common;
        let c = &s.q.coords;
        [
            c[0],
            c[1],
            c[2],
            c[3],
            s.bias.x,
            s.bias.y,
            s.bias.z,
            f64::from(u8::from(s.initialized)),
            s.time,
            s.ramp_elapsed,
            s.accel_rejected,
            s.mag_rejected,
            s.rest,
            s.mag_norm,
            s.mag_dip_sin,
            s.mag_dip_cos,
        ]
    }
}

#[pymethods]
impl PyFilterState {
    /// A state from its fields by name (what pickling stores), checked and normalised by the core;
    /// or a copy of `state`, which the core has checked already (what `update` makes of each
    /// sample's state: through its fields by name it took 6 µs). The fields up to `mag_dip_cos`
    /// are required without `state`.
    #[new]
    #[pyo3(signature = (state=None, /, *, quaternion=None, gyro_bias=None, initialized=None, time=None, ramp_elapsed=None, accel_rejected=None, mag_rejected=None, rest=None, mag_norm=None, mag_dip_sin=None, mag_dip_cos=None, acc_lp1=[0.0; 3], acc_lp2=[0.0; 3], gyro_lp=[0.0; 3], rest_gyro_ms=0.0, rest_accel_lp=[0.0; 3], rest_accel_ms=0.0, accel_calm=0.0, accel_drift=false, mag_held=[0.0; 3], mag_held_s=0.0, world=None, extra=None))]
    #[allow(clippy::too_many_arguments)] // one keyword per field of the state
    fn new(
        py: Python<'_>,
        state: Option<PyRef<'_, PyFilterState>>,
        quaternion: Option<[f64; 4]>,
        gyro_bias: Option<[f64; 3]>,
        initialized: Option<bool>,
        time: Option<f64>,
        ramp_elapsed: Option<f64>,
        accel_rejected: Option<f64>,
        mag_rejected: Option<f64>,
        rest: Option<f64>,
        mag_norm: Option<f64>,
        mag_dip_sin: Option<f64>,
        mag_dip_cos: Option<f64>,
        acc_lp1: [f64; 3],
        acc_lp2: [f64; 3],
        gyro_lp: [f64; 3],
        rest_gyro_ms: f64,
        rest_accel_lp: [f64; 3],
        rest_accel_ms: f64,
        accel_calm: f64,
        accel_drift: bool,
        mag_held: [f64; 3],
        mag_held_s: f64,
        world: Option<Name<World>>,
        extra: Option<Vec<(String, f64)>>,
    ) -> PyResult<Self> {
        let required = [
            quaternion.is_some(),
            gyro_bias.is_some(),
            initialized.is_some(),
            time.is_some(),
            ramp_elapsed.is_some(),
            accel_rejected.is_some(),
            mag_rejected.is_some(),
            rest.is_some(),
            mag_norm.is_some(),
            mag_dip_sin.is_some(),
            mag_dip_cos.is_some(),
        ];
        if let Some(state) = state {
            return state_copy(
                py,
                &*state,
                required.contains(&true) || extra.is_some() || world.is_some(),
            );
        }
        let missing = || {
            raise(
                py,
                "ParameterError",
                "state",
                "expected a state, or the fields quaternion, gyro_bias, initialized, time, ramp_elapsed, accel_rejected, mag_rejected, rest, mag_norm, mag_dip_sin and mag_dip_cos",
            )
        };
        let common = CommonState {
            bias: Vector3::from(gyro_bias.ok_or_else(missing)?),
            initialized: initialized.ok_or_else(missing)?,
            time: time.ok_or_else(missing)?,
            ramp_elapsed: ramp_elapsed.ok_or_else(missing)?,
            accel_rejected: accel_rejected.ok_or_else(missing)?,
            mag_rejected: mag_rejected.ok_or_else(missing)?,
            rest: rest.ok_or_else(missing)?,
            mag_norm: mag_norm.ok_or_else(missing)?,
            mag_dip_sin: mag_dip_sin.ok_or_else(missing)?,
            mag_dip_cos: mag_dip_cos.ok_or_else(missing)?,
            acc_lp1: Vector3::from(acc_lp1),
            acc_lp2: Vector3::from(acc_lp2),
            gyro_lp: Vector3::from(gyro_lp),
            rest_gyro_ms,
            rest_accel_lp: Vector3::from(rest_accel_lp),
            rest_accel_ms,
            accel_calm,
            accel_drift,
            mag_hold: FieldHold {
                field: Vector3::from(mag_held),
                age_s: mag_held_s,
            },
            world: world.map(|w| w.0),
            ..CommonState::default()
        }
        .restored(quaternion.ok_or_else(missing)?)
        .map_err(|e| to_py(py, "state", e))?;
        Ok(Self {
            common,
            extra: extra.unwrap_or_default(),
        })
    }

    /// The uninitialised state, or one initialised at quaternion `q` (xyzw) with zero bias.
    #[staticmethod]
    #[pyo3(signature = (q=None))]
    #[pyo3(name = "_initial")]
    fn initial(py: Python<'_>, q: Option<[f64; 4]>) -> PyResult<Self> {
        let common = match q {
            None => CommonState::default(),
            Some([x, y, z, w]) => {
                let q = imukit::quat::normalize(&nalgebra::Quaternion::new(w, x, y, z))
                    .map_err(|e| to_py(py, "initial", e))?;
                CommonState::at(q, Vector3::zeros(), 0.0)
            }
        };
        Ok(Self {
            common,
            extra: Vec::new(),
        })
    }

    /// From the deprecated 16-value layout (shape and dtype checked by `imukit.filters`).
    #[staticmethod]
    #[pyo3(name = "_from_legacy_values")]
    fn from_legacy_values(py: Python<'_>, values: [f64; 16]) -> PyResult<Self> {
        let [x, y, z, w, bx, by, bz, initialized, time, ramp, accel, mag, rest, norm, sin, cos] = values;
        let q = [x, y, z, w];
        Self::new(
            py,
            None,
            Some(q),
            Some([bx, by, bz]),
            Some(initialized != 0.0),
            Some(time),
            Some(ramp),
            Some(accel),
            Some(mag),
            Some(rest),
            Some(norm),
            Some(sin),
            Some(cos),
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            0.0,
            [0.0; 3],
            0.0,
            0.0,
            false,
            [0.0; 3],
            0.0,
            None,
            None,
        )
    }

    /// The deprecated 16-value layout.
    #[pyo3(name = "_legacy_values")]
    fn legacy_values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.flat_values())
    }

    /// This state with its clock at `time` [s].
    #[pyo3(name = "_at_time")]
    fn at_time(&self, time: f64) -> Self {
        let mut s = self.clone();
        s.common.time = time;
        s
    }

    /// The fields by name: the keywords of the constructor.
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.common;
        let d = PyDict::new(py);
        d.set_item("quaternion", <[f64; 4]>::from(s.q.coords))?;
        d.set_item("gyro_bias", <[f64; 3]>::from(s.bias))?;
        d.set_item("initialized", s.initialized)?;
        d.set_item("time", s.time)?;
        d.set_item("ramp_elapsed", s.ramp_elapsed)?;
        d.set_item("accel_rejected", s.accel_rejected)?;
        d.set_item("mag_rejected", s.mag_rejected)?;
        d.set_item("rest", s.rest)?;
        d.set_item("mag_norm", s.mag_norm)?;
        d.set_item("mag_dip_sin", s.mag_dip_sin)?;
        d.set_item("mag_dip_cos", s.mag_dip_cos)?;
        d.set_item("acc_lp1", <[f64; 3]>::from(s.acc_lp1))?;
        d.set_item("acc_lp2", <[f64; 3]>::from(s.acc_lp2))?;
        d.set_item("gyro_lp", <[f64; 3]>::from(s.gyro_lp))?;
        d.set_item("rest_gyro_ms", s.rest_gyro_ms)?;
        d.set_item("rest_accel_lp", <[f64; 3]>::from(s.rest_accel_lp))?;
        d.set_item("rest_accel_ms", s.rest_accel_ms)?;
        d.set_item("accel_calm", s.accel_calm)?;
        d.set_item("accel_drift", s.accel_drift)?;
        d.set_item("mag_held", <[f64; 3]>::from(s.mag_hold.field))?;
        d.set_item("mag_held_s", s.mag_hold.age_s)?;
        d.set_item("world", s.world.map(World::name))?;
        d.set_item("extra", self.extra.clone())?;
        Ok(d)
    }

    fn __getnewargs_ex__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        Ok((PyTuple::empty(py), self.fields(py)?))
    }

    /// Attitude `q_wb` as `[x, y, z, w]`.
    #[getter]
    fn quaternion<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.q.coords.as_slice())
    }

    /// Gyro-bias estimate [rad/s].
    #[getter]
    fn gyro_bias<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.bias.as_slice())
    }

    /// Whether the attitude has been initialised.
    #[getter]
    fn initialized(&self) -> bool {
        self.common.initialized
    }

    /// Time of the last sample [s].
    #[getter]
    fn time(&self) -> f64 {
        self.common.time
    }

    /// Seconds since start-up or the last recovery (drives the gain ramp).
    #[getter]
    fn ramp_elapsed(&self) -> f64 {
        self.common.ramp_elapsed
    }

    /// Seconds of uninterrupted accelerometer rejection.
    #[getter]
    fn accel_rejected(&self) -> f64 {
        self.common.accel_rejected
    }

    /// Seconds of uninterrupted magnetometer rejection.
    #[getter]
    fn mag_rejected(&self) -> f64 {
        self.common.mag_rejected
    }

    /// Seconds the rest thresholds have held.
    #[getter]
    fn rest(&self) -> f64 {
        self.common.rest
    }

    /// Reference field norm `m₀` (0: not learned yet).
    #[getter]
    fn mag_norm(&self) -> f64 {
        self.common.mag_norm
    }

    /// `sin δ₀` of the reference dip angle.
    #[getter]
    fn mag_dip_sin(&self) -> f64 {
        self.common.mag_dip_sin
    }

    /// `cos δ₀` of the reference dip angle.
    #[getter]
    fn mag_dip_cos(&self) -> f64 {
        self.common.mag_dip_cos
    }

    /// First stage of the accelerometer low pass, body axes [m/s²].
    #[getter]
    fn acc_lp1<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.acc_lp1.as_slice())
    }

    /// The filtered specific force the law sees, body axes [m/s²].
    #[getter]
    fn acc_lp2<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.acc_lp2.as_slice())
    }

    /// The gyro low pass of rest detection, body axes [rad/s].
    #[getter]
    fn gyro_lp<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.gyro_lp.as_slice())
    }

    /// Rest detection's mean square of the gyro's deviation [rad²/s²].
    #[getter]
    fn rest_gyro_ms(&self) -> f64 {
        self.common.rest_gyro_ms
    }

    /// The accelerometer low pass of rest detection, body axes [m/s²].
    #[getter]
    fn rest_accel_lp<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.rest_accel_lp.as_slice())
    }

    /// Rest detection's mean square of `‖a − ā‖` [m²/s⁴].
    #[getter]
    fn rest_accel_ms(&self) -> f64 {
        self.common.rest_accel_ms
    }

    /// Seconds the filtered specific force's norm has stayed near gravity.
    #[getter]
    fn accel_calm(&self) -> f64 {
        self.common.accel_calm
    }

    /// Whether the accelerometer's angle test is off for a drift.
    #[getter]
    fn accel_drift(&self) -> bool {
        self.common.accel_drift
    }

    /// The last streamed field sample in the last sample's body axes (zero: none).
    #[getter]
    fn mag_held<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.common.mag_hold.field.as_slice())
    }

    /// Seconds since that field sample.
    #[getter]
    fn mag_held_s(&self) -> f64 {
        self.common.mag_hold.age_s
    }

    /// The world the attitude is in (`"ENU"` / `"NED"`; None: that of the filter that takes it).
    #[getter]
    fn world(&self) -> Option<&'static str> {
        self.common.world.map(World::name)
    }

    /// The law's own state by field name (empty for Mahony and Madgwick).
    #[getter]
    fn extra(&self) -> Vec<(String, f64)> {
        self.extra.clone()
    }
}

/// One streaming sample through `filter`; the new state.
fn update<L: Law>(
    py: Python<'_>,
    filter: &Filter<L>,
    state: &PyFilterState,
    gyro: [f64; 3],
    accel: [f64; 3],
    dt: f64,
    mag: Option<[f64; 3]>,
) -> PyResult<PyFilterState> {
    let mut s = state.typed::<L>();
    let mag = mag.map(Vector3::from);
    filter
        .update(&mut s, &Vector3::from(gyro), &Vector3::from(accel), mag.as_ref(), dt)
        .map_err(|e| to_py(py, "gyro / accel / dt / state", e))?;
    Ok(PyFilterState::of(&s))
}

/// The batch outputs: `(q (n, 4) xyzw, bias (n, 3), final state)`.
type Outputs<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>, PyFilterState);

/// A batch run through `filter`, GIL released.
#[allow(clippy::too_many_arguments)] // the arrays of a run, the start state and how to start
fn run<'py, L: Law>(
    py: Python<'py>,
    filter: &Filter<L>,
    t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    mag: Option<PyReadonlyArray2<'py, f64>>,
    state: &PyFilterState,
    continued: bool,
) -> PyResult<Outputs<'py>> {
    let mut s = state.typed::<L>();
    let n = t.shape()[0];
    let record = FilterRecord::new(py, SampleCopies::new(py, &t, &gyro, &accel)?, mag.as_ref())?;
    let inputs = record.inputs(py)?;
    // Every row is written (one per sample) or the call fails. The demand is both outputs': seven
    // values a sample.
    let demand = Demand::of("imu", "samples", &[n, 7]);
    let (out_q, out_b) = (empty(py, &demand, [n, 4])?, empty(py, &demand, [n, 3])?);
    {
        let mut gq = out_q.readwrite();
        let mut gb = out_b.readwrite();
        let (sq, sb) = (
            gq.as_slice_mut()?.as_chunks_mut().0,
            gb.as_slice_mut()?.as_chunks_mut().0,
        );
        let state = &mut s;
        let fresh = [Fresh::of(sq), Fresh::of(sb)];
        crate::threads::prefaulting(n, &fresh, || {
            crate::threads::interruptible(py, n, |cancel| {
                filter.run_cancellable(state, &inputs, continued, (sq, sb), cancel)
            })
        })?
        .map_err(|e| to_py(py, "imu / gains", e))?;
    }
    Ok((out_q, out_b, PyFilterState::of(&s)))
}

/// A filter pyclass for one law: `Name(gains, options)`, `update`, `run`, pickling. Adding a law
/// to the bindings is its gains' [`value_class!`] and one line here.
macro_rules! filter_class {
    ($py:ident = $law:ident as $name:literal, gains $gains:ident) => {
        #[doc = concat!("A configured `imukit::filters::Filter<", stringify!($law), ">` (no state).")]
        #[pyclass(name = $name, module = "imukit._core", frozen)]
        pub(crate) struct $py {
            inner: Filter<$law>,
            gains: $gains,
            options: PyFilterOptions,
        }

        #[pymethods]
        impl $py {
            #[new]
            fn new(py: Python<'_>, gains: $gains, options: PyFilterOptions) -> PyResult<Self> {
                let inner = Filter::new(gains.into(), options.options()).map_err(|e| to_py(py, "options", e))?;
                Ok(Self {
                    inner,
                    gains,
                    options,
                })
            }

            fn __getnewargs__(&self) -> ($gains, PyFilterOptions) {
                (self.gains, self.options.clone())
            }

            /// One streaming sample; returns the new state.
            #[pyo3(signature = (state, gyro, accel, dt, mag=None))]
            fn update(
                &self,
                py: Python<'_>,
                state: PyRef<'_, PyFilterState>,
                gyro: [f64; 3],
                accel: [f64; 3],
                dt: f64,
                mag: Option<[f64; 3]>,
            ) -> PyResult<PyFilterState> {
                update(py, &self.inner, &state, gyro, accel, dt, mag)
            }

            /// Batch run, GIL released: `(q (n, 4) xyzw, bias (n, 3), final state)`.
            #[pyo3(signature = (t, gyro, accel, mag, state, continued))]
            #[allow(clippy::too_many_arguments)] // the arrays of a run, the start state and how to start
            fn run<'py>(
                &self,
                py: Python<'py>,
                t: PyReadonlyArray1<'py, f64>,
                gyro: PyReadonlyArray2<'py, f64>,
                accel: PyReadonlyArray2<'py, f64>,
                mag: Option<PyReadonlyArray2<'py, f64>>,
                state: PyRef<'py, PyFilterState>,
                continued: bool,
            ) -> PyResult<Outputs<'py>> {
                run(py, &self.inner, t, gyro, accel, mag, &state, continued)
            }
        }
    };
}

filter_class!(PyMahonyFilter = Mahony as "MahonyFilter", gains PyMahonyGains);
filter_class!(PyMadgwickFilter = Madgwick as "MadgwickFilter", gains PyMadgwickGains);
