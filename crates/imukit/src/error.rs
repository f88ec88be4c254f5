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
    /// The memory a result sized by the input needs could not be had (checked before allocating,
    /// so that an input asking for too much is refused instead of aborting the process).
    #[error("{} {what} need {}", thousands(*.count), bytes_text(*.bytes))]
    Allocation {
        /// How many items were asked for.
        count: usize,
        /// What they are, plural ("windows", "covariances").
        what: &'static str,
        /// Their size in bytes (as u128: the product may exceed `usize`).
        bytes: u128,
    },
    /// The caller cancelled a long kernel through its [`Cancel`] flag (Python: Ctrl-C).
    #[error("interrupted at sample {index}")]
    Interrupted {
        /// The sample reached.
        index: usize,
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
            | Error::NonIncreasingTime { index, .. }
            | Error::Interrupted { index } => Some(*index),
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

/// `count` with thousands separators: `20,000,001`.
pub fn thousands(count: usize) -> String {
    let digits = count.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A byte count in decimal units, one decimal: `51.7 GB`.
pub fn bytes_text(bytes: u128) -> String {
    let units = [
        (1e18, "EB"),
        (1e15, "PB"),
        (1e12, "TB"),
        (1e9, "GB"),
        (1e6, "MB"),
        (1e3, "kB"),
    ];
    let b = bytes as f64;
    match units.iter().find(|(scale, _)| b >= *scale) {
        Some((scale, unit)) => format!("{:.1} {unit}", b / scale),
        None => format!("{bytes} B"),
    }
}

/// An empty vector with room for `count` items of `T`, or [`Error::Allocation`] when the memory
/// cannot be had (`Vec::try_reserve_exact`: no abort on exhaustion).
pub fn try_vec<T>(count: usize, what: &'static str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(count).map_err(|_| Error::Allocation {
        count,
        what,
        bytes: count as u128 * std::mem::size_of::<T>() as u128,
    })?;
    Ok(v)
}

/// A flag another thread sets to stop a long kernel early: the kernel polls it every
/// [`Cancel::EVERY`] samples (a few ms of work) and returns [`Error::Interrupted`]. The Python glue
/// sets it when a signal handler raises (Ctrl-C) while the kernel runs with the GIL released.
#[derive(Debug, Default)]
pub struct Cancel(std::sync::atomic::AtomicBool);

impl Cancel {
    /// Samples between two polls: 65,536 strapdown steps take 3–10 ms.
    pub const EVERY: usize = 1 << 16;

    /// A flag not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the kernel polling this flag to stop.
    pub fn cancel(&self) {
        self.0.store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// [`Error::Interrupted`] at sample `k` when `k` is a polling point and the flag is set.
    #[inline]
    pub fn check(&self, k: usize) -> Result<()> {
        if k.is_multiple_of(Self::EVERY) && self.0.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(Error::Interrupted { index: k });
        }
        Ok(())
    }
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, Error>;
