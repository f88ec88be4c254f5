//! The options every law shares: the start-up gain ramp, the accelerometer and magnetometer
//! gates ([`super::gate`]) and rest detection, each with its `Default` (the only place a default
//! is written: the Python bindings read them from here). Field names carry their unit where it is
//! not the quantity's SI unit by context (`_s`, `_rad`, `_fraction`); errors name an option as
//! `<option>.<quantity>` (`acc_rejection.angle`), the spelling the messages have always had.

use super::world::World;

/// Start-up gain ramp: for `elapsed < duration_s` the correction gain is
/// `nominal · (1 + (factor − 1)(1 − elapsed/duration_s))` (linear from `factor · nominal` down to
/// `nominal`); rejection is suspended and Mahony's integral term frozen meanwhile. A recovery
/// (see [`AccelRejection`]) restarts the ramp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainRamp {
    /// Ramp length \[s\]; 0 disables the ramp.
    pub duration_s: f64,
    /// Gain multiplier at the start (≥ 1).
    pub factor: f64,
}

impl Default for GainRamp {
    fn default() -> Self {
        Self {
            duration_s: 3.0,
            factor: 10.0,
        }
    }
}

/// Acceleration rejection: the accelerometer correction of a sample is skipped when
/// `|‖a‖ − g| > norm` [m/s²] (the raw sample), when the vector the law uses (the low-passed `f`
/// with [`AccelLowPass`], else the raw sample) has `|‖f‖ − g| > filtered_norm` [m/s²], or when the
/// angle between it and the predicted gravity direction exceeds `angle_rad`. After `recovery_s`
/// seconds of uninterrupted rejection the gain ramp is restarted (high gain, no rejection for the
/// ramp's duration; with no ramp, the one sample is accepted) and the counter reset.
///
/// Drift: an angle beyond `angle_rad` is either an acceleration lasting longer than the low pass
/// or the estimate drifting on an unestimated gyro bias. An acceleration `p̈` held against
/// gravity raises `‖f‖` to `√(g² + p̈²)` (5 m/s²: +1.2 m/s²) while the low pass turns; a drift
/// leaves `‖f‖ = g` (the low pass only rotates). So when the samples have been rejected for
/// `drift_s` seconds while `‖f‖` stayed within `filtered_norm` of `g` for as long, the angle test
/// is switched off until the estimate is back within `angle_rad`: the law corrects the drift (and
/// Mahony's integral learns the bias) instead of running on the gyro until the recovery.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelRejection {
    /// Threshold on `|‖a‖ − g|` of the raw sample [m/s²].
    pub norm: f64,
    /// Threshold on the angle between measured and predicted up \[rad\].
    pub angle_rad: f64,
    /// Continuous rejection time after which the filter recovers \[s\].
    pub recovery_s: f64,
    /// Threshold on `|‖f‖ − g|` of the vector the law uses [m/s²].
    pub filtered_norm: f64,
    /// Rejection time with `‖f‖` near `g` after which an angle beyond `angle_rad` is taken for a drift \[s\].
    pub drift_s: f64,
}

impl Default for AccelRejection {
    /// 2 m/s², 3°, 15 s, 0.3 m/s², 2 s: with [`AccelLowPass`] the angle is that of the filtered
    /// vector, so 3° rarely fires on handheld motion, while the raw norm test and the angle catch a
    /// sustained acceleration, held for up to 15 s; the filtered norm stays within 0.3 m/s² of g
    /// on every BROAD trial but the fast translation (99th percentile 0.47 m/s² there) and on
    /// EuRoC's MAV (0.29 m/s²), and leaves it 1 s into a 5 m/s² acceleration (`docs/filters.md`).
    fn default() -> Self {
        Self {
            norm: 2.0,
            angle_rad: 3f64.to_radians(),
            recovery_s: 15.0,
            filtered_norm: 0.3,
            drift_s: 2.0,
        }
    }
}

/// Low-pass pre-filter of the accelerometer in an almost-inertial frame (Laidig & Seel, "VQF:
/// Highly accurate IMU orientation estimation with bias estimation and magnetic disturbance
/// rejection", Information Fusion 91, 2023, §IV-B): the specific force `a = R_ibᵀ (p̈_i + g u_i)`
/// is a body-frame vector; in a frame `I` that only turns with the gyro its linear part
/// `R_ib a − g u_i = p̈_i` integrates to a velocity change, which stays bounded while gravity
/// accumulates, so a low pass in `I` keeps gravity and cancels accelerations that come and go.
///
/// Carried in body axes: before the step the filtered vectors are turned by the gyro increment
/// (`f ← Exp((ω − b̂) dt)ᵀ f`; the correction `ω_c` is the estimate's, not the body's, turn) and
/// pulled towards the new sample by two first-order stages, `f₁ ← f₁ + α (a − f₁)`,
/// `f₂ ← f₂ + α (f₁ − f₂)`, `α = dt / (tau_s + dt)` (a critically damped second-order low
/// pass). The law and the accelerometer gate see `f₂` instead of `a`; rest detection keeps the
/// raw sample. An acceleration `p̈` of frequency `f` reaches the estimate attenuated by
/// `1 / (1 + (2π f tau_s)²)`, and a gyro-bias error `δb` tilts the filtered vector by about
/// `2 tau_s δb` (its lag).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelLowPass {
    /// Time constant of each of the two stages \[s\].
    pub tau_s: f64,
}

impl Default for AccelLowPass {
    /// 1 s: tuned on the 12 BROAD trials with leave-one-group-out validation
    /// (`bench/tune_filters.py`, `docs/filters_accuracy.md`).
    fn default() -> Self {
        Self { tau_s: 1.0 }
    }
}

/// Magnetic rejection (9D): the magnetometer correction is skipped when
/// `|‖m‖ − m₀| > norm_fraction · m₀` or `|δ − δ₀| > dip_rad` (tested as `cos(δ − δ₀) < cos(dip_rad)`,
/// no inverse sine) with `m₀`, `δ₀` the field norm and dip angle learned at the first
/// magnetometer sample (dip δ = angle of the field below the horizontal, measured with the current
/// estimate). After `recovery_s` seconds of uninterrupted rejection the reference is re-learned
/// from the current sample, which is then used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagRejection {
    /// Relative threshold on the field norm (fraction of `m₀`).
    pub norm_fraction: f64,
    /// Threshold on the dip-angle change \[rad\].
    pub dip_rad: f64,
    /// Continuous rejection time after which the reference is re-learned \[s\].
    pub recovery_s: f64,
}

impl Default for MagRejection {
    fn default() -> Self {
        Self {
            norm_fraction: 0.1,
            dip_rad: 10f64.to_radians(),
            recovery_s: 10.0,
        }
    }
}

/// Rest detection (after Laidig & Seel 2023, §IV-D): the sensor is at rest once, for
/// `duration_s` seconds, the gyro has been steady, `⟨‖ω − ω̄‖²⟩ < gyro²` with `ω̄` the gyro's
/// first-order low pass and `⟨·⟩` a first-order low pass of the squared deviation (both with
/// time constant `tau_s`), slow, `‖ω̄‖ < max_bias` [rad/s], and the accelerometer near gravity,
/// `⟨(‖a‖ − g)²⟩ < accel²`. While at rest the bias estimate follows the raw gyro through a
/// first-order low pass, `b ← b + min(dt/tau_s, 1)(ω − b)`. The tests are on deviations, not on
/// `‖ω‖`, so that a gyro bias larger than the threshold (0.08 rad/s on the EuRoC MAV's) is still
/// found, and on mean squares, so that one vibration spike (a MAV's idling rotors) does not
/// restart the clock; `max_bias` keeps a slow steady turn from being taken for a bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestDetection {
    /// Threshold on the rms deviation of the gyro from its low pass [rad/s].
    pub gyro: f64,
    /// Threshold on the rms of `‖a‖ − g` [m/s²].
    pub accel: f64,
    /// Time the thresholds must hold \[s\].
    pub duration_s: f64,
    /// Time constant of the low passes of the tests and of the bias at rest \[s\].
    pub tau_s: f64,
    /// Largest `‖ω̄‖` taken for a bias [rad/s].
    pub max_bias: f64,
}

impl Default for RestDetection {
    fn default() -> Self {
        Self {
            gyro: 0.05,
            accel: 1.0,
            duration_s: 1.0,
            tau_s: 1.0,
            max_bias: 0.1,
        }
    }
}

impl GainRamp {
    /// Checks the fields for their domain (errors name `gain_ramp.<field>`).
    pub fn validate(&self) -> crate::Result<()> {
        check("gain_ramp.duration_s", self.duration_s, "finite and ≥ 0", |x| {
            x >= 0.0
        })?;
        check("gain_ramp.factor", self.factor, "finite and ≥ 1", |x| x >= 1.0)
    }
}

impl AccelLowPass {
    /// Checks the time constant for its domain.
    pub fn validate(&self) -> crate::Result<()> {
        check("acc_lowpass.tau_s", self.tau_s, "finite and > 0", |x| x > 0.0)
    }
}

impl AccelRejection {
    /// Checks the fields for their domain (errors name `acc_rejection.<field>`).
    pub fn validate(&self) -> crate::Result<()> {
        check("acc_rejection.norm", self.norm, "finite and > 0", |x| x > 0.0)?;
        check("acc_rejection.angle_rad", self.angle_rad, "in (0, π]", |x| {
            x > 0.0 && x <= std::f64::consts::PI
        })?;
        check("acc_rejection.recovery_s", self.recovery_s, "finite and > 0", |x| {
            x > 0.0
        })?;
        check(
            "acc_rejection.filtered_norm",
            self.filtered_norm,
            "finite and > 0",
            |x| x > 0.0,
        )?;
        check("acc_rejection.drift_s", self.drift_s, "finite and > 0", |x| x > 0.0)
    }
}

impl MagRejection {
    /// Checks the fields for their domain (errors name `mag_rejection.<field>`).
    pub fn validate(&self) -> crate::Result<()> {
        check(
            "mag_rejection.norm_fraction",
            self.norm_fraction,
            "finite and > 0",
            |x| x > 0.0,
        )?;
        check("mag_rejection.dip_rad", self.dip_rad, "finite and > 0", |x| x > 0.0)?;
        check("mag_rejection.recovery_s", self.recovery_s, "finite and > 0", |x| {
            x > 0.0
        })
    }
}

impl RestDetection {
    /// Checks the fields for their domain (errors name `rest_detection.<field>`).
    pub fn validate(&self) -> crate::Result<()> {
        check("rest_detection.gyro", self.gyro, "finite and > 0", |x| x > 0.0)?;
        check("rest_detection.accel", self.accel, "finite and > 0", |x| x > 0.0)?;
        check("rest_detection.duration_s", self.duration_s, "finite and ≥ 0", |x| {
            x >= 0.0
        })?;
        check("rest_detection.tau_s", self.tau_s, "finite and > 0", |x| x > 0.0)?;
        check("rest_detection.max_bias", self.max_bias, "finite and > 0", |x| x > 0.0)
    }
}

/// Options shared by every law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// World frame of the estimate.
    pub world: World,
    /// Gravity magnitude [m/s²] used by the rejection and rest tests (default: that of
    /// [`crate::imu::GRAVITY`]).
    pub gravity: f64,
    /// Start-up gain ramp.
    pub gain_ramp: GainRamp,
    /// Accelerometer low pass in the gyro frame; None: each raw sample is used as is (the
    /// textbook laws).
    pub acc_lowpass: Option<AccelLowPass>,
    /// Acceleration rejection; None: every accelerometer sample is used.
    pub acc_rejection: Option<AccelRejection>,
    /// Magnetic rejection; None: every magnetometer sample is used.
    pub mag_rejection: Option<MagRejection>,
    /// Rest detection with bias update; None: off (the bias then changes only through the law).
    pub rest_detection: Option<RestDetection>,
    /// Streaming: a field sample stands in, turned by the gyro, for the samples without one up
    /// to this long after it \[s\] ([`super::FieldHold`]); 0: never.
    pub mag_hold_s: f64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            world: World::Enu,
            gravity: crate::imu::GRAVITY[2].abs(),
            gain_ramp: GainRamp::default(),
            acc_lowpass: Some(AccelLowPass::default()),
            acc_rejection: Some(AccelRejection::default()),
            mag_rejection: Some(MagRejection::default()),
            rest_detection: Some(RestDetection::default()),
            mag_hold_s: super::MAG_HOLD_S,
        }
    }
}

impl Options {
    /// Checks every option for its domain.
    pub fn validate(&self) -> crate::Result<()> {
        check("gravity", self.gravity, "a positive finite number", |x| x > 0.0)?;
        check("mag_hold_s", self.mag_hold_s, "finite and ≥ 0", |x| x >= 0.0)?;
        self.gain_ramp.validate()?;
        self.acc_lowpass.as_ref().map_or(Ok(()), AccelLowPass::validate)?;
        self.acc_rejection.as_ref().map_or(Ok(()), AccelRejection::validate)?;
        self.mag_rejection.as_ref().map_or(Ok(()), MagRejection::validate)?;
        self.rest_detection.as_ref().map_or(Ok(()), RestDetection::validate)
    }

    /// The ramp multiplier at `elapsed` seconds since start (or recovery).
    #[inline]
    pub(crate) fn ramp_gain(&self, elapsed: f64) -> f64 {
        let ramp = &self.gain_ramp;
        if elapsed < ramp.duration_s {
            1.0 + (ramp.factor - 1.0) * (1.0 - elapsed / ramp.duration_s)
        } else {
            1.0
        }
    }
}

/// `Ok` when `x` is finite and `ok(x)`, else a [`crate::Error::Parameter`] naming `name`: the one
/// domain check of every option and gain.
pub fn check(name: &'static str, x: f64, expected: &'static str, ok: impl Fn(f64) -> bool) -> crate::Result<()> {
    if x.is_finite() && ok(x) {
        Ok(())
    } else {
        Err(crate::Error::Parameter {
            name,
            expected,
            got: format!("{x}"),
        })
    }
}
