//! Parts shared by both filters: world frame, initialisation, gain ramp, rejection, rest detection,
//! and the plain [`State`] that can be saved and restored.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// World frame of the estimate `R_wb`. The vertical axis is z in both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum World {
    /// x east, y north, z up. At rest the accelerometer reads `R_wbᵀ (0, 0, +g)`.
    Enu,
    /// x north, y east, z down. At rest the accelerometer reads `R_wbᵀ (0, 0, −g)`.
    Ned,
}

crate::named_enum!(World, "world", [Enu => "ENU", Ned => "NED"]);

impl World {
    /// The world "up" direction, which a resting accelerometer measures (specific force).
    #[inline]
    pub fn up(self) -> Vector3<f64> {
        match self {
            World::Enu => Vector3::z(),
            World::Ned => -Vector3::z(),
        }
    }

    /// The world direction of (magnetic) north: +y in ENU, +x in NED.
    #[inline]
    pub fn north(self) -> Vector3<f64> {
        match self {
            World::Enu => Vector3::y(),
            World::Ned => Vector3::x(),
        }
    }

    /// World north and up in body axes, `(R_wbᵀ n_w, R_wbᵀ u_w)`: rows of `R(q)`.
    #[inline(always)]
    pub(crate) fn predicted(self, q: &UnitQuaternion<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let (x, y, z, w) = (q.i, q.j, q.k, q.w);
        let row0 = Vector3::new(
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        );
        let row1 = Vector3::new(
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        );
        let row2 = Vector3::new(
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        );
        match self {
            World::Enu => (row1, row2),
            World::Ned => (row0, -row2),
        }
    }

    /// The `R_wb` whose body directions of "up" and "north" are `up_b` and `north_b` (unit,
    /// orthogonal): the rows of `R_wb` are the world axes written in body coordinates.
    fn attitude_from_up_north(self, up_b: &Vector3<f64>, north_b: &Vector3<f64>) -> UnitQuaternion<f64> {
        let (x, y, z) = match self {
            // east = north × up
            World::Enu => (north_b.cross(up_b), *north_b, *up_b),
            // NED: x north, z down, y = z × x
            World::Ned => (*north_b, (-up_b).cross(north_b), -up_b),
        };
        let m = Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
    }
}

/// Start-up gain ramp: for `elapsed < duration` the correction gain is
/// `nominal · (1 + (factor − 1)(1 − elapsed/duration))` (linear from `factor · nominal` down to
/// `nominal`); rejection is suspended and Mahony's integral term frozen meanwhile. A recovery
/// (see [`AccelRejection`]) restarts the ramp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainRamp {
    /// Ramp length [s]; 0 disables the ramp.
    pub duration: f64,
    /// Gain multiplier at the start (≥ 1).
    pub factor: f64,
}

impl Default for GainRamp {
    fn default() -> Self {
        Self {
            duration: 3.0,
            factor: 10.0,
        }
    }
}

/// Acceleration rejection: the accelerometer correction of a sample is skipped when
/// `|‖a‖ − g| > norm` [m/s²] or the angle between the measured and the predicted gravity
/// direction exceeds `angle` [rad]. After `recovery` seconds of uninterrupted rejection the gain
/// ramp is restarted (high gain, no rejection for the ramp's duration; with no ramp, the one
/// sample is accepted) and the counter reset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelRejection {
    /// Threshold on `|‖a‖ − g|` [m/s²].
    pub norm: f64,
    /// Threshold on the angle between measured and predicted up [rad].
    pub angle: f64,
    /// Continuous rejection time after which the filter recovers [s].
    pub recovery: f64,
}

impl Default for AccelRejection {
    fn default() -> Self {
        Self {
            norm: 4.0,
            angle: 30f64.to_radians(),
            recovery: 5.0,
        }
    }
}

/// Magnetic rejection (9D): the magnetometer correction is skipped when `|‖m‖ − m₀| > norm · m₀`
/// or `|δ − δ₀| > dip` (tested as `cos(δ − δ₀) < cos(dip)`, no inverse sine) with `m₀`, `δ₀` the field norm and dip angle learned at the first
/// magnetometer sample (dip δ = angle of the field below the horizontal, measured with the current
/// estimate). After `recovery` seconds of uninterrupted rejection the reference is re-learned
/// from the current sample, which is then used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagRejection {
    /// Relative threshold on the field norm (fraction of `m₀`).
    pub norm: f64,
    /// Threshold on the dip-angle change [rad].
    pub dip: f64,
    /// Continuous rejection time after which the reference is re-learned [s].
    pub recovery: f64,
}

impl Default for MagRejection {
    fn default() -> Self {
        Self {
            norm: 0.1,
            dip: 10f64.to_radians(),
            recovery: 10.0,
        }
    }
}

/// Rest detection: the sensor is at rest once `‖ω‖ < gyro` [rad/s] and `|‖a‖ − g| < accel`
/// [m/s²] have held for `duration` seconds; while at rest the bias estimate follows the raw gyro
/// through a first-order low pass, `b ← b + min(dt/tau, 1)(ω − b)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestDetection {
    /// Gyro-norm threshold [rad/s].
    pub gyro: f64,
    /// Threshold on `|‖a‖ − g|` [m/s²].
    pub accel: f64,
    /// Time the thresholds must hold [s].
    pub duration: f64,
    /// Time constant of the bias low pass at rest [s].
    pub tau: f64,
}

impl Default for RestDetection {
    fn default() -> Self {
        Self {
            gyro: 0.05,
            accel: 0.2,
            duration: 1.0,
            tau: 1.0,
        }
    }
}

/// Options shared by both filters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Common {
    /// World frame of the estimate.
    pub world: World,
    /// Gravity magnitude [m/s²] used by the rejection and rest tests.
    pub gravity: f64,
    /// Start-up gain ramp.
    pub ramp: GainRamp,
    /// Acceleration rejection; None: every accelerometer sample is used.
    pub accel_rejection: Option<AccelRejection>,
    /// Magnetic rejection; None: every magnetometer sample is used.
    pub mag_rejection: Option<MagRejection>,
    /// Rest detection with bias update; None: off.
    pub rest: Option<RestDetection>,
}

impl Default for Common {
    fn default() -> Self {
        Self {
            world: World::Enu,
            gravity: 9.81,
            ramp: GainRamp::default(),
            accel_rejection: Some(AccelRejection::default()),
            mag_rejection: Some(MagRejection::default()),
            rest: None,
        }
    }
}

impl Common {
    /// Checks every option for its domain.
    pub fn validate(&self) -> crate::Result<()> {
        check("gravity", self.gravity, "a positive finite number", |x| x > 0.0)?;
        check("gain_ramp.duration", self.ramp.duration, "finite and ≥ 0", |x| {
            x >= 0.0
        })?;
        check("gain_ramp.factor", self.ramp.factor, "finite and ≥ 1", |x| x >= 1.0)?;
        if let Some(r) = self.accel_rejection {
            check("acc_rejection.norm", r.norm, "finite and > 0", |x| x > 0.0)?;
            check("acc_rejection.angle", r.angle, "in (0, π]", |x| {
                x > 0.0 && x <= std::f64::consts::PI
            })?;
            check("acc_rejection.recovery", r.recovery, "finite and > 0", |x| x > 0.0)?;
        }
        if let Some(r) = self.mag_rejection {
            check("mag_rejection.norm", r.norm, "finite and > 0", |x| x > 0.0)?;
            check("mag_rejection.dip", r.dip, "finite and > 0", |x| x > 0.0)?;
            check("mag_rejection.recovery", r.recovery, "finite and > 0", |x| x > 0.0)?;
        }
        if let Some(r) = self.rest {
            check("rest_detection.gyro", r.gyro, "finite and > 0", |x| x > 0.0)?;
            check("rest_detection.accel", r.accel, "finite and > 0", |x| x > 0.0)?;
            check("rest_detection.duration", r.duration, "finite and ≥ 0", |x| x >= 0.0)?;
            check("rest_detection.tau", r.tau, "finite and > 0", |x| x > 0.0)?;
        }
        Ok(())
    }

    /// The ramp multiplier at `elapsed` seconds since start (or recovery).
    #[inline]
    pub(crate) fn ramp_gain(&self, elapsed: f64) -> f64 {
        if elapsed < self.ramp.duration {
            1.0 + (self.ramp.factor - 1.0) * (1.0 - elapsed / self.ramp.duration)
        } else {
            1.0
        }
    }
}

pub(crate) fn check(name: &'static str, x: f64, expected: &'static str, ok: impl Fn(f64) -> bool) -> crate::Result<()> {
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

/// The complete state of a filter: a plain `Copy` value, so saving is a copy and restoring an
/// assignment. Both filters use the same layout (Madgwick's bias changes only at rest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Attitude `q_wb` in the chosen world frame.
    pub q: UnitQuaternion<f64>,
    /// Gyro-bias estimate [rad/s], subtracted from the gyro.
    pub bias: Vector3<f64>,
    /// False until the first sample has initialised the attitude.
    pub initialized: bool,
    /// Time of the last sample [s] (batch: its timestamp; streaming: the sum of the `dt`s).
    pub time: f64,
    /// Seconds since start-up or the last recovery (drives the gain ramp).
    pub ramp_elapsed: f64,
    /// Seconds of uninterrupted accelerometer rejection.
    pub accel_rejected: f64,
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
}

impl Default for State {
    fn default() -> Self {
        Self {
            q: UnitQuaternion::identity(),
            bias: Vector3::zeros(),
            initialized: false,
            time: 0.0,
            ramp_elapsed: 0.0,
            accel_rejected: 0.0,
            mag_rejected: 0.0,
            rest: 0.0,
            mag_norm: 0.0,
            mag_dip_sin: 0.0,
            mag_dip_cos: 1.0,
        }
    }
}

/// Number of scalars in [`State::to_array`].
pub const STATE_LEN: usize = 16;

impl State {
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

    /// Flat layout `[qx, qy, qz, qw, bx, by, bz, initialized (0/1), time, ramp_elapsed,
    /// accel_rejected, mag_rejected, rest, mag_norm, sin δ₀, cos δ₀]`.
    pub fn to_array(&self) -> [f64; STATE_LEN] {
        let c = &self.q.coords;
        [
            c[0],
            c[1],
            c[2],
            c[3],
            self.bias.x,
            self.bias.y,
            self.bias.z,
            f64::from(u8::from(self.initialized)),
            self.time,
            self.ramp_elapsed,
            self.accel_rejected,
            self.mag_rejected,
            self.rest,
            self.mag_norm,
            self.mag_dip_sin,
            self.mag_dip_cos,
        ]
    }

    /// Inverse of [`State::to_array`] (exact round trip); a quaternion that is not unit to
    /// 1e-12 is renormalised; NaN/inf refused.
    pub fn from_array(a: &[f64; STATE_LEN]) -> crate::Result<Self> {
        if a.iter().any(|x| !x.is_finite()) {
            return Err(crate::Error::NonFinite { index: 0 });
        }
        let raw = nalgebra::Quaternion::new(a[3], a[0], a[1], a[2]);
        let q = if (raw.norm_squared() - 1.0).abs() < 1e-12 {
            UnitQuaternion::new_unchecked(raw)
        } else {
            crate::quat::normalize(&raw)?
        };
        Ok(Self {
            q,
            bias: Vector3::new(a[4], a[5], a[6]),
            initialized: a[7] != 0.0,
            time: a[8],
            ramp_elapsed: a[9],
            accel_rejected: a[10],
            mag_rejected: a[11],
            rest: a[12],
            mag_norm: a[13],
            mag_dip_sin: a[14],
            mag_dip_cos: a[15],
        })
    }
}

/// Initial attitude from one accelerometer (and magnetometer) sample: tilt from `accel` (the up
/// direction), heading from the horizontal part of `mag` (north), else yaw 0 (ZYX yaw of `R_wb`).
/// A zero accelerometer gives the identity; a magnetometer parallel to up is ignored.
pub fn initial_attitude(world: World, accel: &Vector3<f64>, mag: Option<&Vector3<f64>>) -> UnitQuaternion<f64> {
    let an = accel.norm();
    if an.is_nan() || an <= 1e-9 || an.is_infinite() {
        return UnitQuaternion::identity();
    }
    let up_b = accel / an;
    if let Some(m) = mag {
        // Twice: for a field nearly along gravity one pass leaves h off perpendicular by
        // cancellation (|m| ε/|h|: 2e-9 at 5e-8 rad, found by fuzz/fuzz_targets/filters.rs), and
        // the attitude built from it was neither unit nor level; the second pass removes that.
        let h = m - up_b * m.dot(&up_b);
        let h = h - up_b * h.dot(&up_b);
        let hn = h.norm();
        if hn > 1e-9 * (1.0 + m.norm()) && hn.is_finite() {
            return world.attitude_from_up_north(&up_b, &(h / hn));
        }
    }
    // Yaw 0: roll and pitch of R_wb = Ry(θ) Rx(φ) from up_b = R_wbᵀ up_w.
    let (ax, ay, az) = match world {
        World::Enu => (up_b.x, up_b.y, up_b.z),
        // NED: up_w = −z, so −up_b = R_wbᵀ z: the same formulas on the negated vector.
        World::Ned => (-up_b.x, -up_b.y, -up_b.z),
    };
    let roll = ay.atan2(az);
    let pitch = (-ax).atan2((ay * ay + az * az).sqrt());
    UnitQuaternion::from_euler_angles(roll, pitch, 0.0)
}

/// `(sin δ, cos δ)` of the dip angle δ of `m` (body) below the horizontal, given the body
/// direction of up (δ ∈ [−π/2, π/2], so cos δ ≥ 0).
#[inline]
pub(crate) fn dip(m: &Vector3<f64>, m_norm: f64, up_b: &Vector3<f64>) -> (f64, f64) {
    let s = (-(m.dot(up_b)) / m_norm).clamp(-1.0, 1.0);
    (s, (1.0 - s * s).sqrt())
}
