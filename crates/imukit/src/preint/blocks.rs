//! Block algebra of the preintegration covariance: the 9×9 `[δφ, δv, δp]` covariance kept as its
//! six unique 3×3 blocks, 9×6 cross covariances as 3×2 blocks, and the step's inputs.
//!
//! Both schemes keep the rotation error in frame i (`δφ = ΔR δθ`; `mod.rs`, `midpoint.rs`), where
//! every step has the transition `A = [[I, 0, 0], [W h, I, 0], [½ W h², h I, I]]` (`W` the
//! scheme's `∂(specific force in frame i)/∂δφ`, a skew matrix), and every input (white noise of a
//! sample, a bias change, a bias step) enters through a 9×6 matrix `G` (columns `[gyro, accel]`)
//! with no accelerometer term in θ and p rows equal to `h/2` times the v rows. The products below
//! use only that structure: a few 3×3 products per term instead of dense 9×9 ones.

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::mat3::{Lanes, Unfused, M3};

/// The unique blocks `[θθ, θv, θp, vv, vp, pp]` of the 9×9 covariance, held in padded form
/// (`mat3::M3`) between steps: the per-sample kernels read and write them with no conversion
/// (no conversion to and from `Matrix3` per step: shuffles on the AVX paths).
pub(super) type CovarianceBlocks = [M3; 6];

/// A 9×6 matrix as 3×3 blocks: rows `[θ, v, p]`, columns `[gyro, accel]`. Its θ-row accelerometer
/// block is always zero (no accelerometer input reaches δθ, and `A` keeps it so): the products
/// below skip it.
pub(super) type Cross = [[M3; 2]; 3];

pub(super) const ZERO_CROSS: Cross = [[M3::ZERO; 2]; 3];

/// `R [a]×` by columns: column j is `R (a × e_j)`, a difference of two columns of R (27 flops
/// where the dense product with `[a]×` costs 45, its zeros included).
#[inline(always)]
pub(super) fn times_hat(r: &Matrix3<f64>, a: &Vector3<f64>) -> Matrix3<f64> {
    let (c0, c1, c2) = (r.column(0), r.column(1), r.column(2));
    Matrix3::from_columns(&[c1 * a.z - c2 * a.y, c2 * a.x - c0 * a.z, c0 * a.y - c1 * a.x])
}

/// `A Σ Aᵀ` for the frame-i transition (module docs): with `Σ_θθ` symmetric, `Σ_θθ Wᵀ = (W Σ_θθ)ᵀ` and `Σ_vθ Wᵀ = (W Σ_θv)ᵀ`, so
/// four 3×3 products (`W Σ_θθ`, `W Σ_θv`, `W Σ_θp`, `(W Σ_θθ) Wᵀ`) where the body frame's
/// transition, with `Exp(ω̂h)ᵀ` in its θθ block, takes ten.
/// The diagonal blocks are sums of symmetric terms (`X + Xᵀ` formed first), so they come out
/// exactly symmetric with no `(b + bᵀ)/2`:
///
/// ```text
/// vv' = vv + h (W Σ_θv + ·ᵀ) + h² W Σ_θθ Wᵀ
/// vp' = vp + h W Σ_θp + h vv + h² W Σ_θv + ½h² (W Σ_θv)ᵀ + ½h³ W Σ_θθ Wᵀ
/// pp' = pp + h (vp + ·ᵀ) + h² vv + ½h² (W Σ_θp + ·ᵀ) + ½h³ (W Σ_θv + ·ᵀ) + ¼h⁴ W Σ_θθ Wᵀ
/// ```
#[inline(always)]
pub(super) fn propagate_frame_i<L: Lanes>(l: L, cov: &CovarianceBlocks, w: &M3, h: f64) -> CovarianceBlocks {
    let [tt, tv, tp, vv, vp, pp] = *cov;
    let (h2, half_h2) = (h * h, 0.5 * h * h);
    let (w_tt, w_tv, w_tp) = (
        w.zero_diagonal_mul_with(l, &tt),
        w.zero_diagonal_mul_with(l, &tv),
        w.zero_diagonal_mul_with(l, &tp),
    );
    let (w_tt_t, w_tv_t) = (w_tt.transpose(), w_tv.transpose());
    let w_tt_wt = w_tt.mul_t_symmetric_with(l, w);
    let sym_v = w_tv.add_with(l, &w_tv_t);
    let sym_p = w_tp.add_with(l, &w_tp.transpose());
    let sym_vp = vp.add_with(l, &vp.transpose());
    let new_vv = w_tt_wt.mul_add(l, h, &sym_v).mul_add(l, h, &vv);
    let new_vp = w_tt_wt.mul_add(l, h, &w_tv_t).mul_add(
        l,
        half_h2,
        &w_tv.mul_add(l, h2, &vv.mul_add(l, h, &w_tp.mul_add(l, h, &vp))),
    );
    // ¼h⁴ X + ½h³ S_v + ½h² S_p = ½h² (½h² X + h S_v + S_p).
    let new_pp = w_tt_wt.mul_add(l, half_h2, &sym_v.mul_add(l, h, &sym_p)).mul_add(
        l,
        half_h2,
        &vv.mul_add(l, h2, &sym_vp.mul_add(l, h, &pp)),
    );
    [
        tt,
        w_tt_t.mul_add(l, h, &tv),
        w_tt_t.mul_add(l, half_h2, &tv.mul_add(l, h, &tp)),
        new_vv,
        new_vp,
        new_pp,
    ]
}

/// `A X` for a 9×6 cross covariance `X` (the frame-i transition of `w`, `h`: no product in the θ
/// row).
#[inline(always)]
pub(super) fn transition<L: Lanes>(l: L, x: &Cross, w: &M3, h: f64) -> Cross {
    let half_h2 = 0.5 * h * h;
    let [[xtg, _], [xvg, xva], [xpg, xpa]] = *x;
    let w_tg = w.zero_diagonal_mul_with(l, &xtg);
    [
        [xtg, M3::ZERO],
        [w_tg.mul_add(l, h, &xvg), xva],
        [
            xvg.mul_add(l, h, &w_tg.scale_with(l, half_h2)).add_with(l, &xpg),
            xva.mul_add(l, h, &xpa),
        ],
    ]
}

/// `cov += C q_g Cᵀ + B q_a Bᵀ` for one euler interval's white noise in frame i (`mod.rs`):
/// `C = [g; 0; 0]`, `B = [0; R h; ½ R h²]` for a rotation `R`, whose terms are multiples of I
/// (`R Rᵀ = I`): one product, for `g gᵀ`.
#[inline(always)]
pub(super) fn add_held_noise<L: Lanes>(l: L, cov: &mut CovarianceBlocks, g: &M3, q_g: f64, q_a: f64, h: f64) {
    let half_h2 = 0.5 * h * h;
    cov[0] = g.mul_t_symmetric_with(l, g).mul_add(l, q_g, &cov[0]);
    cov[3] = cov[3].plus_identity(q_a * h * h);
    cov[4] = cov[4].plus_identity(q_a * h * half_h2);
    cov[5] = cov[5].plus_identity(q_a * half_h2 * half_h2);
}

/// A step's 9×6 input matrix `G = [[tg, 0], [vg, va], [h/2 vg, h/2 va]]` (columns `[gyro, accel]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Input {
    pub tg: M3,
    pub vg: M3,
    pub va: M3,
    pub half_h: f64,
}

impl Input {
    /// The zero input.
    pub const ZERO: Input = Input {
        tg: M3::ZERO,
        vg: M3::ZERO,
        va: M3::ZERO,
        half_h: 0.0,
    };

    /// The input whose cross covariance form ([`Input::cross`]) is `x`, an input's: its p rows are
    /// `half_h` times its v rows.
    pub fn of_cross(x: &Cross, half_h: f64) -> Input {
        Input {
            tg: x[0][0],
            vg: x[1][0],
            va: x[1][1],
            half_h,
        }
    }

    /// Each block premultiplied by `r`.
    pub fn rotated(&self, r: &M3) -> Input {
        Input {
            tg: r.mul(&self.tg),
            vg: r.mul(&self.vg),
            va: r.mul(&self.va),
            half_h: self.half_h,
        }
    }

    /// The gyro column `[θ, v, p]` of `D = A P + B` (`P` this input, `A` the frame-i transition of
    /// `W`, `h`; `midpoint.rs`); its accelerometer blocks are multiples of a rotation, known apart.
    #[inline(always)]
    pub fn through<L: Lanes>(&self, l: L, w: &M3, h: f64, b: &Input) -> [M3; 3] {
        let w_tg = w.zero_diagonal_mul_with(l, &self.tg);
        // p row: ½h² W P_θ + (h + h'/2) P_v + (h/2) B_v, P's p row being h'/2 times its v row.
        let p_v = self.vg.scale_with(l, h + self.half_h);
        [
            self.tg.add_with(l, &b.tg),
            w_tg.mul_add(l, h, &self.vg).add_with(l, &b.vg),
            w_tg.mul_add(l, 0.5 * h * h, &p_v)
                .add_with(l, &b.vg.scale_with(l, b.half_h)),
        ]
    }

    /// `x + G` for a 9×6 `x`, in `l`'s lanes.
    #[inline(always)]
    pub fn added_to<L: Lanes>(&self, l: L, x: &Cross) -> Cross {
        [
            [x[0][0].add_with(l, &self.tg), x[0][1]],
            [x[1][0].add_with(l, &self.vg), x[1][1].add_with(l, &self.va)],
            [
                self.vg.mul_add(l, self.half_h, &x[2][0]),
                self.va.mul_add(l, self.half_h, &x[2][1]),
            ],
        ]
    }

    /// `G` as a cross covariance.
    #[inline(always)]
    pub fn cross(&self) -> Cross {
        let (vg, va) = (self.vg, self.va);
        [[self.tg, M3::ZERO], [vg, va], [vg * self.half_h, va * self.half_h]]
    }

    /// `G diag(s_g I, s_a I)` as a cross covariance.
    #[inline(always)]
    pub fn scaled(&self, s_g: f64, s_a: f64) -> Cross {
        let (tg, vg, va) = (self.tg * s_g, self.vg * s_g, self.va * s_a);
        Input { tg, vg, va, ..*self }.cross()
    }

    /// `cov += G diag(s_g I, s_a I) Gᵀ` (`va` enters only through `va vaᵀ`). `va_gram` is `Some(c)`
    /// where `va vaᵀ = c I` is known (`va` a multiple of a rotation, or of I): no product for it.
    #[inline(always)]
    pub fn add_quadratic<L: Lanes>(&self, l: L, cov: &mut CovarianceBlocks, s_g: f64, s_a: f64, va_gram: Option<f64>) {
        let tv = self.tg.mul_t_with(l, &self.vg).scale_with(l, s_g);
        let vg_vg = self.vg.mul_t_symmetric_with(l, &self.vg).scale_with(l, s_g);
        let vv = match va_gram {
            Some(c) => vg_vg.plus_identity(c * s_a),
            None => self.va.mul_t_symmetric_with(l, &self.va).mul_add(l, s_a, &vg_vg),
        };
        let c = self.half_h;
        cov[0] = self.tg.mul_t_symmetric_with(l, &self.tg).mul_add(l, s_g, &cov[0]);
        cov[1] = cov[1].add_with(l, &tv);
        cov[2] = tv.mul_add(l, c, &cov[2]);
        cov[3] = cov[3].add_with(l, &vv);
        cov[4] = vv.mul_add(l, c, &cov[4]);
        cov[5] = vv.mul_add(l, c * c, &cov[5]);
    }

    /// `cov += Y Gᵀ + G Yᵀ` for a 9×6 `Y` (a transported cross covariance).
    #[inline(always)]
    pub fn add_cross<L: Lanes>(&self, l: L, cov: &mut CovarianceBlocks, y: &Cross) {
        let c = self.half_h;
        let (vg, va) = (&self.vg, &self.va);
        // u_i = (Y Gᵀ) in block column v; block column p is c u_i, block column θ is y_i0 tgᵀ.
        let u = [
            y[0][0].mul_t_with(l, vg), // y's θ-row accelerometer block is zero
            y[1][0].mul_t_with(l, vg).add_with(l, &y[1][1].mul_t_with(l, va)),
            y[2][0].mul_t_with(l, vg).add_with(l, &y[2][1].mul_t_with(l, va)),
        ];
        let y0t = y[0][0].mul_t_with(l, &self.tg);
        cov[0] += y0t + y0t.transpose();
        cov[1] = cov[1].add_with(l, &u[0].add_with(l, &self.tg.mul_t_with(l, &y[1][0])));
        cov[2] = cov[2].add_with(l, &u[0].mul_add(l, c, &self.tg.mul_t_with(l, &y[2][0])));
        cov[3] += u[1] + u[1].transpose();
        cov[4] = cov[4].add_with(l, &u[1].mul_add(l, c, &u[2].transpose()));
        cov[5] += (u[2] + u[2].transpose()) * c;
    }
}

/// `cov += D diag(q_g I, q_a I) Dᵀ` for a 9×6 `D` with gyro column `[dt, dv, dp]` and accelerometer
/// blocks `0`, `c_v R`, `c_p R` for a rotation `R`: those enter as multiples of I, with no product;
/// the gyro column takes six.
#[inline(always)]
pub(super) fn add_noise<L: Lanes>(
    l: L,
    cov: &mut CovarianceBlocks,
    [dt, dv, dp]: &[M3; 3],
    q_g: f64,
    q_a: f64,
    [c_v, c_p]: [f64; 2],
) {
    let (st, sv, sp) = (dt.scale_with(l, q_g), dv.scale_with(l, q_g), dp.scale_with(l, q_g));
    cov[0] = cov[0].add_with(l, &st.mul_t_symmetric_with(l, dt));
    cov[1] = cov[1].add_with(l, &st.mul_t_with(l, dv));
    cov[2] = cov[2].add_with(l, &st.mul_t_with(l, dp));
    cov[3] = cov[3]
        .add_with(l, &sv.mul_t_symmetric_with(l, dv))
        .plus_identity(q_a * c_v * c_v);
    cov[4] = cov[4].add_with(l, &sv.mul_t_with(l, dp)).plus_identity(q_a * c_v * c_p);
    cov[5] = cov[5]
        .add_with(l, &sp.mul_t_symmetric_with(l, dp))
        .plus_identity(q_a * c_p * c_p);
}

/// `x` with its θ row premultiplied by `r` (its θ-row accelerometer block is zero).
pub(super) fn rotate_rows(x: &Cross, r: &M3) -> Cross {
    let mut out = *x;
    out[0][0] = r.mul(&x[0][0]);
    out
}

/// `T Σ Tᵀ` for `T = diag(r, I, I)`.
pub(super) fn rotate_covariance(cov: &CovarianceBlocks, r: &M3) -> CovarianceBlocks {
    let [tt, tv, tp, vv, vp, pp] = *cov;
    let r_tt = r.mul(&tt);
    [
        r_tt.mul_t_symmetric_with(Unfused, r),
        r.mul(&tv),
        r.mul(&tp),
        vv,
        vp,
        pp,
    ]
}

/// Block-wise `a + b` for cross covariances.
#[inline(always)]
pub(super) fn add(a: &Cross, b: &Cross) -> Cross {
    let row = |i: usize| [a[i][0] + b[i][0], a[i][1] + b[i][1]];
    [row(0), row(1), row(2)]
}

/// The 9×9 matrix of the blocks.
pub(super) fn assemble(blocks: &CovarianceBlocks) -> SMatrix<f64, 9, 9> {
    let mut out = SMatrix::<f64, 9, 9>::zeros();
    let places = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    for ((i, j), b) in places.into_iter().zip(blocks) {
        let b = b.matrix();
        out.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&b);
        out.fixed_view_mut::<3, 3>(3 * j, 3 * i).copy_from(&b.transpose());
    }
    out
}

/// The unique blocks of a symmetric 9×9 matrix.
pub(super) fn blocks_of(m: &SMatrix<f64, 9, 9>) -> CovarianceBlocks {
    let b = |i: usize, j: usize| M3::of(&m.fixed_view::<3, 3>(3 * i, 3 * j).into_owned());
    [b(0, 0), b(0, 1), b(0, 2), b(1, 1), b(1, 2), b(2, 2)]
}

/// A cross covariance as a dense 9×6 matrix.
pub(super) fn cross_matrix(x: &Cross) -> SMatrix<f64, 9, 6> {
    let mut out = SMatrix::<f64, 9, 6>::zeros();
    for (i, row) in x.iter().enumerate() {
        for (j, b) in row.iter().enumerate() {
            out.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&b.matrix());
        }
    }
    out
}

/// The blocks of a dense 9×6 matrix.
pub(super) fn cross_of(m: &SMatrix<f64, 9, 6>) -> Cross {
    std::array::from_fn(|i| std::array::from_fn(|j| M3::of(&m.fixed_view::<3, 3>(3 * i, 3 * j).into_owned())))
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Vector3};

    use crate::so3::hat;

    /// The column form against the dense product with `[a]×`.
    #[test]
    fn times_hat_is_the_product_with_hat() {
        let r = Matrix3::new(0.3, -1.2, 2.5, 0.7, 0.1, -0.4, -2.2, 1.9, 0.6);
        let a = Vector3::new(9.81, -0.37, 1.4);
        let err = (super::times_hat(&r, &a) - r * hat(&a)).abs().max();
        assert!(err < 1e-14, "{err:e}");
    }
}
