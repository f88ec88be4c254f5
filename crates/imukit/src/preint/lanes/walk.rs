//! The bias random walk (`combined`) in lanes: `BiasWalk::step` and `Input::add_quadratic`
//! (`preint/mod.rs`, `preint/blocks.rs`), element for element.

use super::{transition, In, Lanes, B};
use crate::preint::blocks::ZERO_CROSS;
use crate::preint::{BiasWalk, Noise};

/// The bias part of the 15×15 covariance, per lane: `Cov(δx, δb)` as `[θg, vg, va, pg, pa]` and
/// the bias variances `[gyro, accel]`.
pub(super) struct Walk<V> {
    pub(super) cross: [B<V>; 5],
    pub(super) var: [V; 2],
}

impl<V: Lanes> Walk<V> {
    /// Every lane at `w`.
    pub(super) fn of(k: V, w: &BiasWalk) -> Self {
        let [[tg, _], [vg, va], [pg, pa]] = &w.cross;
        Walk {
            cross: [tg, vg, va, pg, pa].map(|m| B::splat(k, m)),
            var: [k.splat(w.var_gyro), k.splat(w.var_accel)],
        }
    }

    /// Lane `i`.
    pub(super) fn lane(&self, i: usize) -> BiasWalk {
        let [tg, vg, va, pg, pa] = self.cross.each_ref().map(|b| b.m3(i));
        let mut cross = ZERO_CROSS;
        cross[0][0] = tg;
        cross[1] = [vg, va];
        cross[2] = [pg, pa];
        BiasWalk {
            cross,
            var_gyro: self.var[0].lane(i),
            var_accel: self.var[1].lane(i),
        }
    }

    /// `BiasWalk::step`: the cross terms of `F Σ₁₅ Fᵀ` added to `cov`, the cross and the bias
    /// variances propagated over `h` (`2 g_b.half_h`).
    #[inline(always)]
    pub(super) fn step(&mut self, cov: &mut [B<V>; 6], w: &B<V>, g_b: &In<V>, noise: &Noise) {
        let k = g_b.half_h;
        let h = k.splat(2.0) * g_b.half_h;
        let half_h2 = k.splat(0.5) * h * h;
        let y = transition(&self.cross, w, h, half_h2);
        // `Input::add_cross`: `cov += Y Gᵀ + G Yᵀ`.
        let c = g_b.half_h;
        let (tg, vg, va) = (&g_b.tg, &g_b.vg, &g_b.va);
        let [y_tg, y_vg, y_va, y_pg, y_pa] = &y;
        let u = [
            y_tg.mul_t(vg),
            y_vg.mul_t(vg).add(&y_va.mul_t(va)),
            y_pg.mul_t(vg).add(&y_pa.mul_t(va)),
        ];
        let y0t = y_tg.mul_t(tg);
        cov[0] = cov[0].add(&y0t.add(&y0t.transpose()));
        cov[1] = cov[1].add(&u[0].add(&tg.mul_t(y_vg)));
        cov[2] = cov[2].add(&u[0].mul_add(c, &tg.mul_t(y_pg)));
        cov[3] = cov[3].add(&u[1].add(&u[1].transpose()));
        cov[4] = cov[4].add(&u[1].mul_add(c, &u[2].transpose()));
        cov[5] = cov[5].add(&u[2].add(&u[2].transpose()).scale(c));
        // `blocks::add(y, g_b.scaled(var_g, var_a))`.
        let [s_g, s_a] = self.var;
        let (stg, svg, sva) = (tg.scale(s_g), vg.scale(s_g), va.scale(s_a));
        self.cross = [
            y_tg.add(&stg),
            y_vg.add(&svg),
            y_va.add(&sva),
            y_pg.add(&svg.scale(c)),
            y_pa.add(&sva.scale(c)),
        ];
        let (rw_g, rw_a) = (noise.gyro_random_walk, noise.accel_random_walk);
        self.var = [
            self.var[0] + k.splat(rw_g * rw_g) * h,
            self.var[1] + k.splat(rw_a * rw_a) * h,
        ];
    }
}

impl<V: Lanes> In<V> {
    /// `cov += G diag(s_g I, s_a I) Gᵀ` (`Input::add_quadratic` with no Gram shortcut).
    #[inline(always)]
    pub(super) fn add_quadratic(&self, cov: &mut [B<V>; 6], [s_g, s_a]: [V; 2]) {
        let tv = self.tg.mul_t(&self.vg).scale(s_g);
        let vg_vg = self.vg.mul_t_symmetric(&self.vg).scale(s_g);
        let vv = self.va.mul_t_symmetric(&self.va).mul_add(s_a, &vg_vg);
        let c = self.half_h;
        cov[0] = self.tg.mul_t_symmetric(&self.tg).mul_add(s_g, &cov[0]);
        cov[1] = cov[1].add(&tv);
        cov[2] = tv.mul_add(c, &cov[2]);
        cov[3] = cov[3].add(&vv);
        cov[4] = vv.mul_add(c, &cov[4]);
        cov[5] = vv.mul_add(c * c, &cov[5]);
    }
}
