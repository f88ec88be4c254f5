//! The world frame (ENU or NED) and the attitude a filter starts from.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

use crate::quat::multiply;

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

    /// World north, east and up in body axes, `(R_wbᵀ n_w, R_wbᵀ e_w, R_wbᵀ u_w)`: rows of `R(q)`.
    /// East (`n × u`) is a row too, read instead of crossed (Mahony's heading error needs it on
    /// the step's chain; the same to rounding for a unit `q`).
    #[inline(always)]
    pub(crate) fn predicted(self, q: &UnitQuaternion<f64>) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
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
            World::Enu => (row1, row0, row2),
            World::Ned => (row0, row1, -row2),
        }
    }

    /// The attitude `q_wb` given in world `from`, in this world. ENU to NED and back is one
    /// rotation, its own inverse: 180° about `(1, 1, 0)/√2` (swaps x and y, flips z).
    #[inline(always)]
    pub fn attitude_in(self, from: World, q: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
        if self == from {
            return *q;
        }
        let h = std::f64::consts::FRAC_1_SQRT_2;
        UnitQuaternion::new_unchecked(multiply(&Quaternion::new(0.0, h, h, 0.0), q.quaternion()))
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
