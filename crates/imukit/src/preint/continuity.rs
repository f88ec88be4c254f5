//! The continuity rule of both schemes: a batch (or a merged preintegration) that continues a
//! preintegration starts with its last sample, the same time and the same readings. Consecutive
//! batches and windows share their boundary sample, as GTSAM's and VINS-Mono's keyframe windows
//! do; a batch that starts one sample later would drop the interval between (in the euler scheme
//! silently: Δp off by 0.145 m after 1 s in 4 chunks of a 200 Hz recording), and a repeated,
//! out-of-order or gapped batch would integrate a motion that never happened.
//!
//! | end | time | readings |
//! |---|---|---|
//! | batch (`integrate_samples*`) | its first and last stamps on the caller's clock | its first and last samples |
//! | window of `preintegrate_windows` | unknown (the record carries the boundary times) | the scheme's signal at the boundary |
//! | `try_integrate_measurement` | unknown | euler: the first call's sample starts, the end is open (the next sample is held from it); midpoint: each call's sample ends |
//!
//! An unknown time matches any time; an unknown end (`None`) matches any start.

use nalgebra::Vector3;

use super::Preintegrator;
use crate::error::{Error, Result};

/// A sample at one end of a preintegration: its time on the caller's clock (when known) and its
/// readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct End {
    /// Time on the caller's clock \[s\], when known.
    pub t: Option<f64>,
    /// Accelerometer reading [m/s²].
    pub accel: Vector3<f64>,
    /// Gyro reading [rad/s].
    pub gyro: Vector3<f64>,
}

impl End {
    /// Whether a preintegration ending here may be continued by one starting at `start`.
    fn continued_by(&self, start: &End) -> bool {
        let same_time = match (self.t, start.t) {
            (Some(a), Some(b)) => a == b,
            _ => true,
        };
        same_time && self.accel == start.accel && self.gyro == start.gyro
    }

    /// The refusal of `start` after this end, under the argument `name`.
    fn refusal(&self, start: &End, name: &'static str) -> Error {
        let time = |t: Option<f64>| t.map_or("?".to_string(), |t| format!("{t}"));
        Error::Parameter {
            name,
            expected: "a continuation starting with the preintegration's last sample (consecutive \
                       batches share their boundary sample: imu[0:50], then imu[49:100])",
            got: format!(
                "a start at t = {} (accel {:?}, gyro {:?}) after an end at t = {} (accel {:?}, gyro {:?})",
                time(start.t),
                start.accel.as_slice(),
                start.gyro.as_slice(),
                time(self.t),
                self.accel.as_slice(),
                self.gyro.as_slice()
            ),
        }
    }
}

/// The two ends of a preintegration, `None` where unknown or before any sample.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ends {
    /// The sample it starts with.
    pub first: Option<End>,
    /// The sample it ends with.
    pub last: Option<End>,
}

impl Ends {
    /// Checks that `start` may follow (errors name `name`).
    pub(super) fn check_next(&self, start: &End, name: &'static str) -> Result<()> {
        match self.last {
            Some(last) if !last.continued_by(start) => Err(last.refusal(start, name)),
            _ => Ok(()),
        }
    }

    /// These ends followed by `next`'s (a merge or a batch added after these).
    pub(super) fn then(&self, next: &Ends) -> Ends {
        Ends {
            first: self.first.or(next.first),
            last: next.last,
        }
    }
}

impl Preintegrator {
    /// The ends of this preintegration (module docs of `continuity.rs`).
    pub fn ends(&self) -> Ends {
        self.boundary
    }
}
