//! The one error type of the crate. Every fallible function returns [`Result`]; nothing reachable
//! from user input panics.

/// Why an imukit computation refused its input. Batch variants carry the flat row index of the
/// offending element so that bindings can point at it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A flat input slice is not a whole number of rows.
    #[error("length {len} is not a multiple of the row size {row}")]
    RowLength {
        /// Length of the flat slice.
        len: usize,
        /// Number of scalars per row.
        row: usize,
    },
    /// Input and output slices describe different numbers of rows.
    #[error("input has {input} rows but output has room for {output}")]
    RowCount {
        /// Rows in the input.
        input: usize,
        /// Rows in the output.
        output: usize,
    },
    /// An input value is NaN or infinite.
    #[error("element {index} contains a NaN or infinite value")]
    NonFinite {
        /// Row index.
        index: usize,
    },
    /// A finite input produced a non-finite result (magnitudes beyond what f64 can square).
    #[error("element {index} is too large in magnitude to compute with (result overflowed)")]
    Overflow {
        /// Row index.
        index: usize,
    },
    /// A quaternion with (numerically) zero norm, which represents no rotation.
    #[error("element {index} is a zero-norm quaternion (norm {norm:e}), which is no rotation")]
    ZeroQuaternion {
        /// Row index.
        index: usize,
        /// Its norm.
        norm: f64,
    },
    /// A 3x3 matrix that is not a rotation (RᵀR ≠ I or det R ≤ 0).
    #[error(
        "element {index} is not a rotation matrix: max |RᵀR - I| = {orthogonality:e}, det = {det} \
         (need orthonormal with det +1, tolerance {tolerance:e})"
    )]
    NotRotation {
        /// Row index.
        index: usize,
        /// Largest absolute entry of RᵀR − I.
        orthogonality: f64,
        /// Determinant.
        det: f64,
        /// Tolerance applied to `orthogonality`.
        tolerance: f64,
    },
    /// Pitch within the tolerance of ±90° (or past it between two samples), where the ZYX
    /// Euler-angle rate map is singular.
    #[error(
        "gimbal lock at element {index}: pitch {pitch_deg:.9}° is within {tolerance_deg:e}° of, or has \
         passed, ±90°, where the ZYX Euler rate map E(χ) is singular"
    )]
    GimbalLock {
        /// Row index.
        index: usize,
        /// The pitch angle, degrees.
        pitch_deg: f64,
        /// The tolerance, degrees.
        tolerance_deg: f64,
    },
    /// Timestamps that do not strictly increase.
    #[error("time must increase strictly: step into sample {index} has dt = {dt:e} s")]
    NonIncreasingTime {
        /// The later sample of the offending pair.
        index: usize,
        /// `t[index] − t[index − 1]`.
        dt: f64,
    },
    /// A scheme that the chosen representation does not support.
    #[error("scheme {scheme:?} is not available for representation {representation:?}; it supports {supported:?}")]
    Unsupported {
        /// The scheme asked for.
        scheme: &'static str,
        /// The representation asked for.
        representation: &'static str,
        /// The schemes it does support.
        supported: Vec<&'static str>,
    },
    /// An error in one named input of a function with several.
    #[error("{name}: {source}")]
    Argument {
        /// The argument's name.
        name: &'static str,
        /// What is wrong with it.
        source: Box<Error>,
    },
    /// A parameter (not array data) is out of its domain.
    #[error("{name} must be {expected}, got {got}")]
    Parameter {
        /// Parameter name.
        name: &'static str,
        /// What was expected.
        expected: &'static str,
        /// What was given, formatted.
        got: String,
    },
}

impl Error {
    /// The same error with its row index replaced (batch kernels report global rows).
    pub(crate) fn at(self, row: usize) -> Self {
        match self {
            Error::NonFinite { .. } => Error::NonFinite { index: row },
            Error::Overflow { .. } => Error::Overflow { index: row },
            Error::ZeroQuaternion { norm, .. } => Error::ZeroQuaternion { index: row, norm },
            Error::NotRotation {
                orthogonality,
                det,
                tolerance,
                ..
            } => Error::NotRotation {
                index: row,
                orthogonality,
                det,
                tolerance,
            },
            Error::GimbalLock {
                pitch_deg,
                tolerance_deg,
                ..
            } => Error::GimbalLock {
                index: row,
                pitch_deg,
                tolerance_deg,
            },
            other => other,
        }
    }
}

impl Error {
    /// Attributes this error to the input argument `name`.
    pub fn in_argument(self, name: &'static str) -> Self {
        Error::Argument {
            name,
            source: Box::new(self),
        }
    }

    /// The input at fault: the outermost [`Error::Argument`] or [`Error::Parameter`] name, or
    /// `None` when the error names no input (the caller knows which one it passed).
    pub fn argument(&self) -> Option<&'static str> {
        match self {
            Error::Argument { name, .. } | Error::Parameter { name, .. } => Some(name),
            _ => None,
        }
    }

    /// The row or sample at fault, when the innermost error names one.
    pub fn index(&self) -> Option<usize> {
        match self.root() {
            Error::NonFinite { index }
            | Error::Overflow { index }
            | Error::ZeroQuaternion { index, .. }
            | Error::NotRotation { index, .. }
            | Error::GimbalLock { index, .. }
            | Error::NonIncreasingTime { index, .. } => Some(*index),
            _ => None,
        }
    }

    /// The text after the argument: what the wrapped error says for an [`Error::Argument`], the
    /// whole message otherwise (a [`Error::Parameter`] message names its parameter itself).
    pub fn message(&self) -> String {
        match self {
            Error::Argument { source, .. } => source.to_string(),
            other => other.to_string(),
        }
    }

    /// The innermost error, past any [`Error::Argument`] wrappers.
    pub fn root(&self) -> &Error {
        match self {
            Error::Argument { source, .. } => source.root(),
            other => other,
        }
    }
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, Error>;
