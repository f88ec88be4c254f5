//! Binding of `imukit::text::parse_block`, the fast path of `imukit.io._lines` (converts only).

use imukit::text::{parse_block, Layout, Separator, StampForm};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::raise;

/// Line numbers, line offsets, values `(N, C)`, exact stamps, whether all stamps were exact,
/// deferred line numbers, deferred offsets, and the block's line count.
type Parsed<'py> = (
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyAny>,
    Bound<'py, PyArray1<i64>>,
    bool,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray1<u64>>,
    u64,
);

/// The rows and deferred lines of the whole lines `block`, numbered from `first_line`:
/// `separator` one byte or None (runs of white space); `stamp` `"float"`, `"integer"` or
/// `"nine-decimals"` (see `imukit::text`); `trailing`: a line ending in the separator has that
/// empty last field dropped.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (block, first_line, separator, width, columns, stamp_column, stamp, stamp_required, trailing))]
pub(crate) fn text_parse_block<'py>(
    py: Python<'py>,
    block: &Bound<'py, PyBytes>,
    first_line: u64,
    separator: Option<u8>,
    width: usize,
    columns: Vec<usize>,
    stamp_column: usize,
    stamp: &str,
    stamp_required: bool,
    trailing: bool,
) -> PyResult<Parsed<'py>> {
    let stamp = match stamp {
        "float" => StampForm::Float,
        "integer" => StampForm::Integer,
        "nine-decimals" => StampForm::NineDecimals,
        other => {
            return Err(raise(
                py,
                "ParameterError",
                "stamp",
                format!("expected 'float', 'integer' or 'nine-decimals', got {other:?}"),
            ))
        }
    };
    let layout = Layout {
        separator: separator.map_or(Separator::Whitespace, Separator::Byte),
        width,
        columns: &columns,
        stamp_column,
        stamp,
        stamp_required,
        trailing,
    };
    let bytes = block.as_bytes();
    let parsed = py.detach(|| parse_block(bytes, first_line, &layout));
    let rows = parsed.lines.len();
    let values = PyArray1::from_vec(py, parsed.values).reshape([rows, columns.len()])?;
    Ok((
        PyArray1::from_vec(py, parsed.lines),
        PyArray1::from_vec(py, parsed.offsets),
        values.into_any(),
        PyArray1::from_vec(py, parsed.stamps),
        parsed.exact,
        PyArray1::from_vec(py, parsed.deferred_lines),
        PyArray1::from_vec(py, parsed.deferred_offsets),
        parsed.line_count,
    ))
}
