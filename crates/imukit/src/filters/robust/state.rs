//! The state of [`super::Robust`]: a plain `Copy` struct (save by copying, restore by
//! assigning), flattened to named numbers by [`Fields`] for the bindings (exact round trip).
//! Attitudes are internal ENU (the world conversion is applied at the output only).

use nalgebra::{Matrix2x3, Matrix3, Quaternion, SMatrix, UnitQuaternion, Vector2, Vector3};

use std::f64::consts::{PI, TAU};

use crate::filters::{FieldHold, Fields};

/// A value that flattens to numbers: how the state macro stores each field.
trait Flat: Sized {
    fn push(&self, out: &mut Vec<f64>);
    fn take(it: &mut impl Iterator<Item = f64>) -> Option<Self>;
}

impl Flat for f64 {
    fn push(&self, out: &mut Vec<f64>) {
        out.push(*self);
    }
    fn take(it: &mut impl Iterator<Item = f64>) -> Option<Self> {
        it.next()
    }
}

impl Flat for bool {
    fn push(&self, out: &mut Vec<f64>) {
        out.push(f64::from(u8::from(*self)));
    }
    fn take(it: &mut impl Iterator<Item = f64>) -> Option<Self> {
        it.next().map(|x| x != 0.0)
    }
}

impl<const R: usize, const C: usize> Flat for SMatrix<f64, R, C> {
    fn push(&self, out: &mut Vec<f64>) {
        out.extend(self.iter());
    }
    fn take(it: &mut impl Iterator<Item = f64>) -> Option<Self> {
        let mut m = Self::zeros();
        for x in m.iter_mut() {
            *x = it.next()?;
        }
        Some(m)
    }
}

/// `[x, y, z, w]`, kept bit for bit (checked by [`RobustState::restored`]).
impl Flat for UnitQuaternion<f64> {
    fn push(&self, out: &mut Vec<f64>) {
        out.extend(self.coords.iter());
    }
    fn take(it: &mut impl Iterator<Item = f64>) -> Option<Self> {
        let (x, y, z, w) = (it.next()?, it.next()?, it.next()?, it.next()?);
        Some(Self::new_unchecked(Quaternion::new(w, x, y, z)))
    }
}

/// The held field, then its age.
impl Flat for FieldHold {
    fn push(&self, out: &mut Vec<f64>) {
        Flat::push(&self.field, out);
        out.push(self.age_s);
    }
    fn take(it: &mut impl Iterator<Item = f64>) -> Option<Self> {
        Some(Self {
            field: Flat::take(it)?,
            age_s: it.next()?,
        })
    }
}

macro_rules! state {
    ($($(#[$doc:meta])* $field:ident: $ty:ty = [$($name:literal),+]),+ $(,)?) => {
        /// The complete state of [`super::Robust`].
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct RobustState {
            $($(#[$doc])* pub $field: $ty),+
        }

        impl Fields for RobustState {
            const NAMES: &'static [&'static str] = &[$($($name),+),+];

            fn values(&self) -> Vec<f64> {
                let mut out = Vec::with_capacity(Self::NAMES.len());
                $(Flat::push(&self.$field, &mut out);)+
                out
            }

            fn from_values(values: &[f64]) -> Option<Self> {
                let mut it = values.iter().copied();
                let s = Self { $($field: Flat::take(&mut it)?),+ };
                it.next().is_none().then_some(s)
            }
        }
    };
}

state!(
    /// False until the first sample (or an initial attitude) has set the attitude.
    initialized: bool = ["initialized"],
    /// Time of the last sample \[s\].
    time: f64 = ["time"],
    /// The output attitude `q_wb` in the configured world frame (what the last step produced).
    q: UnitQuaternion<f64> = ["qx", "qy", "qz", "qw"],
    /// Strapdown attitude body → almost-inertial frame `I` (gyro only, bias removed).
    q_gyro: UnitQuaternion<f64> = ["q_gyro_x", "q_gyro_y", "q_gyro_z", "q_gyro_w"],
    /// Inclination correction `I` → `E'` (ENU up to heading).
    q_incl: UnitQuaternion<f64> = ["q_incl_x", "q_incl_y", "q_incl_z", "q_incl_w"],
    /// Heading offset `E'` → ENU about the vertical, `Rz(ψ)` as the unit pair `(cos ψ/2, sin ψ/2)`
    /// (the w, z of its quaternion; w ≥ 0, i.e. ψ ∈ [−π, π]): turned by a small rotation each
    /// sample, without trigonometry.
    heading: Vector2<f64> = ["heading_w", "heading_z"],
    /// The same heading ψ \[rad\] as an angle in [−π, π] (equal to `heading`'s to rounding): the
    /// heading error is the field's own angle less ψ, so the loop-carried chain of the heading
    /// filter is a subtraction, a wrap and a multiply-add, with no `atan2` on it.
    heading_angle: f64 = ["heading_angle"],
    /// False until the specific-force low pass has been set to its first input.
    lp_ready: bool = ["lp_ready"],
    /// First delay element of the Butterworth low pass (per axis, frame `I`).
    lp_s1: Vector3<f64> = ["lp_s1_x", "lp_s1_y", "lp_s1_z"],
    /// Second delay element of the Butterworth low pass.
    lp_s2: Vector3<f64> = ["lp_s2_x", "lp_s2_y", "lp_s2_z"],
    /// The step \[s\] the low pass was last advanced with (0: none yet): a much longer or shorter
    /// next step maps its delay elements (`step::Coefs::carry_from`).
    lp_dt: f64 = ["lp_dt"],
    /// Gyro-bias estimate [rad/s].
    bias: Vector3<f64> = ["bias_x", "bias_y", "bias_z"],
    /// Bias covariance [rad²/s²] (column-major).
    bias_cov: Matrix3<f64> = ["p00", "p10", "p20", "p01", "p11", "p21", "p02", "p12", "p22"],
    /// Low-passed gyro of rest detection [rad/s].
    rest_gyro: Vector3<f64> = ["rest_gyro_x", "rest_gyro_y", "rest_gyro_z"],
    /// Low-passed accelerometer of rest detection [m/s²].
    rest_accel: Vector3<f64> = ["rest_accel_x", "rest_accel_y", "rest_accel_z"],
    /// Gyro of rest detection with noise and vibration low-passed off [rad/s].
    rest_gyro_smooth: Vector3<f64> = ["rest_gyro_smooth_x", "rest_gyro_smooth_y", "rest_gyro_smooth_z"],
    /// Accelerometer of rest detection with noise and vibration low-passed off [m/s²].
    rest_accel_smooth: Vector3<f64> = ["rest_accel_smooth_x", "rest_accel_smooth_y", "rest_accel_smooth_z"],
    /// Mean squares of the raw deviations `‖ω − ω̄‖²`, `‖a − ā‖²` (low-passed as `ω̄`).
    rest_ms: Vector2<f64> = ["rest_gyro_ms", "rest_accel_ms"],
    /// Seconds the rest thresholds have held.
    rest_time: f64 = ["rest_time"],
    /// Butterworth delay elements of the rows x, y of `R_E'b` (the correction loop's response to
    /// a bias, see `step::window_sums`).
    loop_rot1: Matrix2x3<f64> = ["lr1_00", "lr1_10", "lr1_01", "lr1_11", "lr1_02", "lr1_12"],
    /// Second delay elements of the same.
    loop_rot2: Matrix2x3<f64> = ["lr2_00", "lr2_10", "lr2_01", "lr2_11", "lr2_02", "lr2_12"],
    /// Butterworth delay elements of `(R_E'b b̂)_{x,y}`.
    loop_bias1: Vector2<f64> = ["lb1_x", "lb1_y"],
    /// Second delay elements of the same.
    loop_bias2: Vector2<f64> = ["lb2_x", "lb2_y"],
    /// The step \[s\] the loop's model was last advanced with, as `lp_dt`.
    loop_dt: f64 = ["loop_dt"],
    /// Heading loop's error driven by row z of `R_E'b` \[s\].
    loop_head_rot: Vector3<f64> = ["lh_x", "lh_y", "lh_z"],
    /// Heading loop's error driven by `(R_E'b b̂)_z` \[rad\].
    loop_head_bias: f64 = ["lh_b"],
    /// Seconds in the current bias window.
    win_time: f64 = ["win_time"],
    /// Sum of the gyro over the current rest segment, `Σ ω dt` \[rad\].
    rest_sum: Vector3<f64> = ["rest_sum_x", "rest_sum_y", "rest_sum_z"],
    /// Seconds in the current rest segment.
    rest_sum_time: f64 = ["rest_sum_time"],
    /// Whether the current still segment has been declared rest.
    rest_segment: bool = ["rest_segment"],
    /// Sum of the corrections over the window (x, y: inclination; z: heading) \[rad\].
    win_corr: Vector3<f64> = ["win_corr_x", "win_corr_y", "win_corr_z"],
    /// Sum of the loops' responses to the rotation, `S` with `C = −S b + O` \[s\].
    win_rot: Matrix3<f64> = ["w00", "w10", "w20", "w01", "w11", "w21", "w02", "w12", "w22"],
    /// Sum of the loops' responses to the estimated bias, `O` \[rad\].
    win_off: Vector3<f64> = ["win_off_x", "win_off_y", "win_off_z"],
    /// Seconds of the window with a heading correction.
    win_mag_time: f64 = ["win_mag_time"],
    /// Whether the reference field has been learned.
    mag_ready: bool = ["mag_ready"],
    /// Reference field norm `m₀`.
    mag_norm: f64 = ["mag_norm"],
    /// Reference dip angle `δ₀` as `(sin δ₀, cos δ₀)`.
    mag_dip: Vector2<f64> = ["mag_dip_sin", "mag_dip_cos"],
    /// Seconds of uninterrupted rejection.
    mag_rejected: f64 = ["mag_rejected"],
    /// Candidate new field: norm.
    cand_norm: f64 = ["cand_norm"],
    /// Candidate new field: dip as `(sin δ, cos δ)`.
    cand_dip: Vector2<f64> = ["cand_dip_sin", "cand_dip_cos"],
    /// Seconds of turning the candidate has held.
    cand_time: f64 = ["cand_time"],
    /// Whether the last sample was at rest.
    rest: bool = ["rest"],
    /// Whether the last magnetometer sample was rejected as disturbed.
    mag_disturbed: bool = ["mag_disturbed"],
    /// True until a field sample has given the heading (from the first sample on, with an
    /// initial attitude too): the first field sample sets it, even one that arrives late.
    heading_pending: bool = ["heading_pending"],
    /// The last streamed field sample, for the samples after it without one ([`FieldHold`]).
    mag_hold: FieldHold = ["mag_held_x", "mag_held_y", "mag_held_z", "mag_held_s"],
);

impl Default for RobustState {
    fn default() -> Self {
        let q = UnitQuaternion::identity();
        Self {
            initialized: false,
            time: 0.0,
            q,
            q_gyro: q,
            q_incl: q,
            heading: Vector2::new(1.0, 0.0),
            heading_angle: 0.0,
            lp_ready: false,
            lp_s1: Vector3::zeros(),
            lp_s2: Vector3::zeros(),
            lp_dt: 0.0,
            bias: Vector3::zeros(),
            bias_cov: Matrix3::zeros(),
            rest_gyro: Vector3::zeros(),
            rest_accel: Vector3::zeros(),
            rest_gyro_smooth: Vector3::zeros(),
            rest_accel_smooth: Vector3::zeros(),
            rest_ms: Vector2::zeros(),
            rest_time: 0.0,
            win_time: 0.0,
            rest_sum: Vector3::zeros(),
            rest_sum_time: 0.0,
            rest_segment: false,
            win_corr: Vector3::zeros(),
            win_rot: Matrix3::zeros(),
            win_off: Vector3::zeros(),
            loop_rot1: Matrix2x3::zeros(),
            loop_rot2: Matrix2x3::zeros(),
            loop_bias1: Vector2::zeros(),
            loop_bias2: Vector2::zeros(),
            loop_dt: 0.0,
            loop_head_rot: Vector3::zeros(),
            loop_head_bias: 0.0,
            win_mag_time: 0.0,
            mag_ready: false,
            mag_norm: 0.0,
            mag_dip: Vector2::zeros(),
            mag_rejected: 0.0,
            cand_norm: 0.0,
            cand_dip: Vector2::zeros(),
            cand_time: 0.0,
            rest: false,
            mag_disturbed: false,
            heading_pending: false,
            mag_hold: FieldHold::default(),
        }
    }
}

impl RobustState {
    /// A state from stored values ([`Fields::values`] order): every number finite and each
    /// quaternion and the heading pair unit within 1e-9, the heading angle in [−π, π] and within
    /// 1e-6 rad of the pair's (then kept bit for bit). Errors name the argument `state`.
    pub fn restored(values: &[f64]) -> crate::Result<Self> {
        let bad = |expected: &'static str| crate::Error::Parameter {
            name: "state",
            expected,
            got: format!("{} values", values.len()),
        };
        if !values.iter().all(|x| x.is_finite()) {
            return Err(crate::Error::NonFinite { index: 0 }.in_argument("state"));
        }
        let s = Self::from_values(values).ok_or_else(|| bad("the fields of a RobustState"))?;
        let unit = |q: &UnitQuaternion<f64>| (q.norm_squared() - 1.0).abs() < 1e-9;
        let unit_heading = (s.heading.norm_squared() - 1.0).abs() < 1e-9;
        // The output turns by the pair and the heading error is taken from the angle: a state
        // edited in one and not the other would hold two headings, the gap never closing.
        let gap = (s.heading_angle - 2.0 * s.heading.y.atan2(s.heading.x) + PI).rem_euclid(TAU) - PI;
        if unit(&s.q)
            && unit(&s.q_gyro)
            && unit(&s.q_incl)
            && unit_heading
            && s.heading_angle.abs() <= PI
            && gap.abs() < 1e-6
            && s.mag_hold.valid()
        {
            Ok(s)
        } else {
            Err(bad(
                "unit quaternions and heading pair, a heading angle in [−π, π] equal to the pair's within 1e-6 rad, a held field whose squared norm is finite",
            ))
        }
    }
}
