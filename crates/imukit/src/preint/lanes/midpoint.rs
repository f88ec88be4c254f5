//! The midpoint interval in lanes: `Preintegrator::integrate_midpoint` (`preint/midpoint.rs`),
//! element for element, with unit variance scales. What the scheme carries from
//! one interval to the next (the last point, its noise variances, the pending input `P`, the
//! window's start cross covariance) is kept per lane in [`Mid`].

use nalgebra::Vector3;

use super::{exp_and_right_jacobian, hat_neg, propagate, transition, In, Lanes, State, B};
use crate::preint::blocks::Input;
use crate::preint::midpoint::{Ends, Sample};
use crate::preint::Preintegrator;

/// A point of a midpoint window: `[accel, gyro]`, each lane-wise.
pub(in crate::preint) type Point<V> = [[V; 3]; 2];

/// The midpoint scheme's memory between intervals, per lane.
pub(in crate::preint) struct Mid<V> {
    /// The window's first point.
    first: Point<V>,
    /// The last point, where the next interval starts.
    last: Point<V>,
    /// Noise variances `[gyro, accel]` of the first point (set by the first interval).
    first_var: [V; 2],
    /// Those of the last point (from the interval it ends).
    last_var: [V; 2],
    /// `P`, the response of the error to the last point's noise (zero before the first interval).
    pending: In<V>,
    /// `Cov(δx, n_first)` as `[θg, vg, va, pg, pa]`.
    start_cross: [B<V>; 5],
}

impl<V: Lanes> Mid<V> {
    /// A window about to start at `first` (lane-wise), before its first interval.
    pub(in crate::preint) fn start(first: Point<V>) -> Self {
        let zero = first[0][0].splat(0.0);
        let block = B([zero; 9]);
        Mid {
            first,
            last: first,
            first_var: [zero; 2],
            last_var: [zero; 2],
            pending: In {
                tg: block,
                vg: block,
                va: block,
                half_h: zero,
            },
            start_cross: [block; 5],
        }
    }

    /// Lane `i`'s `ends` written into `p` (the variance scales 1: no lane holds a clipped sample).
    pub(in crate::preint) fn write_lane(&self, i: usize, p: &mut Preintegrator) {
        let vector = |v: &[V; 3]| Vector3::new(v[0].lane(i), v[1].lane(i), v[2].lane(i));
        let sample = |point: &Point<V>, var: &[V; 2]| Sample {
            accel: vector(&point[0]),
            gyro: vector(&point[1]),
            var: Some([var[0].lane(i), var[1].lane(i)]),
            scale: [1.0, 1.0],
        };
        let [tg, vg, va, pg, pa] = self.start_cross.each_ref().map(|b| b.m3(i));
        p.ends = Ends {
            first: Some(sample(&self.first, &self.first_var)),
            last: Some(sample(&self.last, &self.last_var)),
            start_cross: [[tg, crate::mat3::M3::ZERO], [vg, va], [pg, pa]],
            pending: Input {
                tg: self.pending.tg.m3(i),
                vg: self.pending.vg.m3(i),
                va: self.pending.va.m3(i),
                half_h: self.pending.half_h.lane(i),
            },
        };
    }
}

impl<V: Lanes> State<V> {
    /// One midpoint interval in every lane, from `mid`'s last point to `(accel, gyro)` over `h`;
    /// `first`: the window's first interval.
    #[inline(always)]
    pub(in crate::preint) fn step_midpoint(
        &mut self,
        mid: &mut Mid<V>,
        [accel, gyro]: &Point<V>,
        h: V,
        first: bool,
        p: &Preintegrator,
    ) {
        let k = h;
        let (ba, bg) = (&p.bias_accel, &p.bias_gyro);
        let half = k.splat(0.5);
        let [prev_accel, prev_gyro] = &mid.last;
        let w = [
            (prev_gyro[0] + gyro[0]) * half - k.splat(bg.x),
            (prev_gyro[1] + gyro[1]) * half - k.splat(bg.y),
            (prev_gyro[2] + gyro[2]) * half - k.splat(bg.z),
        ];
        let (exp, jr) = exp_and_right_jacobian(k, &[w[0] * h, w[1] * h, w[2] * h]);
        let bias = [k.splat(ba.x), k.splat(ba.y), k.splat(ba.z)];
        let a0 = [
            prev_accel[0] - bias[0],
            prev_accel[1] - bias[1],
            prev_accel[2] - bias[2],
        ];
        let a1 = [accel[0] - bias[0], accel[1] - bias[1], accel[2] - bias[2]];
        let r0 = self.rotation;
        let r1 = r0.mul_plain(&exp);
        let (d_a, d_g) = (p.noise.accel_density, p.noise.gyro_density);
        let q = [k.like(|i| d_g * d_g / h.lane(i)), k.like(|i| d_a * d_a / h.lane(i))];
        let q0 = if first { q } else { mid.last_var };
        let half_h = half * h;
        let half_h2 = half_h * h;
        let (u0, u1) = (r0.apply(&a0), r1.apply(&a1));
        let acc = [(u0[0] + u1[0]) * half, (u0[1] + u1[1]) * half, (u0[2] + u1[2]) * half];

        // Frame i: W = −[ā]×, G = R_1 J_r, each B_s's v row h K = ¼h² [R_1 â_1]× G.
        let w_m = hat_neg(&acc);
        let g = r1.mul(&jr);
        let quarter_h2 = k.splat(0.25) * h * h;
        let v = [u1[0] * quarter_h2, u1[1] * quarter_h2, u1[2] * quarter_h2];
        let vg = hat_neg(&[-v[0], -v[1], -v[2]]).zero_diagonal_mul(&g);
        let tg = g.scale(-half_h);
        let (va0, va1) = (r0.scale(-half_h), r1.scale(-half_h));
        let b0 = In {
            tg,
            vg,
            va: va0,
            half_h,
        };
        let g_b = In {
            tg: tg.add(&tg),
            vg: vg.add(&vg),
            va: va0.add(&va1),
            half_h,
        };

        // The last point's noise enters now through D = A P + B_0 (`Input::through`), whose
        // accelerometer blocks are −½(h' + h) R_0 and −¼(h' + h)² R_0 (`blocks::add_noise`).
        let pending = mid.pending;
        let w_tg = w_m.zero_diagonal_mul(&pending.tg);
        let p_v = pending.vg.scale(h + pending.half_h);
        let [dt, dv, dp] = [
            pending.tg.add(&b0.tg),
            w_tg.mul_add(h, &pending.vg).add(&b0.vg),
            w_tg.mul_add(half_h2, &p_v).add(&b0.vg.scale(b0.half_h)),
        ];
        let mut cov = propagate(&self.cov, &w_m, h, half_h2);
        let c_v = -(pending.half_h + half_h);
        let c_p = -c_v * c_v;
        let [q_g, q_a] = q0;
        let (st, sv, sp) = (dt.scale(q_g), dv.scale(q_g), dp.scale(q_g));
        cov[0] = cov[0].add(&st.mul_t_symmetric(&dt));
        cov[1] = cov[1].add(&st.mul_t(&dv));
        cov[2] = cov[2].add(&st.mul_t(&dp));
        cov[3] = cov[3].add(&sv.mul_t_symmetric(&dv)).plus_identity(q_a * c_v * c_v);
        cov[4] = cov[4].add(&sv.mul_t(&dp)).plus_identity(q_a * c_v * c_p);
        cov[5] = cov[5].add(&sp.mul_t_symmetric(&dp)).plus_identity(q_a * c_p * c_p);
        if let Some(walk) = &mut self.walk {
            g_b.add_quadratic(&mut cov, walk.var);
            walk.step(&mut cov, &w_m, &g_b, &p.noise);
        }
        self.cov = cov;
        mid.pending = In { va: va1, ..b0 };
        mid.start_cross = if first {
            // `Input::scaled(q_g, q_a).cross()`: the first point's noise enters through B_0 alone.
            let (tg, vg, va) = (b0.tg.scale(q_g), b0.vg.scale(q_g), b0.va.scale(q_a));
            [tg, vg, va, vg.scale(half_h), va.scale(half_h)]
        } else {
            transition(&mid.start_cross, &w_m, h, half_h2)
        };
        self.jac = g_b.added_to(&transition(&self.jac, &w_m, h, half_h2));

        for ((p, v), a) in self.position.iter_mut().zip(self.velocity.iter_mut()).zip(acc) {
            *p = *p + (*v * h + a * half_h2);
            *v = *v + a * h;
        }
        self.rotation = r1;
        self.t = self.t + h;
        if first {
            mid.first_var = q0;
        }
        mid.last = [*accel, *gyro];
        mid.last_var = q;
    }
}
