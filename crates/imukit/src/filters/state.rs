//! The state of a filter: [`CommonState`] (attitude, bias, clock, gate and rest counters: what the
//! shared step owns) and the law's own [`Law::Extra`], together a plain `Copy` [`State`]: save by
//! copying, restore by assigning.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::{Law, World};
use crate::quat::exp_step;

/// The part of the state every law has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommonState {
    /// Attitude `q_wb` in the chosen world frame.
    pub q: UnitQuaternion<f64>,
    /// The world `q` is in: a filter of the other world turns it into its own before the next
    /// sample. `None` (a state stored without it): the world of the filter that takes it.
    pub world: Option<World>,
    /// Gyro-bias estimate [rad/s], subtracted from the gyro.
    pub bias: Vector3<f64>,
    /// False until the first sample has initialised the attitude.
    pub initialized: bool,
    /// Time of the last sample \[s\] (batch: its timestamp; streaming: the sum of the `dt`s).
    pub time: f64,
    /// Seconds since start-up or the last recovery (drives the gain ramp).
    pub ramp_elapsed: f64,
    /// Seconds of uninterrupted accelerometer rejection.
    pub accel_rejected: f64,
    /// Seconds the filtered specific force's norm has stayed near gravity (see [`super::AccelRejection`]).
    pub accel_calm: f64,
    /// The angle test is off until the estimate is back within its angle (a drift, not an acceleration).
    pub accel_drift: bool,
    /// Seconds of uninterrupted magnetometer rejection.
    pub mag_rejected: f64,
    /// Seconds the rest thresholds have held.
    pub rest: f64,
    /// Reference field norm `m₀` (0: not learned yet).
    pub mag_norm: f64,
    /// `sin δ₀` of the reference dip angle.
    pub mag_dip_sin: f64,
    /// `cos δ₀` of the reference dip angle (≥ 0).
    pub mag_dip_cos: f64,
    /// First stage of the accelerometer low pass, body axes [m/s²] (zero: not started).
    pub acc_lp1: Vector3<f64>,
    /// Second stage, the filtered specific force the law sees [m/s²] (zero: not started).
    pub acc_lp2: Vector3<f64>,
    /// Low pass of the gyro for rest detection, `ω̄` [rad/s].
    pub gyro_lp: Vector3<f64>,
    /// Rest detection's mean square of `‖ω − ω̄‖` [rad²/s²].
    pub rest_gyro_ms: f64,
    /// Low pass of the accelerometer for rest detection, body axes, `ā` [m/s²].
    pub rest_accel_lp: Vector3<f64>,
    /// Rest detection's mean square of `‖a − ā‖` [m²/s⁴].
    pub rest_accel_ms: f64,
    /// The last field sample of a streamed run, for the samples after it without one.
    pub mag_hold: FieldHold,
}

/// The last field sample of a streamed run, in the body axes of the last sample: on a sample
/// without a field it stands in, turned into that sample's axes by its bias-corrected gyro step,
/// while it is at most the filter's `mag_hold_s` old (default [`super::MAG_HOLD_S`]; 0: never). A field slower than the gyro then corrects the
/// heading at the rate of one on every sample (a correction is a rate: on its own samples only, a
/// 10 Hz field beside a 100 Hz gyro had a tenth of the gain) and its gate counts seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FieldHold {
    /// The field in the last sample's body axes (zero: none).
    pub field: Vector3<f64>,
    /// Seconds since it was sampled.
    pub age_s: f64,
}

impl FieldHold {
    /// Holds `mag` (a field sample, or none), sampled now.
    pub fn keep(&mut self, mag: Option<&Vector3<f64>>) {
        self.field = mag.copied().unwrap_or_else(Vector3::zeros);
        self.age_s = 0.0;
    }

    /// The held field on a sample without one, `dt` \[s\] after the last, the body having turned
    /// by `turn = (ω − b̂) dt` \[rad\]; None when there is none or it grew older than `limit_s`.
    pub fn next(&mut self, turn: &Vector3<f64>, dt: f64, limit_s: f64) -> Option<Vector3<f64>> {
        if self.field == Vector3::zeros() {
            return None;
        }
        self.age_s += dt;
        if self.age_s > limit_s {
            self.field = Vector3::zeros();
            return None;
        }
        self.field = exp_step(turn).inverse_transform_vector(&self.field);
        Some(self.field)
    }

    /// The field a streamed sample uses: `mag` when it has one (then held), else the held one
    /// turned by the body's `turn = (ω − b̂) dt` \[rad\] over `dt` \[s\] ([`FieldHold::next`]) once
    /// the filter is `initialized`.
    pub fn for_sample(
        &mut self,
        mag: Option<&Vector3<f64>>,
        initialized: bool,
        turn: &Vector3<f64>,
        dt: f64,
        limit_s: f64,
    ) -> Option<Vector3<f64>> {
        match mag {
            Some(m) => {
                self.keep(Some(m));
                Some(*m)
            }
            None if initialized => self.next(turn, dt, limit_s),
            None => None,
        }
    }

    /// After a batch run over `mags` (None: 6D) that ended with `result` (errors name the row in
    /// the record whose first row is `first`): the field of the last row the state has taken
    /// (none taken: the state's own hold stays).
    pub fn after_run<T>(&mut self, mags: Option<&[[f64; 3]]>, rows: usize, first: usize, result: &crate::Result<T>) {
        let done = result
            .as_ref()
            .err()
            .map_or(rows, |e| e.index().map_or(0, |k| k.saturating_sub(first)));
        if let Some(k) = done.checked_sub(1) {
            self.keep(mags.map(|m| Vector3::from(m[k])).as_ref());
        }
    }

    /// Finite, its age ≥ 0, with a squared norm that does not overflow (a held field is used as
    /// a field).
    pub fn valid(&self) -> bool {
        self.age_s >= 0.0 && self.age_s.is_finite() && self.field.norm_squared().is_finite()
    }
}

impl Default for CommonState {
    fn default() -> Self {
        Self {
            q: UnitQuaternion::identity(),
            world: None,
            bias: Vector3::zeros(),
            initialized: false,
            time: 0.0,
            ramp_elapsed: 0.0,
            accel_rejected: 0.0,
            accel_calm: 0.0,
            accel_drift: false,
            mag_rejected: 0.0,
            rest: 0.0,
            mag_norm: 0.0,
            mag_dip_sin: 0.0,
            mag_dip_cos: 1.0,
            acc_lp1: Vector3::zeros(),
            acc_lp2: Vector3::zeros(),
            gyro_lp: Vector3::zeros(),
            rest_gyro_ms: 0.0,
            rest_accel_lp: Vector3::zeros(),
            rest_accel_ms: 0.0,
            mag_hold: FieldHold::default(),
        }
    }
}

impl CommonState {
    /// A state already initialised at attitude `q` with bias `bias`, at `time`.
    pub fn at(q: UnitQuaternion<f64>, bias: Vector3<f64>, time: f64) -> Self {
        Self {
            q,
            bias,
            initialized: true,
            time,
            ..Self::default()
        }
    }

    /// Checks a state built from stored values: every number finite, and the quaternion `xyzw`
    /// unit (one within 1e-12 of unit is kept bit for bit, so a saved state restores exactly;
    /// another is normalised, a zero one refused). Errors name the argument `state`.
    pub fn restored(mut self, xyzw: [f64; 4]) -> crate::Result<Self> {
        let scalars = [
            self.time,
            self.ramp_elapsed,
            self.accel_rejected,
            self.accel_calm,
            self.mag_rejected,
            self.rest,
            self.mag_norm,
            self.mag_dip_sin,
            self.mag_dip_cos,
            self.rest_gyro_ms,
            self.rest_accel_ms,
            self.mag_hold.age_s,
        ];
        let finite = xyzw
            .iter()
            .chain(self.bias.iter())
            .chain(self.acc_lp1.iter())
            .chain(self.acc_lp2.iter())
            .chain(self.gyro_lp.iter())
            .chain(self.rest_accel_lp.iter())
            .chain(self.mag_hold.field.iter())
            .chain(&scalars)
            .all(|x| x.is_finite());
        if !finite {
            return Err(crate::Error::NonFinite { index: 0 }.in_argument("state"));
        }
        if self.mag_hold.age_s < 0.0 {
            return Err(crate::Error::Parameter {
                name: "state",
                expected: "a held field's age mag_held_s ≥ 0",
                got: format!("{}", self.mag_hold.age_s),
            });
        }
        // As `update` refuses a field whose squared norm overflows: the held one is used as a field.
        if !self.mag_hold.valid() {
            return Err(crate::Error::Overflow { index: 0 }.in_argument("state"));
        }
        let raw = Quaternion::new(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
        self.q = if (raw.norm_squared() - 1.0).abs() < 1e-12 {
            UnitQuaternion::new_unchecked(raw)
        } else {
            crate::quat::normalize(&raw).map_err(|e| e.in_argument("state"))?
        };
        Ok(self)
    }

    /// This state as the filter of `world` continues it: the attitude turned into `world` when
    /// the state says it is in the other one.
    pub fn express_in(&mut self, world: World) {
        if let Some(from) = self.world {
            self.q = world.attitude_in(from, &self.q);
        }
        self.world = Some(world);
    }
}

/// The complete state of a filter with law `L`.
pub struct State<L: Law> {
    /// What every law has.
    pub common: CommonState,
    /// The law's own state.
    pub extra: L::Extra,
}

impl<L: Law> State<L> {
    /// A state already initialised at attitude `q` with bias `bias`, at `time` (the law's own
    /// state at its default).
    pub fn at(q: UnitQuaternion<f64>, bias: Vector3<f64>, time: f64) -> Self {
        Self::from(CommonState::at(q, bias, time))
    }
}

impl<L: Law> From<CommonState> for State<L> {
    /// `common` with the law's own state at its default.
    fn from(common: CommonState) -> Self {
        Self {
            common,
            extra: L::Extra::default(),
        }
    }
}

// By hand: a derive would ask `L` itself (not only `L::Extra`) to be Copy, Default, ...
impl<L: Law> Clone for State<L> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<L: Law> Copy for State<L> {}
impl<L: Law> Default for State<L> {
    fn default() -> Self {
        Self::from(CommonState::default())
    }
}
impl<L: Law> PartialEq for State<L> {
    fn eq(&self, other: &Self) -> bool {
        self.common == other.common && self.extra == other.extra
    }
}
impl<L: Law> std::fmt::Debug for State<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("State")
            .field("common", &self.common)
            .field("extra", &self.extra)
            .finish()
    }
}

/// A law's own state as named numbers: how bindings show, store and restore it, exactly.
pub trait Fields: Sized {
    /// The names, in the order of [`Fields::values`].
    const NAMES: &'static [&'static str];
    /// The values, in the order of [`Fields::NAMES`].
    fn values(&self) -> Vec<f64>;
    /// Back from [`Fields::values`]; None when `values` has the wrong length.
    fn from_values(values: &[f64]) -> Option<Self>;
}

/// No state of its own (Mahony, Madgwick: their bias is the common one).
impl Fields for () {
    const NAMES: &'static [&'static str] = &[];

    fn values(&self) -> Vec<f64> {
        Vec::new()
    }

    fn from_values(values: &[f64]) -> Option<Self> {
        values.is_empty().then_some(())
    }
}
