//! Gyro integration: attitude from body rates, in three representations by five schemes.
//!
//! | item | convention |
//! |---|---|
//! | input | timestamps `t` \[s\] (strictly increasing, any spacing), body rates `ω` [rad/s], one row per sample |
//! | ODE | `Ṙ = R [ω]×`; `q̇ = ½ q ⊗ [ω, 0]`; `χ̇ = E(χ) ω` for ZYX angles χ |
//! | output | Hamilton `q_wb` per sample, `[x, y, z, w]`, element 0 = the initial attitude |
//!
//! Schemes over step `k → k+1`, `h = t[k+1] − t[k]`, `ω_k` the sample at `t[k]`:
//!
//! | scheme | update | order |
//! |---|---|---|
//! | [`Scheme::Euler`] | `y ← y + h f(y, ω_k)`, then back onto the manifold | 1 |
//! | [`Scheme::Exp`] | `R ← R Exp(ω_k h)` (exact for a rate held over the step) | 1 (exact for constant ω) |
//! | [`Scheme::Rk2`] | explicit midpoint on the ODE with `ω_mid = ½(ω_k + ω_{k+1})` | 2 |
//! | [`Scheme::Rk4`] | classical RK4 on the ODE; `ω(t_k + h/2)` from the local cubic | 4 |
//! | [`Scheme::Magnus`] | `R ← R Exp(½h(ω₁+ω₂) + (√3/12) h² ω₁ × ω₂)`, ω₁, ω₂ at the Gauss nodes from the cubic | 4 (exact for constant ω) |
//!
//! The Magnus step: with `Y = Rᵀ`, `Ẏ = A(t) Y` for `A = −[ω]×`, and the fourth-order Magnus
//! integrator with two Gauss–Legendre nodes is `Ω = ½h(A₁+A₂) − (√3/12) h² [A₁, A₂]` (Blanes,
//! Casas, Oteo & Ros 2009, eq. 253). Since `[[a]×, [b]×] = [a × b]×`, this is
//! `Y(h) = Exp(−θ) Y(0)`, i.e. `R(h) = R(0) Exp(θ)` with the θ in the table.
//!
//! Representation × scheme: quaternion and matrix take all five; ZYX Euler angles have no group
//! structure and take `euler`, `rk2` and `rk4` only. Quaternions are renormalised and
//! matrices re-orthonormalised (nearest rotation, Björck–Bowie iteration) after every step of the
//! ODE schemes, and every `RENORMALIZE_EVERY` steps of `exp`/`magnus`, which multiply exact
//! rotations. Euler angles are refused within the gimbal tolerance of ±90°, and when cos(pitch)
//! changes sign between two samples (the path jumped across the singularity).

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

use rayon::prelude::*;

use crate::interp::{Cubic, StepInterpolator};
use crate::{euler, so3, time, Cancel, Error, Result};

/// Integration scheme; see the module table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Forward Euler on the ODE.
    Euler,
    /// Zero-order hold: `Exp(ω_k h)`.
    Exp,
    /// Explicit midpoint (second-order Runge–Kutta) on the ODE; formerly named `midpoint`.
    Rk2,
    /// Classical Runge–Kutta on the ODE.
    Rk4,
    /// Fourth-order Magnus (coning-corrected) closed form.
    Magnus,
}

/// Attitude representation the ODE is integrated in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Representation {
    /// Hamilton unit quaternion.
    Quaternion,
    /// Rotation matrix.
    Matrix,
    /// Intrinsic ZYX Euler angles.
    Euler,
}

crate::named_enum!(
    Scheme,
    "scheme",
    [Euler => "euler", Exp => "exp", Rk2 => "rk2", Rk4 => "rk4", Magnus => "magnus"],
    // Deprecated: `midpoint` means Exp of the averaged rate in strapdown and preintegration.
    aliases ["midpoint" => Rk2]
);
crate::named_enum!(
    Representation,
    "representation",
    [Quaternion => "quaternion", Matrix => "matrix", Euler => "euler"]
);

impl Representation {
    /// The schemes this representation supports.
    pub fn schemes(self) -> &'static [Scheme] {
        match self {
            Representation::Quaternion | Representation::Matrix => {
                &[Scheme::Euler, Scheme::Exp, Scheme::Rk2, Scheme::Rk4, Scheme::Magnus]
            }
            Representation::Euler => &[Scheme::Euler, Scheme::Rk2, Scheme::Rk4],
        }
    }
}

/// Options of [`integrate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Integration scheme.
    pub scheme: Scheme,
    /// Representation the ODE is integrated in.
    pub representation: Representation,
    /// For [`Representation::Euler`]: refuse pitch within this many radians of ±π/2.
    pub gimbal_tolerance: f64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            scheme: Scheme::Rk2,
            representation: Representation::Quaternion,
            gimbal_tolerance: euler::GIMBAL_TOLERANCE,
        }
    }
}

/// An attitude representation as an ODE state: `ẏ = f(y, ω)`, with a projection back onto the
/// manifold after each step.
trait State: Copy + std::ops::Add<Output = Self> + std::ops::Mul<f64, Output = Self> {
    fn derivative(&self, omega: &Vector3<f64>, tolerance: f64) -> Result<Self>;
    /// Whether the state may be used at all (Euler angles: not at gimbal lock).
    fn admissible(&self, _tolerance: f64) -> Result<()> {
        Ok(())
    }
    /// The pitch (degrees) if the path from `previous` to `self` jumped across a singularity
    /// between samples (Euler angles: cos(pitch) changed sign without landing within the tolerance),
    /// the step having turned the body by at most `turn` radians (`|ω| h`).
    fn crossed_singularity(&self, _previous: &Self, _turn: f64) -> Option<f64> {
        None
    }
    fn project(self) -> Self;
    fn quaternion(&self) -> UnitQuaternion<f64>;
    /// `y ⊕ θ = y Exp(θ)`, not re-projected (see [`RENORMALIZE_EVERY`]); only called for group
    /// representations.
    fn compose_exp(&self, theta: &Vector3<f64>) -> Self;
}

impl State for Quaternion<f64> {
    #[inline]
    fn derivative(&self, omega: &Vector3<f64>, _: f64) -> Result<Self> {
        Ok(self * Quaternion::from_imag(*omega) * 0.5)
    }
    #[inline]
    fn project(self) -> Self {
        self / self.norm()
    }
    #[inline]
    fn quaternion(&self) -> UnitQuaternion<f64> {
        UnitQuaternion::new_unchecked(*self)
    }
    #[inline]
    fn compose_exp(&self, theta: &Vector3<f64>) -> Self {
        crate::quat::multiply(self, crate::quat::exp(theta).quaternion())
    }
}

impl State for Matrix3<f64> {
    #[inline]
    fn derivative(&self, omega: &Vector3<f64>, _: f64) -> Result<Self> {
        Ok(self * so3::hat(omega))
    }
    #[inline]
    fn project(self) -> Self {
        // The nearest rotation (orthogonal polar factor) by Björck–Bowie iteration
        // X ← X (3I − XᵀX)/2, quadratically convergent from a near-orthonormal start; a projection
        // through the quaternion would instead leak the O(h²) symmetric error of an Euler step
        // into the rotation.
        let mut x = self;
        for _ in 0..8 {
            let gram = x.transpose() * x;
            if (gram - Matrix3::identity()).abs().max() <= 4.0 * f64::EPSILON {
                break;
            }
            x = x * (Matrix3::identity() * 3.0 - gram) * 0.5;
        }
        x
    }
    #[inline]
    fn quaternion(&self) -> UnitQuaternion<f64> {
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*self));
        UnitQuaternion::new_normalize(q.into_inner())
    }
    #[inline]
    fn compose_exp(&self, theta: &Vector3<f64>) -> Self {
        self * so3::exp(theta).matrix()
    }
}

impl State for Vector3<f64> {
    #[inline]
    fn derivative(&self, omega: &Vector3<f64>, tolerance: f64) -> Result<Self> {
        Ok(euler::rate_matrix(self, tolerance)? * omega)
    }
    #[inline]
    fn admissible(&self, tolerance: f64) -> Result<()> {
        euler::check_pitch(self.y, tolerance)
    }
    #[inline]
    fn crossed_singularity(&self, previous: &Self, turn: f64) -> Option<f64> {
        // Near ±90° the ZYX rates grow like tan θ: a step that crosses cos θ = 0, or that turns yaw
        // or roll by more than MAX_EULER_STEP, has not resolved the dynamics (the integrated pitch
        // then turns back instead of passing through 90°). A jump the body's own turn explains
        // (a pure yaw of 1 rad/s over dt = 1e15 s) is no sign of the singularity: only jumps
        // beyond twice `turn` are.
        let wrapped = |d: f64| (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        let jump = wrapped(self.x - previous.x)
            .abs()
            .max(wrapped(self.z - previous.z).abs());
        let amplified = jump > MAX_EULER_STEP && jump > 2.0 * turn;
        (self.y.cos() * previous.y.cos() <= 0.0 || amplified).then(|| self.y.to_degrees())
    }
    #[inline]
    fn project(self) -> Self {
        self
    }
    #[inline]
    fn quaternion(&self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_rotation_matrix(&euler::to_rotation(self))
    }
    fn compose_exp(&self, _: &Vector3<f64>) -> Self {
        // `check` refuses group schemes for Euler angles before any step runs.
        *self
    }
}

/// Largest yaw or roll change \[rad\] one Euler-angle step may make before it counts as jumping over
/// the singularity (1 rad: 200 rad/s at 200 Hz, far beyond any gyro's range).
const MAX_EULER_STEP: f64 = 1.0;

/// Checks the shapes shared by every integrator (values are checked during the run).
fn check(t: &[f64], gyro: &[f64], out_len: Option<usize>) -> Result<()> {
    if t.is_empty() {
        return Err(Error::Parameter {
            name: "t",
            expected: "at least one sample",
            got: "0 samples".into(),
        });
    }
    if gyro.len() != 3 * t.len() {
        let e = Error::RowCount {
            input: t.len(),
            output: gyro.len() / 3,
        };
        return Err(e.in_argument("gyro"));
    }
    if let Some(len) = out_len {
        if len != 4 * t.len() {
            let e = Error::RowCount {
                input: t.len(),
                output: len / 4,
            };
            return Err(e.in_argument("out"));
        }
    }
    Ok(())
}

/// Finite, strictly increasing `t` and finite `gyro`, naming the first bad sample.
fn check_values(t: &[f64], gyro: &[f64]) -> Result<()> {
    time::check_increasing(t).map_err(|e| e.in_argument("t"))?;
    if let Some(i) = gyro.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite { index: i / 3 }.in_argument("gyro"));
    }
    Ok(())
}

/// Integrates body rates `gyro` (n rows, rad/s) sampled at `t` (n, seconds) from `initial`.
///
/// Writes every attitude (`[x, y, z, w]`, row 0 = `initial`) to `out` (n rows) when given, and
/// returns the final attitude. No allocation per sample.
pub fn integrate(
    t: &[f64],
    gyro: &[[f64; 3]],
    initial: &UnitQuaternion<f64>,
    options: &Options,
    out: Option<&mut [[f64; 4]]>,
) -> Result<UnitQuaternion<f64>> {
    integrate_cancellable(t, gyro, initial, options, out, &Cancel::new())
}

/// [`integrate`], stopping with [`Error::Interrupted`] when `cancel` is set (polled every
/// [`Cancel::EVERY`] samples).
pub fn integrate_cancellable(
    t: &[f64],
    gyro: &[[f64; 3]],
    initial: &UnitQuaternion<f64>,
    options: &Options,
    out: Option<&mut [[f64; 4]]>,
    cancel: &Cancel,
) -> Result<UnitQuaternion<f64>> {
    // The steps index flat rows; the views are the same memory.
    let (gyro, out) = (gyro.as_flattened(), out.map(|o| o.as_flattened_mut()));
    check(t, gyro, out.as_ref().map(|o| o.len()))?;
    check_options(options)?;
    if !initial.coords.iter().all(|v| v.is_finite()) {
        return Err(Error::NonFinite { index: 0 }.in_argument("initial"));
    }
    integrate_checked(t, gyro, initial, options, out, cancel)
}

crate::simd_dispatch! {
    /// [`integrate_cancellable`] on checked inputs (flat rows), per instruction-set path.
    fn integrate_checked(
        t: &[f64],
        gyro: &[f64],
        initial: &UnitQuaternion<f64>,
        options: &Options,
        out: Option<&mut [f64]>,
        cancel: &Cancel,
    ) -> Result<UnitQuaternion<f64>> {
        let last = match options.representation {
            Representation::Quaternion => match out {
                Some(out) if matches!(options.scheme, Scheme::Exp | Scheme::Magnus) && t.len() > 1 => {
                    return quaternion_product(t, gyro, initial, options.scheme, out, cancel);
                }
                out => run(initial.into_inner(), t, gyro, options, out, cancel)?.quaternion(),
            },
            Representation::Matrix => {
                run(*initial.to_rotation_matrix().matrix(), t, gyro, options, out, cancel)?.quaternion()
            }
            Representation::Euler => {
                let chi = euler::from_rotation(&initial.to_rotation_matrix());
                run(chi, t, gyro, options, out, cancel)?.quaternion()
            }
        };
        Ok(last)
    }
}

/// Integrates body rates in the rotation-matrix representation from the matrix `initial` and
/// returns the final matrix itself, with `options.representation` ignored (taken as
/// [`Representation::Matrix`]). [`integrate`] converts the same state to a quaternion; this form
/// lets a caller continue a long stream in matrix form, so the state never passes through a
/// quaternion (and the matrix's own orthonormality can be checked: `tests/stability.rs`).
pub fn integrate_rotation_matrix(
    t: &[f64],
    gyro: &[[f64; 3]],
    initial: &Matrix3<f64>,
    options: &Options,
) -> Result<Matrix3<f64>> {
    let gyro = gyro.as_flattened();
    let options = Options {
        representation: Representation::Matrix,
        ..*options
    };
    check(t, gyro, None)?;
    check_options(&options)?;
    let orthonormal = (initial.transpose() * initial - Matrix3::identity()).abs().max() <= 1e-9;
    if !(initial.iter().all(|v| v.is_finite()) && orthonormal && initial.determinant() > 0.0) {
        return Err(Error::Parameter {
            name: "initial",
            expected: "a rotation matrix (RᵀR = I to 1e-9, det R = +1)",
            got: format!("{initial:?}"),
        });
    }
    run(*initial, t, gyro, &options, None, &Cancel::new())
}

/// The scheme is supported by the representation and the gimbal tolerance is an angle in [0, π/2).
fn check_options(options: &Options) -> Result<()> {
    if !options.representation.schemes().contains(&options.scheme) {
        // The scheme is the one at fault: the representation supports others.
        return Err(Error::Unsupported {
            scheme: options.scheme.name(),
            representation: options.representation.name(),
            supported: options.representation.schemes().iter().map(|s| s.name()).collect(),
        }
        .in_argument("scheme"));
    }
    let tol = options.gimbal_tolerance;
    if !(tol.is_finite() && (0.0..std::f64::consts::FRAC_PI_2).contains(&tol)) {
        return Err(Error::Parameter {
            name: "gimbal_tolerance",
            expected: "a finite angle in [0, π/2) radians",
            got: format!("{tol}"),
        });
    }
    Ok(())
}

/// Group schemes multiply exact rotations, so the state leaves the manifold only by rounding
/// (≈ 1e-16 per step): projecting every 16 steps keeps |q| and RᵀR within ~1e-15 of 1 and I while
/// taking the projection (a dependent chain of ~25 cycles) off most steps.
const RENORMALIZE_EVERY: usize = 16;

/// `(√3/6)`: Gauss–Legendre nodes at `h (½ ∓ √3/6)`.
const GAUSS_OFFSET: f64 = 0.288_675_134_594_812_9;
/// `√3/12`, the commutator weight of the fourth-order Magnus step.
const MAGNUS_WEIGHT: f64 = 0.144_337_567_297_406_44;

#[inline(always)] // into each instruction-set copy (crate::simd)
fn run<S: State>(
    mut y: S,
    t: &[f64],
    gyro: &[f64],
    options: &Options,
    out: Option<&mut [f64]>,
    cancel: &Cancel,
) -> Result<S> {
    let (rates, _) = gyro.as_chunks::<3>();
    let mut out = out.map(|o| o.as_chunks_mut::<4>().0);
    let gauss = gauss_nodes(t, gyro);
    let midstep = StepInterpolator::new(Cubic::new(t, gyro), [0.5]);
    let tol = options.gimbal_tolerance;
    let f = |y: &S, w: &Vector3<f64>, k: usize| y.derivative(w, tol).map_err(|e| e.at(k));
    let mut store = |k: usize, y: &S| {
        if let Some(out) = out.as_deref_mut() {
            let q = y.quaternion();
            out[k] = [q.i, q.j, q.k, q.w];
        }
    };
    if !(t[0].is_finite() && rates[0].iter().all(|v| v.is_finite())) {
        return Err(input_error(t, gyro));
    }
    y.admissible(tol)?;
    store(0, &y);
    let mut previous = y;
    for (k, (tt, ww)) in t.windows(2).zip(rates.windows(2)).enumerate() {
        cancel.check(k)?;
        let h = tt[1] - tt[0];
        // Validated on the fly, one pass over the data; the slow path finds the first bad index.
        if !(h > 0.0 && h <= f64::MAX && ww[1].iter().all(|v| v.is_finite())) {
            return Err(input_error(t, gyro));
        }
        let (w0, w1) = (Vector3::from(ww[0]), Vector3::from(ww[1]));
        y = match options.scheme {
            Scheme::Euler => (y + f(&y, &w0, k)? * h).project(),
            Scheme::Exp | Scheme::Magnus => y.compose_exp(&group_increment(options.scheme, &gauss, &w0, h, k)),
            Scheme::Rk2 => {
                let mid = y + f(&y, &w0, k)? * (0.5 * h);
                (y + f(&mid, &((w0 + w1) * 0.5), k)? * h).project()
            }
            Scheme::Rk4 => {
                let [wm] = midstep.at(k);
                let k1 = f(&y, &w0, k)?;
                let k2 = f(&(y + k1 * (0.5 * h)), &wm, k)?;
                let k3 = f(&(y + k2 * (0.5 * h)), &wm, k)?;
                let k4 = f(&(y + k3 * h), &w1, k)?;
                (y + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)).project()
            }
        };
        if matches!(options.scheme, Scheme::Exp | Scheme::Magnus) && (k + 1) % RENORMALIZE_EVERY == 0 {
            y = y.project();
        }
        y.admissible(tol).map_err(|e| e.at(k + 1))?;
        let turn = w0.amax().max(w1.amax()) * 3f64.sqrt() * h;
        if let Some(pitch_deg) = y.crossed_singularity(&previous, turn) {
            return Err(Error::GimbalLock {
                index: k + 1,
                pitch_deg,
                tolerance_deg: tol.to_degrees(),
            });
        }
        previous = y;
        store(k + 1, &y);
    }
    check_finite_quaternions(&y.quaternion(), out.as_deref().map(|o| o.as_flattened()), t.len())?;
    Ok(y)
}

/// Finite rates can still overflow (e.g. 1e200 rad/s): refuse a non-finite result, naming the
/// first non-finite stored attitude when there is a store, else the last sample. An ODE step can
/// also overflow only the norm: `q/|q|` with `|q|² = inf` is the zero quaternion, finite but no
/// rotation, and the following steps keep it zero; so a result off the unit sphere (every valid
/// one is unit to ~1e-15) is refused the same way.
fn check_finite_quaternions(last: &UnitQuaternion<f64>, out: Option<&[f64]>, n: usize) -> Result<()> {
    let valid = crate::quat::is_unit_coords;
    if valid(last.coords.as_slice()) {
        return Ok(());
    }
    let index = out
        .and_then(|o| o.chunks_exact(4).position(|q| !valid(q)))
        .unwrap_or(n - 1);
    Err(Error::Overflow { index })
}

/// The rates at the two Gauss–Legendre nodes of every step.
fn gauss_nodes<'a>(t: &'a [f64], gyro: &'a [f64]) -> StepInterpolator<'a, 2> {
    StepInterpolator::new(Cubic::new(t, gyro), [0.5 - GAUSS_OFFSET, 0.5 + GAUSS_OFFSET])
}

/// The rotation vector θ of step k for the closed-form schemes: `R ← R Exp(θ)`.
#[inline]
fn group_increment(
    scheme: Scheme,
    gauss: &StepInterpolator<'_, 2>,
    w0: &Vector3<f64>,
    h: f64,
    k: usize,
) -> Vector3<f64> {
    if scheme == Scheme::Magnus {
        let [a, b] = gauss.at(k);
        (a + b) * (0.5 * h) + a.cross(&b) * (MAGNUS_WEIGHT * h * h)
    } else {
        w0 * h
    }
}

/// Steps per parallel task in [`quaternion_product`]'s first pass.
const CHUNK: usize = 4096;

/// Closed-form schemes in quaternion form, every attitude stored, in two passes: the increments
/// `Exp(θ_k)` are independent of the attitude, so they are computed in parallel straight into
/// `out[k+1]`; a sequential pass then turns them in place into the running product
/// `q_{k+1} = q_k ⊗ Exp(θ_k)`. Same operations in the same order as [`run`], so the same bits,
/// with the expensive half spread over the cores.
#[inline(always)] // into each instruction-set copy (crate::simd)
fn quaternion_product(
    t: &[f64],
    gyro: &[f64],
    initial: &UnitQuaternion<f64>,
    scheme: Scheme,
    out: &mut [f64],
    cancel: &Cancel,
) -> Result<UnitQuaternion<f64>> {
    let (rates, _) = gyro.as_chunks::<3>();
    let (out, _) = out.as_chunks_mut::<4>();
    let gauss = gauss_nodes(t, gyro);
    if !(t[0].is_finite() && rates[0].iter().all(|v| v.is_finite())) {
        return Err(input_error(t, gyro));
    }
    let increments = &mut out[1..];
    let valid = increments.par_chunks_mut(CHUNK).enumerate().all(|(c, chunk)| {
        chunk.iter_mut().enumerate().all(|(j, slot)| {
            let k = c * CHUNK + j;
            let h = t[k + 1] - t[k];
            let ok = h > 0.0 && h <= f64::MAX && rates[k + 1].iter().all(|v| v.is_finite());
            let dq = crate::quat::exp(&group_increment(scheme, &gauss, &Vector3::from(rates[k]), h, k));
            *slot = [dq.i, dq.j, dq.k, dq.w];
            ok
        })
    });
    if !valid {
        return Err(input_error(t, gyro));
    }
    let mut q = initial.into_inner();
    out[0] = [q.i, q.j, q.k, q.w];
    cancel.check(0)?;
    for (k, slot) in out[1..].iter_mut().enumerate() {
        cancel.check(k)?;
        let [x, y, z, w] = *slot;
        q = crate::quat::multiply(&q, &Quaternion::new(w, x, y, z));
        if (k + 1) % RENORMALIZE_EVERY == 0 {
            q = q.project();
        }
        *slot = [q.i, q.j, q.k, q.w];
    }
    let last = UnitQuaternion::new_unchecked(q);
    check_finite_quaternions(&last, Some(out.as_flattened()), t.len())?;
    Ok(last)
}

/// The precise error for inputs that failed the fast in-loop check.
fn input_error(t: &[f64], gyro: &[f64]) -> Error {
    match check_values(t, gyro) {
        Err(e) => e,
        Ok(()) => Error::Parameter {
            name: "t",
            expected: "finite, strictly increasing timestamps",
            got: "a value that failed the in-loop check".into(),
        },
    }
}
