//! Simulator bindings: closed-form motions into truth arrays, and the sensor error model; wrapped by
//! `imukit.sim`.

use imukit::sim::{self, Motion, SensorModel};
use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};
use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadwriteArray2};
use pyo3::prelude::*;

use crate::{contiguous, raise, to_py};

fn v3(p: &[f64]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// `R_wb` from an `[x, y, z, w]` unit quaternion.
fn rotation(p: &[f64]) -> Rotation3<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(p[3], p[0], p[1], p[2])).to_rotation_matrix()
}

/// The motion of `kind` from its parameters, in the order `imukit.sim` documents for each class.
fn motion(py: Python<'_>, kind: &str, p: &[f64]) -> PyResult<Motion> {
    let expected = match kind {
        "static" => 7,
        "constant_twist" => 13,
        "helix" => 6,
        "figure_eight" => 9,
        "vio_ellipse" => 10,
        other => {
            let message = format!("expected a motion kind known to imukit.sim, got {other:?}");
            return Err(raise(py, "ParameterError", "trajectory", message));
        }
    };
    if p.len() != expected || p.iter().any(|v| !v.is_finite()) {
        let message = format!("{kind}: expected {expected} finite parameters, got {p:?}");
        return Err(raise(py, "ParameterError", "trajectory", message));
    }
    Ok(match kind {
        "static" => Motion::Static {
            position: v3(&p[0..3]),
            rotation: rotation(&p[3..7]),
        },
        "constant_twist" => Motion::ConstantTwist {
            position: v3(&p[0..3]),
            rotation: rotation(&p[3..7]),
            body_velocity: v3(&p[7..10]),
            body_rate: v3(&p[10..13]),
        },
        "helix" => Motion::Helix {
            center: v3(&p[0..3]),
            radius: p[3],
            angular_rate: p[4],
            climb_rate: p[5],
        },
        "figure_eight" => Motion::FigureEight {
            center: v3(&p[0..3]),
            amplitude: v3(&p[3..6]),
            angular_rate: p[6],
            roll: p[7],
            pitch: p[8],
        },
        _ => Motion::VioEllipse {
            center: v3(&p[0..3]),
            amplitude: v3(&p[3..6]),
            angular_rate: p[6],
            height_frequency: p[7],
            roll: p[8],
            pitch: p[9],
        },
    })
}

type Arrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// `(position, velocity, rotation xyzw, gyro, accel)` of a closed-form motion at the times `t`.
#[pyfunction]
pub(crate) fn sim_motion<'py>(
    py: Python<'py>,
    kind: &str,
    params: Vec<f64>,
    t: PyReadonlyArray1<'py, f64>,
    gravity: [f64; 3],
) -> PyResult<Arrays<'py>> {
    let motion = motion(py, kind, &params)?;
    // No private copy: imukit.sim passes an array it has just made and shares with no one.
    let t = contiguous(py, "t", &t)?;
    let n = t.len();
    let make = |w: usize| PyArray2::<f64>::zeros(py, [n, w], false);
    let (p, v, q, w, a) = (make(3), make(3), make(4), make(3), make(3));
    {
        let (mut pg, mut vg, mut qg, mut wg, mut ag) = (
            p.readwrite(),
            v.readwrite(),
            q.readwrite(),
            w.readwrite(),
            a.readwrite(),
        );
        let out = sim::Truth {
            position: pg.as_slice_mut()?,
            velocity: vg.as_slice_mut()?,
            rotation: qg.as_slice_mut()?,
            gyro: wg.as_slice_mut()?,
            accel: ag.as_slice_mut()?,
        };
        let g = Vector3::from(gravity);
        py.detach(|| sim::evaluate(&motion, t, &g, out))
            .map_err(|e| to_py(py, "simulate", e))?;
    }
    Ok((p, v, q, w, a))
}

/// Measures one triad in place: `ideal` (the caller's fresh `(N, 3)` array) becomes the readings;
/// returns the true biases. `model` is `[T (9, row-major), bias (3), σ_on, σ, σ_w, σ_gm, τ_gm, range,
/// resolution]`. Private to `imukit.sim`, which passes arrays it has just made and shares with no one,
/// so nothing is copied.
#[pyfunction]
pub(crate) fn sim_measure<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    mut ideal: PyReadwriteArray2<'py, f64>,
    model: [f64; 19],
    seed: u64,
    triad: u64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = &model;
    let model = SensorModel {
        matrix: Matrix3::from_row_slice(&m[0..9]),
        bias: v3(&m[9..12]),
        turn_on_sigma: m[12],
        density: m[13],
        random_walk: m[14],
        gauss_markov_sigma: m[15],
        gauss_markov_tau: m[16],
        range: m[17],
        resolution: m[18],
    };
    let t = contiguous(py, "t", &t)?;
    let n = t.len();
    let bias = PyArray2::<f64>::zeros(py, [n, 3], false);
    {
        let mut bg = bias.readwrite();
        let b = bg.as_slice_mut()?;
        let values = ideal
            .as_slice_mut()
            .map_err(|_| raise(py, "ShapeError", "ideal", "expected a C-contiguous float64 array"))?;
        let errors = if triad == 0 { "gyro_errors" } else { "accel_errors" };
        py.detach(|| sim::measure_in_place(t, values, &model, seed, triad, b))
            .map_err(|e| raise(py, crate::class_name(&e), errors, e.root()))?;
    }
    Ok(bias)
}
