//! The parameters of [`super::Robust`] and their `Default`: the one place every default number
//! is written (the Python bindings read them from here by name, [`Fields`]). Units are in the
//! names where they are not SI by context: `_s` seconds, `_rad` radians, `_rad_s` rad/s.

use crate::filters::{check, Fields};

/// Parameters of [`super::Robust`]. Defaults: `docs/filters_robust.md` (chosen on BROAD with
/// leave-one-group-out cross-validation, `bench/robust_tune.py`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustParams {
    /// Time constant of the 2nd-order Butterworth low pass of the specific force in the
    /// almost-inertial frame \[s\] (cut-off `1/(2π τ)`).
    pub tau_acc_s: f64,
    /// Time constant of the first-order heading correction from the magnetometer \[s\].
    pub tau_mag_s: f64,
    /// Length of one bias-estimation window \[s\]: corrections are summed over it, then one Kalman
    /// update (successive low-passed samples are not independent measurements).
    pub bias_window_s: f64,
    /// Prior standard deviation of each gyro-bias component [rad/s].
    pub bias_sigma_init_rad_s: f64,
    /// Time in which the bias variance grows by `bias_sigma_init²` without measurements \[s\]
    /// (random-walk process noise `σ_init²/T` per second).
    pub bias_forgetting_s: f64,
    /// Standard deviation of a window's mean correction rate as a bias measurement in motion
    /// [rad/s].
    pub bias_sigma_motion_rad_s: f64,
    /// Standard deviation of one second's mean gyro at rest as a bias measurement [rad/s] (a rest
    /// segment of `T` seconds counts with `σ/√T`).
    pub bias_sigma_rest_rad_s: f64,
    /// At rest, one bias update per this much rest (and one when the rest ends) \[s\].
    pub bias_rest_window_s: f64,
    /// The bias estimate is clipped to ± this per axis [rad/s].
    pub bias_clip_rad_s: f64,
    /// Rest: `‖ω̃ − ω̄‖` below this, and `‖ω̄ − b̂‖` below it widened by the bias uncertainty
    /// [rad/s] (`ω̃`, `ω̄` the gyro low-passed with `rest_noise_tau_s` and `rest_tau_s`, `b̂` the
    /// bias estimate).
    pub rest_gyro_rad_s: f64,
    /// Rest: `‖ã − ā‖` below this [m/s²] (the accelerometer low-passed as the gyro).
    pub rest_accel: f64,
    /// Rest: time the thresholds must hold \[s\].
    pub rest_duration_s: f64,
    /// Time constant of the rest-detection low passes `ω̄`, `ā` (the window means) \[s\].
    pub rest_tau_s: f64,
    /// Time constant of the low passes `ω̃`, `ã` that take sensor noise and vibration off the
    /// samples the rest tests compare with the window means \[s\].
    pub rest_noise_tau_s: f64,
    /// Magnetic disturbance: relative threshold on `|‖m‖ − m₀|/m₀`.
    pub mag_norm_fraction: f64,
    /// Magnetic disturbance: threshold on the dip-angle change `|δ − δ₀|` \[rad\].
    pub mag_dip_rad: f64,
    /// After this much uninterrupted rejection the field is used again, with the heading time
    /// constant multiplied by `mag_slow_factor` \[s\].
    pub mag_max_rejection_s: f64,
    /// Heading time-constant multiplier for a field used after `mag_max_rejection_s`.
    pub mag_slow_factor: f64,
    /// A new field, homogeneous (norm and dip within the thresholds of a candidate) while the
    /// sensor turns, becomes the reference after this many seconds of turning \[s\].
    pub mag_new_field_s: f64,
    /// Minimum rotation rate for time to count towards a new field [rad/s].
    pub mag_new_field_gyro_rad_s: f64,
    /// Streaming: a field sample stands in, turned by the gyro, for the samples without one up
    /// to this long after it \[s\] ([`crate::filters::FieldHold`]); 0: never.
    pub mag_hold_s: f64,
}

impl Default for RobustParams {
    fn default() -> Self {
        let deg = 1f64.to_radians();
        Self {
            tau_acc_s: 2.0,
            tau_mag_s: 20.0,
            bias_window_s: 4.0,
            bias_sigma_init_rad_s: 2.0 * deg,
            bias_forgetting_s: 16000.0,
            bias_sigma_motion_rad_s: 0.2 * deg,
            bias_sigma_rest_rad_s: 0.06 * deg,
            bias_rest_window_s: 1.0,
            bias_clip_rad_s: 6.0 * deg,
            rest_gyro_rad_s: 2.0 * deg,
            rest_accel: 0.5,
            rest_duration_s: 1.5,
            rest_tau_s: 0.5,
            rest_noise_tau_s: 0.05,
            mag_norm_fraction: 0.1,
            mag_dip_rad: 25.0 * deg,
            mag_max_rejection_s: 60.0,
            mag_slow_factor: 2.0,
            mag_new_field_s: 20.0,
            mag_new_field_gyro_rad_s: 20.0 * deg,
            mag_hold_s: crate::filters::MAG_HOLD_S,
        }
    }
}

/// Declares the field names once: [`Fields`] (by-name construction in the bindings) and the
/// domain check of each (finite and positive; those after `; at_least_0:` finite and ≥ 0).
macro_rules! named {
    ($($field:ident),+ ; at_least_0: $($zero:ident),+ $(,)?) => {
        impl Fields for RobustParams {
            const NAMES: &'static [&'static str] = &[$(stringify!($field)),+ $(, stringify!($zero))+];

            fn values(&self) -> Vec<f64> {
                vec![$(self.$field),+ $(, self.$zero)+]
            }

            fn from_values(values: &[f64]) -> Option<Self> {
                let mut it = values.iter().copied();
                let p = Self { $($field: it.next()?),+ $(, $zero: it.next()?)+ };
                it.next().is_none().then_some(p)
            }
        }

        impl RobustParams {
            /// Checks every parameter: finite and > 0 (or ≥ 0 where 0 switches it off); the bias σ at most 1e6 rad/s (far past any
            /// gyro's bias, which is clipped at `bias_clip_rad_s`: an uninformative prior or an
            /// ignored measurement; above ~1e50 the filter's covariance algebra overflows) and the
            /// bias's random walk `σ_init²/T` finite (errors name it).
            pub fn validate(&self) -> crate::Result<()> {
                $(check(stringify!($field), self.$field, "finite and > 0", |x| x > 0.0)?;)+
                $(check(stringify!($zero), self.$zero, "finite and ≥ 0", |x| x >= 0.0)?;)+
                check("mag_slow_factor", self.mag_slow_factor, "finite and ≥ 1", |x| x >= 1.0)?;
                for (name, sigma) in [
                    ("bias_sigma_init_rad_s", self.bias_sigma_init_rad_s),
                    ("bias_sigma_motion_rad_s", self.bias_sigma_motion_rad_s),
                    ("bias_sigma_rest_rad_s", self.bias_sigma_rest_rad_s),
                ] {
                    check(name, sigma, "> 0 and at most 1e6 rad/s", |x| x <= 1e6)?;
                }
                let walk = self.bias_sigma_init_rad_s.powi(2) / self.bias_forgetting_s;
                check(
                    "bias_forgetting_s",
                    self.bias_forgetting_s,
                    "> 0 and large enough that bias_sigma_init_rad_s² / bias_forgetting_s is finite",
                    |_| walk.is_finite(),
                )
            }
        }
    };
}

named!(
    tau_acc_s,
    tau_mag_s,
    bias_window_s,
    bias_sigma_init_rad_s,
    bias_forgetting_s,
    bias_sigma_motion_rad_s,
    bias_sigma_rest_rad_s,
    bias_rest_window_s,
    bias_clip_rad_s,
    rest_gyro_rad_s,
    rest_accel,
    rest_duration_s,
    rest_tau_s,
    rest_noise_tau_s,
    mag_norm_fraction,
    mag_dip_rad,
    mag_max_rejection_s,
    mag_slow_factor,
    mag_new_field_s,
    mag_new_field_gyro_rad_s;
    at_least_0: mag_hold_s,
);
