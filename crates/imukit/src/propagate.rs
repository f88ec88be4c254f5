//! Error-state covariance propagation along a strapdown integration (ESKF; Solà, "Quaternion
//! kinematics for the error-state Kalman filter", 2017, §5.4).
//!
//! | item | convention |
//! |---|---|
//! | error state δx (15) | `[δp, δv, δθ, δb_a, δb_g]` (Solà's order) |
//! | perturbations | `p = p̂ + δp`, `v = v̂ + δv`, `R = R̂ Exp(δθ)` (right, local), `b = b̂ + δb` |
//! | impulses i (12) | `[v_i, θ_i, a_i, ω_i]`: velocity, angle, accelerometer-bias and gyro-bias steps |
//! | `Q_i` | `diag(σ_a² h, σ_g² h, σ_ba² h, σ_bg² h) ⊗ I₃` from continuous densities ([`Noise`]) |
//!
//! The discrete step whose Jacobians are used is the first-order one, with impulses:
//! `p⁺ = p + v h + ½(R â + g) h²`, `v⁺ = v + (R â + g) h + v_i`, `R⁺ = R Exp(ω̂ h + θ_i)`,
//! `b_a⁺ = b_a + a_i`, `b_g⁺ = b_g + ω_i` with `â = a_m − b_a`, `ω̂ = ω_m − b_g`. Its exact
//! Jacobians (tested against central differences) are, in 3×3 blocks,
//!
//! ```text
//!       δp   δv    δθ              δb_a        δb_g                v_i  θ_i     a_i  ω_i
//! F_x = I    hI   −½h² R[â]×      −½h² R      0             F_i = 0    0       0    0
//!       0    I    −h R[â]×        −h R        0                   I    0       0    0
//!       0    0    Exp(ω̂h)ᵀ        0           −h J_r(ω̂h)          0    J_r(ω̂h) 0    0
//!       0    0    0               I           0                   0    0       I    0
//!       0    0    0               0           I                   0    0       0    I
//! ```
//!
//! **Rotating world** ([`Options::earth_rate`] `Ω` non-zero, a fixed [`crate::earth::LocalLevel`]):
//! the mean takes the Earth's turn and Coriolis as strapdown does; with the right perturbation the
//! turn `Exp(−Ωh)` on the left of `R` leaves `δθ` unchanged, and the Coriolis term adds
//! `−2h [Ω]×` to `∂δv⁺/∂δv` and `−h² [Ω]×` to `∂δp⁺/∂δv`, applied as a separate factor after the
//! step (`coriolis_blocks`; its cross terms with the step are O(h²), below the step's order).
//!
//! **Lever arm and a frame that follows the vehicle** ([`Model`], [`propagate_model`]): a dense
//! step that carries the lever-arm conversion's gyro noise across the three samples it spans, and
//! for the ellipsoid the error model of [`crate::ellipsoid_errors`] (module `augmented`).
//!
//! Solà's §5.4.3 drops the h² terms of the position row and uses `I` for `J_r`; both are kept here
//! because they cost nothing in the block product. The mean may be integrated with any
//! [`strapdown::Scheme`]; the covariance always uses these Jacobians at
//! the state and sample at the start of each step (their difference from the scheme's own
//! Jacobians is O(h) relative per step).

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::earth::LocalLevel;
use crate::imu::{Bias, NavState, Noise, Samples};
use crate::mat3::{Lanes, M3};
use crate::simd::Path;
use crate::strapdown::{self, Options, StatesOut, Stepper};
use crate::{so3, Cancel, Error, Result};

mod augmented;

/// 15×15 error-state covariance, order `[δp, δv, δθ, δb_a, δb_g]`.
pub type Covariance = SMatrix<f64, 15, 15>;

/// What the readings and the world are beyond an IMU at the body origin in a fixed world
/// ([`propagate_model`]); the default is neither.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Model {
    /// The sensor's lever arm `r` in body axes \[m\]: the readings given are the body origin's,
    /// converted by [`crate::extrinsics::to_body`] (biases removed, α the central difference of
    /// the gyro), and the covariance carries the gyro noise that conversion puts into the specific
    /// force (`augmented` module docs). Zero for none.
    pub lever_arm: Vector3<f64>,
    /// A local-level frame that follows the vehicle ([`crate::ellipsoid`]): the mean is
    /// [`crate::ellipsoid::integrate`]'s (positions `(φ, λ, h)`), the covariance the error model
    /// of [`crate::ellipsoid_errors`]; `options.gravity` and `options.earth_rate` are unused.
    pub transport: Option<LocalLevel>,
}

/// The step Jacobians as dense matrices (the propagation itself uses their block structure).
#[derive(Debug, Clone, PartialEq)]
pub struct StepJacobians {
    /// `∂δx⁺/∂δx`, 15×15.
    pub f_x: Covariance,
    /// `∂δx⁺/∂i`, 15×12.
    pub f_i: SMatrix<f64, 15, 12>,
}

/// Blocks of one step: `R`, `[â]×`, `Exp(ω̂h)ᵀ`, `J_r(ω̂h)`.
struct StepBlocks {
    r: Matrix3<f64>,
    a_cross: Matrix3<f64>,
    phi_t: Matrix3<f64>,
    jr: Matrix3<f64>,
}

impl StepBlocks {
    #[inline(always)]
    fn new(x: &NavState, w_hat: &Vector3<f64>, a_hat: &Vector3<f64>, h: f64) -> Self {
        // `Exp` and `J_r` from one θ (one set of series coefficients).
        let (exp, jr) = so3::exp_and_right_jacobian(&(w_hat * h));
        Self {
            r: *x.rotation.to_rotation_matrix().matrix(),
            a_cross: so3::hat(a_hat),
            phi_t: exp.transpose(),
            jr,
        }
    }
}

/// Dense `F_x`, `F_i` of the first-order step from `x` with bias-corrected inputs `ω̂`, `â`.
pub fn step_jacobians(x: &NavState, w_hat: &Vector3<f64>, a_hat: &Vector3<f64>, h: f64) -> StepJacobians {
    let b = StepBlocks::new(x, w_hat, a_hat, h);
    let i3 = Matrix3::identity();
    let mut f_x = Covariance::identity();
    let mut set = |r: usize, c: usize, m: Matrix3<f64>| f_x.fixed_view_mut::<3, 3>(3 * r, 3 * c).copy_from(&m);
    set(0, 1, i3 * h);
    set(0, 2, -b.r * b.a_cross * (0.5 * h * h));
    set(0, 3, -b.r * (0.5 * h * h));
    set(1, 2, -b.r * b.a_cross * h);
    set(1, 3, -b.r * h);
    set(2, 2, b.phi_t);
    set(2, 4, -b.jr * h);
    let mut f_i = SMatrix::<f64, 15, 12>::zeros();
    f_i.fixed_view_mut::<3, 3>(3, 0).copy_from(&i3);
    f_i.fixed_view_mut::<3, 3>(6, 3).copy_from(&b.jr);
    f_i.fixed_view_mut::<3, 3>(9, 6).copy_from(&i3);
    f_i.fixed_view_mut::<3, 3>(12, 9).copy_from(&i3);
    StepJacobians { f_x, f_i }
}

/// `Q_i` for a step of `h` seconds.
pub fn impulse_covariance(noise: &Noise, h: f64) -> SMatrix<f64, 12, 12> {
    let d = [
        noise.accel_density,
        noise.gyro_density,
        noise.accel_random_walk,
        noise.gyro_random_walk,
    ];
    SMatrix::<f64, 12, 12>::from_diagonal(&SMatrix::<f64, 12, 1>::from_fn(|i, _| d[i / 3] * d[i / 3] * h))
}

/// The covariance as 5×5 blocks of 3×3, the form the propagation works in (padded blocks,
/// `mat3::M3`, so that the block algebra runs in whole vector registers). The step reads and
/// writes only the upper block triangle `i ≤ j` (a lower block is the transpose of its mirror,
/// [`block`]); the blocks below it are stale but for [`coriolis_blocks`], which fills them first.
type Blocks = [[M3; 5]; 5];
const P: usize = 0;
const V: usize = 1;
const TH: usize = 2;
const BA: usize = 3;
const BG: usize = 4;

/// Block `(i, j)` of the symmetric covariance held in the upper triangle of `b`.
#[inline(always)]
fn block(b: &Blocks, i: usize, j: usize) -> M3 {
    if i <= j {
        b[i][j]
    } else {
        b[j][i].transpose()
    }
}

/// The blocks of `c`, the upper triangle of `(c + cᵀ)/2` (`c` itself when it is symmetric).
fn to_blocks(c: &Covariance) -> Blocks {
    let full: Blocks =
        std::array::from_fn(|i| std::array::from_fn(|j| M3::of(&c.fixed_view::<3, 3>(3 * i, 3 * j).into_owned())));
    std::array::from_fn(|i| std::array::from_fn(|j| (full[i][j] + full[j][i].transpose()) * 0.5))
}

/// The covariance as a row-major 15×15, each element stored once: row `r` of a lower block
/// `(i, j)`, `j < i`, is column `r` of the stored `U_ji` (three contiguous values, no transposed
/// block formed); row `r` of an upper one is gathered from its columns.
#[inline]
fn write_blocks(b: &Blocks, out: &mut [f64; 225]) {
    for (row, out_row) in out.as_chunks_mut::<15>().0.iter_mut().enumerate() {
        let (i, r) = (row / 3, row % 3);
        for (j, cell) in out_row.as_chunks_mut::<3>().0.iter_mut().enumerate() {
            *cell = if j < i {
                let c = &b[j][i].0[r].0;
                [c[0], c[1], c[2]]
            } else {
                let u = &b[i][j].0;
                [u[0].0[r], u[1].0[r], u[2].0[r]]
            };
        }
    }
}

/// `P ← F_x P F_xᵀ + F_i Q_i F_iᵀ` using the block structure of `F_x` (module docs): only the
/// blocks of `A = F_x P` that the upper block triangle of `A F_xᵀ` reads are formed, with
/// `R [â]×` and `R` shared between the δp and δv rows ([`Blocks`]: the upper triangle only).
// Per sample: inlined into each instruction-set copy of the loop ([`block_loop`]).
#[allow(clippy::needless_range_loop)] // block indices name error-state components (P, V, TH, …)
#[inline(always)]
fn propagate_blocks<L: Lanes>(l: L, p: &mut Blocks, b: &StepBlocks, noise: &Noise, h: f64) {
    let half_h2 = 0.5 * h * h;
    let (r, a_cross, phi_t, jr) = (M3::of(&b.r), M3::of(&b.a_cross), M3::of(&b.phi_t), M3::of(&b.jr));
    let (ra, h_jr) = (r.mul_with(l, &a_cross), jr.scale_with(l, h));
    // Row δp of A: all five block columns; row δv: columns δv…; row δθ: columns δθ…, with
    // n_j = R ([â]× P_θj + P_aj) the common part of rows δp and δv. Array literals, not loops
    // over zeroed arrays (those stayed `memset` calls). The block algebra runs in `l`'s lanes
    // (fused on the AVX paths, `mat3`'s module docs); nested fns, not closures, for the same
    // reason.
    let u = &*p;
    #[inline(always)]
    fn sum<L: Lanes>(l: L, x: M3, y: M3) -> M3 {
        x.add_with(l, &y)
    }
    // Lower blocks P_ij = U_jiᵀ enter through `mul_t` (X P_ij = X U_jiᵀ) or one transpose.
    let n = [
        sum(l, ra.mul_t_with(l, &u[P][TH]), r.mul_t_with(l, &u[P][BA])),
        sum(l, ra.mul_t_with(l, &u[V][TH]), r.mul_t_with(l, &u[V][BA])),
        sum(l, ra.mul_with(l, &u[TH][TH]), r.mul_t_with(l, &u[TH][BA])),
        sum(l, ra.mul_with(l, &u[TH][BA]), r.mul_with(l, &u[BA][BA])),
        sum(l, ra.mul_with(l, &u[TH][BG]), r.mul_with(l, &u[BA][BG])),
    ];
    // `u_pj + p_vj h − n_j h²/2` and `u_vj − n_j h`.
    #[inline(always)]
    fn row_p<L: Lanes>(l: L, u_pj: &M3, p_vj: &M3, n_j: &M3, h: f64, half_h2: f64) -> M3 {
        n_j.mul_add(l, -half_h2, &p_vj.mul_add(l, h, u_pj))
    }
    let a_p = [
        row_p(l, &u[P][P], &u[P][V].transpose(), &n[P], h, half_h2),
        row_p(l, &u[P][V], &u[V][V], &n[V], h, half_h2),
        row_p(l, &u[P][TH], &u[V][TH], &n[TH], h, half_h2),
        row_p(l, &u[P][BA], &u[V][BA], &n[BA], h, half_h2),
        row_p(l, &u[P][BG], &u[V][BG], &n[BG], h, half_h2),
    ];
    let a_v = [
        M3::ZERO,
        n[V].mul_add(l, -h, &u[V][V]),
        n[TH].mul_add(l, -h, &u[V][TH]),
        n[BA].mul_add(l, -h, &u[V][BA]),
        n[BG].mul_add(l, -h, &u[V][BG]),
    ];
    // `x yᵀ − z wᵀ`.
    #[inline(always)]
    fn diff<L: Lanes>(l: L, x: M3, z: M3) -> M3 {
        z.mul_add(l, -1.0, &x)
    }
    let a_th = [
        M3::ZERO,
        M3::ZERO,
        diff(l, phi_t.mul_with(l, &u[TH][TH]), h_jr.mul_t_with(l, &u[TH][BG])),
        diff(l, phi_t.mul_with(l, &u[TH][BA]), h_jr.mul_t_with(l, &u[BA][BG])),
        diff(l, phi_t.mul_with(l, &u[TH][BG]), h_jr.mul_with(l, &u[BG][BG])),
    ];
    // P' = A F_xᵀ on the upper block triangle.
    let np = sum(l, a_p[TH].mul_t_with(l, &a_cross), a_p[BA]).mul_t_with(l, &r);
    let nv = sum(l, a_v[TH].mul_t_with(l, &a_cross), a_v[BA]).mul_t_with(l, &r);
    p[P][P] = np.mul_add(l, -half_h2, &a_p[V].mul_add(l, h, &a_p[P]));
    p[P][V] = np.mul_add(l, -h, &a_p[V]);
    p[V][V] = nv.mul_add(l, -h, &a_v[V]);
    p[P][TH] = diff(l, a_p[TH].mul_t_with(l, &phi_t), a_p[BG].mul_t_with(l, &h_jr));
    p[V][TH] = diff(l, a_v[TH].mul_t_with(l, &phi_t), a_v[BG].mul_t_with(l, &h_jr));
    p[TH][TH] = diff(l, a_th[TH].mul_t_with(l, &phi_t), a_th[BG].mul_t_with(l, &h_jr));
    for (i, row) in [(P, &a_p), (V, &a_v), (TH, &a_th)] {
        p[i][BA] = row[BA];
        p[i][BG] = row[BG];
    }
    let q = |d: f64| d * d * h;
    p[V][V] = p[V][V].plus_identity(q(noise.accel_density));
    p[TH][TH] = jr.mul_t_with(l, &jr).mul_add(l, q(noise.gyro_density), &p[TH][TH]);
    p[BA][BA] = p[BA][BA].plus_identity(q(noise.accel_random_walk));
    p[BG][BG] = p[BG][BG].plus_identity(q(noise.gyro_random_walk));
    for d in P..=BG {
        // Exact symmetry on the diagonal blocks.
        p[d][d] = p[d][d].symmetric();
    }
}

/// The rotating world's terms of the step (module docs, "Rotating world"): `P ← D P Dᵀ` with `D = I`
/// but for the post-step `δv` column, `D_pv = −h² [Ω]×`, `D_vv = I − 2h [Ω]×`, the Coriolis
/// acceleration `−2 Ω × δv` of the velocity error (Groves 2013, §14.2, the local-level error model
/// without its transport and gravity-gradient terms). Applied after the inertial step so that the default path pays nothing.
#[allow(clippy::needless_range_loop)] // block indices name error-state components
#[inline(always)]
fn coriolis_blocks(p: &mut Blocks, omega: &Vector3<f64>, h: f64) {
    for i in P..=BG {
        for j in 0..i {
            p[i][j] = p[j][i].transpose();
        }
    }
    let w = so3::hat(omega);
    let (d_pv, d_vv) = (M3::of(&(w * (-h * h))), M3::of(&(Matrix3::identity() - w * (2.0 * h))));
    let [row_p, row_v, ..] = p;
    for (pj, vj) in row_p.iter_mut().zip(row_v.iter_mut()) {
        *pj += d_pv.mul(vj);
        *vj = d_vv.mul(vj);
    }
    for row in p.iter_mut() {
        let av = row[V];
        row[P] += av.mul_t(&d_pv);
        row[V] = av.mul_t(&d_vv);
    }
}

/// What the default model's step reads besides the covariance.
struct BlockRun<'a> {
    samples: &'a Samples<'a>,
    bias: &'a Bias,
    noise: &'a Noise,
    options: &'a Options,
}

/// Called after each step with `k`, the state at `k + 1` and the covariance.
type Visit<'v> = dyn FnMut(usize, &NavState, &Blocks) -> Result<()> + 'v;

/// The covariance step from sample k at state `x` (module docs).
#[inline(always)]
fn block_step<L: Lanes>(l: L, p: &mut Blocks, run: &BlockRun<'_>, k: usize, x: &NavState) {
    let s = run.samples;
    let h = s.t[k + 1] - s.t[k];
    let w_hat = s.gyro_at(k) - run.bias.gyro;
    let a_hat = s.accel_at(k) - run.bias.accel;
    propagate_blocks(l, p, &StepBlocks::new(x, &w_hat, &a_hat, h), run.noise, h);
    if run.options.earth_rate != Vector3::zeros() {
        coriolis_blocks(p, &run.options.earth_rate, h);
    }
}

/// The default model's loop, `fn $name(run, x0, p, visit)`: the strapdown stepper with
/// [`block_step`] as its visitor, the stepper's loop compiled into it ([`Stepper::run_here`], not
/// dispatched again: on the AVX-512 path 0.90× the time with one covariance in 1000 kept, results
/// equal bit for bit). Written out for the baseline and the AVX2 paths of [`crate::simd`]
/// (the features as there) because a closure inherits the target features of the function it is
/// written in: a closure written in a `simd_dispatch!` body would run on the baseline target
/// whatever the path, unless inlined.
macro_rules! block_loop {
    ($(#[$meta:meta])* $name:ident, $fma:expr) => {
        $(#[$meta])*
        fn $name(run: &BlockRun<'_>, x0: NavState, p: &mut Blocks, visit: &mut Visit<'_>) -> Result<NavState> {
            crate::mat3::with_lanes!($fma, |l| Stepper::new(*run.samples, *run.bias, *run.options).run_here(
                x0,
                |k, x, next| {
                    block_step(l, p, run, k, x);
                    visit(k, next, p)
                }
            ))
        }
    };
}

block_loop!(baseline_loop, false);
block_loop!(
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2")]
    avx2_loop,
    true
);

/// [`block_loop`] on the process's path ([`crate::simd::path`]); the AVX-512 path takes the AVX2
/// copy, which ran about 1.5× faster (LLVM packs pairs of padded columns into 512-bit registers
/// at the cost of shuffles; docs/performance.md).
fn run_blocks(run: &BlockRun<'_>, x0: NavState, p: &mut Blocks, visit: &mut Visit<'_>) -> Result<NavState> {
    match crate::simd::path() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `path()` is `Avx2` or `Avx512` only where the CPU has every feature `avx2_loop`
        // enables.
        #[allow(unsafe_code)]
        Path::Avx2 | Path::Avx512 => unsafe { avx2_loop(run, x0, p, visit) },
        _ => baseline_loop(run, x0, p, visit),
    }
}

/// Output buffers of [`propagate`].
#[derive(Debug)]
pub struct Outputs<'a> {
    /// Every state, or `None`.
    pub states: Option<StatesOut<'a>>,
    /// Covariances (one row-major 15×15 per row) at samples `0, every, 2·every, …` and the last
    /// sample.
    pub covariances: &'a mut [[f64; 225]],
    /// Stride of the stored covariances (≥ 1).
    pub every: usize,
}

/// How many covariances [`propagate`] stores for `n` samples with stride `every`.
pub fn covariance_count(n: usize, every: usize) -> usize {
    if n == 0 || every == 0 {
        return 0;
    }
    (n - 1) / every + 1 + usize::from(!(n - 1).is_multiple_of(every))
}

/// Integrates the mean with `options.scheme` and propagates `covariance` (initial, at sample 0)
/// with the step Jacobians of the module docs. Returns the final state and covariance.
pub fn propagate(
    samples: &Samples<'_>,
    initial: &NavState,
    covariance: &Covariance,
    bias: &Bias,
    noise: &Noise,
    options: &Options,
    outputs: Outputs<'_>,
) -> Result<(NavState, Covariance)> {
    let model = Model::default();
    let setup = Setup {
        bias,
        noise,
        options,
        model: &model,
    };
    propagate_model(samples, initial, covariance, setup, outputs, &Cancel::new())
}

/// The inputs of [`propagate_model`] besides the samples, the initial state and covariance.
#[derive(Debug, Clone, Copy)]
pub struct Setup<'a> {
    /// The biases removed from the samples.
    pub bias: &'a Bias,
    /// The noise densities.
    pub noise: &'a Noise,
    /// Scheme, gravity and the fixed world's rotation rate.
    pub options: &'a Options,
    /// Lever arm and frame that follows the vehicle ([`Model`]).
    pub model: &'a Model,
}

/// [`propagate`] with a lever arm or a frame that follows the vehicle ([`Model`]), stopping with
/// [`Error::Interrupted`] when `cancel` is set (polled every [`Cancel::EVERY`] samples). The
/// default model takes the block-structured step of the module docs, any other the dense
/// augmented step (`augmented` module docs).
pub fn propagate_model(
    samples: &Samples<'_>,
    initial: &NavState,
    covariance: &Covariance,
    setup: Setup<'_>,
    outputs: Outputs<'_>,
    cancel: &Cancel,
) -> Result<(NavState, Covariance)> {
    let Setup {
        bias,
        noise,
        options,
        model,
    } = setup;
    noise.check()?;
    strapdown::check_parameters(initial, bias, options)?;
    let n = samples.t.len();
    let Outputs {
        mut states,
        covariances,
        every,
    } = outputs;
    if every == 0 {
        return Err(Error::Parameter {
            name: "every",
            expected: "a stride of at least 1",
            got: "0".into(),
        });
    }
    if covariances.len() != covariance_count(n, every) {
        let e = Error::RowCount {
            input: covariance_count(n, every),
            output: covariances.len(),
        };
        return Err(e.in_argument("covariances"));
    }
    if let Some(out) = states.as_ref() {
        out.check(n)?;
    }
    let symmetric = (covariance - covariance.transpose()).amax() <= 1e-9 * covariance.amax();
    let nonnegative_diagonal = covariance.diagonal().iter().all(|v| *v >= 0.0);
    if !(covariance.iter().all(|v| v.is_finite()) && symmetric && nonnegative_diagonal) {
        return Err(Error::Parameter {
            name: "covariance",
            expected: "a finite, symmetric 15×15 matrix with a non-negative diagonal",
            got: "one that is not".into(),
        });
    }
    let mut p = to_blocks(covariance);
    let mut stored = 0;
    if let Some(out) = states.as_mut() {
        out.store(0, initial);
    }
    write_blocks(&p, &mut covariances[0]);
    // After step k: the state, the covariance when its stride comes, the cancel flag.
    let mut sink = |k: usize, next: &NavState, write: &dyn Fn(&mut [f64; 225])| {
        if let Some(out) = states.as_mut() {
            out.store(k + 1, next);
        }
        if (k + 1).is_multiple_of(every) || k + 2 == n {
            stored += 1;
            write(&mut covariances[stored]);
        }
        cancel.check(k)
    };
    let (x, last) = if *model == Model::default() {
        let run = BlockRun {
            samples,
            bias,
            noise,
            options,
        };
        let mut visit = |k: usize, next: &NavState, p: &Blocks| sink(k, next, &|out| write_blocks(p, out));
        let x = run_blocks(&run, *initial, &mut p, &mut visit)?;
        let mut last = Covariance::zeros();
        for i in P..=BG {
            for j in P..=BG {
                last.fixed_view_mut::<3, 3>(3 * i, 3 * j)
                    .copy_from(&block(&p, i, j).matrix());
            }
        }
        (x, last)
    } else {
        augmented::run(
            samples,
            initial,
            covariance,
            bias,
            noise,
            options,
            model,
            |k, next, p| {
                // Row-major 15×15 (nalgebra stores columns; the matrix is symmetric to rounding).
                sink(k, next, &|out| {
                    for (i, row) in out.as_chunks_mut::<15>().0.iter_mut().enumerate() {
                        for (j, v) in row.iter_mut().enumerate() {
                            *v = p[(i, j)];
                        }
                    }
                })
            },
        )?
    };
    strapdown::check_finite_result(&x, states.as_ref(), (samples, initial, bias, options))?;
    if !last.iter().all(|v| v.is_finite()) {
        // The mean is finite: the covariance ends near (P₀ + Q)·(1 + D)², D the largest
        // |ω − b_g|·T or |a − b_a|·T of the error-state Jacobian (Sola 2017, eq. 269). Blame the larger
        // factor, in logarithms: the rates or biases that D comes from, else P₀ or the noise Q.
        let span = samples.t[n - 1] - samples.t[0];
        let densities = [
            noise.gyro_density,
            noise.accel_density,
            noise.gyro_random_walk,
            noise.accel_random_walk,
        ];
        let added = densities.iter().fold(0.0_f64, |m, d| m.max(d * d * span));
        let readings = strapdown::largest(samples.gyro).max(strapdown::largest(samples.accel));
        let biases = bias.gyro.amax().max(bias.accel.amax());
        let growth = 2.0 * (1.0 + readings.max(biases) * span).log10();
        let name = if growth > covariance.amax().max(added).log10().max(0.0) {
            if biases > readings {
                "bias"
            } else {
                "imu"
            }
        } else if added > covariance.amax() {
            "noise"
        } else {
            "covariance"
        };
        return Err(Error::Overflow { index: n - 1 }.in_argument(name));
    }
    Ok((x, last))
}
