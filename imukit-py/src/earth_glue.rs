//! `local_level`: the Earth rate and gravity of an `imukit.LocalLevel` (read by field name) from
//! [`imukit::earth::LocalLevel`], which checks the values.

use imukit::earth::{Axes, LocalLevel};
use pyo3::prelude::*;

use crate::to_py;

/// `imukit.LocalLevel`'s fields.
#[derive(FromPyObject)]
pub(crate) struct LocalLevelFields {
    latitude: f64,
    height: f64,
    // A name, parsed below: a failed parse inside the derive would surface as a TypeError.
    axes: String,
}

impl LocalLevelFields {
    /// The core's frame, its values checked there.
    pub(crate) fn frame(&self, py: Python<'_>) -> PyResult<LocalLevel> {
        let axes = self.axes.parse::<Axes>().map_err(|e| to_py(py, "axes", e))?;
        LocalLevel::new(self.latitude, self.height, axes).map_err(|e| to_py(py, "frame", e))
    }
}

/// `(earth_rate, gravity)` of the frame, in its axes.
#[pyfunction]
pub(crate) fn local_level(py: Python<'_>, frame: LocalLevelFields) -> PyResult<([f64; 3], [f64; 3])> {
    let f = frame.frame(py)?;
    Ok((f.earth_rate().into(), f.gravity().into()))
}
