//! Core errors as `imukit._errors` exceptions: the class from the error's kind, the argument and
//! the sample index as fields (`exc.argument`, `exc.index`), the text without the `name: ` prefix
//! (the exception adds it, so `str(exc)` is `"<argument>: <message>"`).

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The `imukit._errors` class for an imukit error, so Python sees one hierarchy.
pub(crate) fn class_name(e: &imukit::Error) -> &'static str {
    use imukit::Error as E;
    match e.root() {
        E::RowLength { .. } | E::RowCount { .. } => "ShapeError",
        E::NonFinite { .. } | E::Overflow { .. } => "NonFiniteError",
        E::ZeroQuaternion { .. } => "InvalidQuaternionError",
        E::NotRotation { .. } => "InvalidRotationError",
        E::GimbalLock { .. } => "GimbalLockError",
        E::NonIncreasingTime { .. } => "TimestampError",
        E::Parameter { .. } | E::Unsupported { .. } => "ParameterError",
        E::Allocation { .. } => "ResourceError",
        // Only reached when no signal handler raised (the glue returns that exception instead).
        E::Interrupted { .. } => "ImukitError",
        E::Argument { .. } => "ImukitError",
    }
}

/// `imukit.<class>(message, argument=name, index=index)`.
fn exception(py: Python<'_>, class: &str, name: &str, message: String, index: Option<usize>) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let kwargs = PyDict::new(py);
        kwargs.set_item("argument", name)?;
        kwargs.set_item("index", index)?;
        let class = py.import("imukit._errors")?.getattr(class)?;
        Ok(PyErr::from_value(class.call((message,), Some(&kwargs))?))
    };
    build().unwrap_or_else(|failure| failure)
}

/// Raises `imukit.<class>` about the argument `name` (`str(exc)` is `"<name>: <message>"`).
pub(crate) fn raise(py: Python<'_>, class: &str, name: &str, message: impl std::fmt::Display) -> PyErr {
    exception(py, class, name, message.to_string(), None)
}

/// Raises `e` under the argument it names (an `Argument` or a `Parameter` error), else under
/// `fallback`, with the sample index it names.
pub(crate) fn to_py(py: Python<'_>, fallback: &str, e: imukit::Error) -> PyErr {
    let name = e.argument().unwrap_or(fallback);
    exception(py, class_name(&e), name, e.message(), e.index())
}
