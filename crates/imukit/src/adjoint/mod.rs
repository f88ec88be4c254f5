//! Differentiable preintegration: batched forward kernels over flat buffers and their analytic
//! reverse sweep (vector–Jacobian product), for `imukit.torch`'s CPU path.
//!
//! A batch holds `windows` windows of `n` intervals each, every buffer row-major and
//! window-major (what a contiguous torch tensor `(B, N, …)` is, read without a copy):
//!
//! | buffer | per interval | meaning |
//! |---|---|---|
//! | `h` | 1 | its step \[s\], ≥ 0 (0: an identity step, how ragged windows are padded) |
//! | `w` | 3 | its rate ω [rad/s], bias-corrected (midpoint: the mean of its two samples) |
//! | `a` | 3 | its specific force [m/s²], bias-corrected (midpoint: at its start) |
//! | `a_end` | 3 | midpoint only: the specific force at its end |
//! | `cov_g`, `cov_a` | 9 | the covariance of its gyro / accelerometer white noise (3×3) |
//!
//! or, instead of `cov_g`, `cov_a`, one pair per window `[σ_g², σ_a²]` of variance densities
//! ([`Noise::Densities`], the common case, with no per-sample buffers): each sample's covariance
//! is then `σ²/h I`, `h` the step it owns (docs/conventions.md, row 11): its interval's, or for
//! midpoint a window's first sample (whose own interval is an identity step, `h = 0`) the next
//! interval's; a sample that owns no step (masked) has no noise.
//!
//! The interval step is `step.rs` (Forster et al. 2017; the midpoint scheme of
//! `preint/midpoint.rs`, with its shared-sample noise correlation), deltas, covariance and bias
//! Jacobian in both schemes. The common case — lie_euler, noise as densities, the final record's
//! covariance without the bias Jacobian — runs `euler.rs` instead: the same numbers (to rounding)
//! with the covariance's rotation error in the window's start frame, where the step is five 3×3
//! products instead of two structured 9×9 passes.
//! [`forward`] writes one record per interval (`per_step`) or per window:
//! `[ΔR (9, row-major), Δv (3), Δp (3), P (81, if cov), J (54, if jac)]`. [`backward`] takes the
//! cotangents of those records and writes per interval `[h̄, w̄ (3), ā (3), ā_end (3, midpoint),
//! Σ̄_g (9), Σ̄_a (9, if per-sample noise)]` or, with densities, `[…, σ̄²_g, σ̄²_a]`, the interval's
//! share of its window's density cotangents (their sum over the window is the cotangent): it re-runs each window forward, keeping of
//! the state before every interval what the reverse step reads (a tape, one window at a time per
//! thread: O(n) memory per thread, none between the passes), then sweeps back. Windows run in parallel (rayon); each window's arithmetic is independent of
//! the thread count.

mod euler;
mod so3;
mod step;
#[cfg(test)]
mod tests;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use step::{Before, Interval, Linear, Mat6, Mat9, Mat96, State};

/// A batch of windows (module docs).
#[derive(Debug, Clone, Copy)]
pub struct Windows<'a> {
    /// Intervals per window.
    pub n: usize,
    /// Steps `(windows, n)`.
    pub h: &'a [f64],
    /// Rates `(windows, n, 3)`.
    pub w: &'a [f64],
    /// Specific forces `(windows, n, 3)`.
    pub a: &'a [f64],
    /// Midpoint: specific forces at the intervals' ends `(windows, n, 3)`.
    pub a_end: Option<&'a [f64]>,
    /// The white noise, if any.
    pub noise: Option<Noise<'a>>,
}

/// Where each sample's white-noise covariance comes from (module docs).
#[derive(Debug, Clone, Copy)]
pub enum Noise<'a> {
    /// Gyro and accelerometer covariances `(windows, n, 3, 3)` each, per sample.
    Samples(&'a [f64], &'a [f64]),
    /// Variance densities `[σ_g², σ_a²]` `(windows, 2)`, per window.
    Densities(&'a [f64]),
}

/// What [`forward`] returns and [`backward`] differentiates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outputs {
    /// One record per interval, else one per window.
    pub per_step: bool,
    /// The 9×9 covariance (needs `Windows::cov`).
    pub covariance: bool,
    /// The 9×6 bias Jacobian.
    pub jacobian: bool,
}

impl Outputs {
    /// Numbers per output record.
    pub fn width(&self) -> usize {
        15 + if self.covariance { 81 } else { 0 } + if self.jacobian { 54 } else { 0 }
    }

    fn records(&self, n: usize) -> usize {
        if self.per_step {
            n
        } else {
            1
        }
    }

    fn linear(&self, noise: Option<Noise<'_>>) -> Linear {
        Linear {
            cov: self.covariance,
            jac: self.jacobian,
            symmetric: matches!(noise, Some(Noise::Densities(_))),
        }
    }
}

impl Windows<'_> {
    /// Numbers per record of [`backward`]'s input cotangents.
    pub fn grad_width(&self) -> usize {
        let noise = match self.noise {
            None => 0,
            Some(Noise::Samples(..)) => 18,
            Some(Noise::Densities(_)) => 2,
        };
        7 + if self.a_end.is_some() { 3 } else { 0 } + noise
    }

    /// The number of windows, after checking every buffer's length and every value.
    fn check(&self, out: &Outputs) -> Result<usize> {
        if self.n == 0 {
            return Err(Error::Parameter {
                name: "n",
                expected: "at least one interval per window",
                got: "0".into(),
            });
        }
        if out.covariance && self.noise.is_none() {
            return Err(Error::Parameter {
                name: "covariance",
                expected: "noise covariances",
                got: "none".into(),
            });
        }
        let windows = self.h.len() / self.n;
        // (name, buffer, numbers per row, rows per window)
        let n = self.n;
        let mut buffers = vec![("dt", self.h, 1, n), ("gyro", self.w, 3, n), ("accel", self.a, 3, n)];
        if let Some(a) = self.a_end {
            buffers.push(("accel", a, 3, n));
        }
        match self.noise {
            Some(Noise::Samples(g, a)) => buffers.extend([("gyro_cov", g, 9, n), ("accel_cov", a, 9, n)]),
            Some(Noise::Densities(q)) => buffers.push(("noise", q, 2, 1)),
            None => {}
        }
        for (name, x, width, rows) in buffers {
            if x.len() != windows * rows * width {
                return Err(Error::RowLength {
                    len: x.len(),
                    row: width,
                }
                .in_argument(name));
            }
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(Error::NonFinite { index: i / width }.in_argument(name));
            }
        }
        if let Some(i) = self.h.iter().position(|&h| h < 0.0) {
            return Err(Error::Parameter {
                name: "dt",
                expected: "steps ≥ 0",
                got: format!("{} at {i}", self.h[i]),
            });
        }
        Ok(windows)
    }

    /// The densities when `euler.rs` runs this call: lie_euler, noise as densities, the
    /// covariance of the final record without the bias Jacobian (`imukit.torch`'s common case).
    fn euler_densities(&self, out: &Outputs) -> Option<&[f64]> {
        match self.noise {
            Some(Noise::Densities(q)) if self.a_end.is_none() && out.covariance && !out.jacobian && !out.per_step => {
                Some(q)
            }
            _ => None,
        }
    }

    /// The interval whose step sample `k`'s density is discretised over, and that step (module
    /// docs): a midpoint window's first sample owns the next interval's.
    fn own_step(&self, k: usize) -> (usize, f64) {
        if self.h[k] == 0.0 && self.a_end.is_some() && k + 1 < self.n {
            (k + 1, self.h[k + 1])
        } else {
            (k, self.h[k])
        }
    }

    fn interval(&self, k: usize) -> Interval {
        let v = |x: &[f64]| Vector3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
        let m = |x: &[f64]| Matrix3::from_row_slice(&x[9 * k..9 * k + 9]);
        let (cov_g, cov_a) = match self.noise {
            None => (Matrix3::zeros(), Matrix3::zeros()),
            Some(Noise::Samples(g, a)) => (m(g), m(a)),
            Some(Noise::Densities(q)) => match self.own_step(k).1 {
                h if h > 0.0 => (
                    Matrix3::from_diagonal_element(q[0] / h),
                    Matrix3::from_diagonal_element(q[1] / h),
                ),
                _ => (Matrix3::zeros(), Matrix3::zeros()),
            },
        };
        Interval {
            h: self.h[k],
            w: v(self.w),
            a: v(self.a),
            a_end: self.a_end.map(v),
            cov_g,
            cov_a,
        }
    }
}

fn write(s: &State, out: &Outputs, record: &mut [f64]) {
    record[..9].copy_from_slice(s.r.transpose().as_slice());
    record[9..12].copy_from_slice(s.v.as_slice());
    record[12..15].copy_from_slice(s.p.as_slice());
    let mut at = 15;
    if out.covariance {
        record[at..at + 81].copy_from_slice(s.cov.transpose().as_slice());
        at += 81;
    }
    if out.jacobian {
        record[at..at + 54].copy_from_slice(s.jac.transpose().as_slice());
    }
}

fn read(record: &[f64], out: &Outputs) -> State {
    let mut s = State::zero();
    s.r = Matrix3::from_row_slice(&record[..9]);
    s.v = Vector3::from_column_slice(&record[9..12]);
    s.p = Vector3::from_column_slice(&record[12..15]);
    let mut at = 15;
    if out.covariance {
        s.cov = Mat9::from_row_slice(&record[at..at + 81]);
        at += 81;
    }
    if out.jacobian {
        s.jac = Mat96::from_row_slice(&record[at..at + 54]);
    }
    s
}

fn add(a: &State, b: &State) -> State {
    State {
        r: a.r + b.r,
        v: a.v + b.v,
        p: a.p + b.p,
        cov: a.cov + b.cov,
        jac: a.jac + b.jac,
        cross: a.cross + b.cross,
        last: a.last + b.last,
    }
}

/// The states before each interval of one window, of each only what [`step::reverse`] reads
/// ([`Before`]), flat: `ΔR`, `Δv` (12 numbers); with the covariance `P`'s first six columns (54),
/// its first six rows (54, non-symmetric noise only), midpoint's `X` and `S` (90); with the bias
/// Jacobian `J`'s first six rows (36). Lie_euler with densities keeps 66 numbers per interval, not
/// a whole [`State`] (255): the tape of a 1,000-interval window stays in a core's cache.
struct Tape {
    linear: Linear,
    midpoint: bool,
    width: usize,
    data: Vec<f64>,
}

impl Tape {
    fn new(linear: Linear, midpoint: bool, n: usize) -> Tape {
        let cov = 54 + if linear.symmetric { 0 } else { 54 } + if midpoint { 90 } else { 0 };
        let width = 12 + if linear.cov { cov } else { 0 } + if linear.jac { 36 } else { 0 };
        Tape {
            linear,
            midpoint,
            width,
            data: Vec::with_capacity(n * width),
        }
    }

    fn push(&mut self, s: &State) {
        let d = &mut self.data;
        d.extend_from_slice(s.r.as_slice());
        d.extend_from_slice(s.v.as_slice());
        if self.linear.cov {
            // Column-major: the first six columns are the first 54 numbers.
            d.extend_from_slice(&s.cov.as_slice()[..54]);
            if !self.linear.symmetric {
                d.extend(s.cov.fixed_rows::<6>(0).transpose().iter());
            }
            if self.midpoint {
                d.extend_from_slice(s.cross.as_slice());
                d.extend_from_slice(s.last.as_slice());
            }
        }
        if self.linear.jac {
            d.extend(s.jac.fixed_rows::<6>(0).iter());
        }
    }

    fn get(&self, k: usize) -> Before {
        let mut at = k * self.width;
        let mut take = |len: usize| {
            let x = &self.data[at..at + len];
            at += len;
            x
        };
        let mut b = Before {
            r: Matrix3::from_column_slice(take(9)),
            v: Vector3::from_column_slice(take(3)),
            cov_cols: Mat96::zeros(),
            cov_rows: Mat96::zeros(),
            jac: Mat6::zeros(),
            cross: Mat96::zeros(),
            last: Mat6::zeros(),
        };
        if self.linear.cov {
            b.cov_cols = Mat96::from_column_slice(take(54));
            if !self.linear.symmetric {
                b.cov_rows = Mat96::from_column_slice(take(54));
            }
            if self.midpoint {
                b.cross = Mat96::from_column_slice(take(54));
                b.last = Mat6::from_column_slice(take(36));
            }
        }
        if self.linear.jac {
            b.jac = Mat6::from_column_slice(take(36));
        }
        b
    }
}

/// The window `b` of `x`.
fn window<'a>(x: &Windows<'a>, b: usize) -> Windows<'a> {
    let n = x.n;
    let part = |s: &'a [f64], width: usize| &s[b * n * width..(b + 1) * n * width];
    Windows {
        n,
        h: part(x.h, 1),
        w: part(x.w, 3),
        a: part(x.a, 3),
        a_end: x.a_end.map(|a| part(a, 3)),
        noise: x.noise.map(|noise| match noise {
            Noise::Samples(g, a) => Noise::Samples(part(g, 9), part(a, 9)),
            Noise::Densities(q) => Noise::Densities(&q[2 * b..2 * b + 2]),
        }),
    }
}

/// Preintegrates every window of `x` into `out` (`windows × records × width` numbers, module
/// docs). Errors: a buffer of the wrong length, a non-finite input, a negative step, a result
/// that overflows (the window's index).
pub fn forward(x: &Windows<'_>, outputs: &Outputs, out: &mut [f64]) -> Result<()> {
    let windows = x.check(outputs)?;
    let chunk = outputs.records(x.n) * outputs.width();
    if out.len() != windows * chunk {
        return Err(Error::RowCount {
            input: windows * chunk,
            output: out.len(),
        });
    }
    let linear = outputs.linear(x.noise);
    out.par_chunks_mut(chunk).enumerate().try_for_each(|(b, o)| {
        let x = window(x, b);
        if let Some(q) = x.euler_densities(outputs) {
            euler::forward(&x, q, outputs, o);
            return finite(o, b);
        }
        let mut s = State::start();
        for k in 0..x.n {
            s = step::forward(&s, &x.interval(k), linear);
            if outputs.per_step {
                write(&s, outputs, &mut o[k * outputs.width()..(k + 1) * outputs.width()]);
            }
        }
        if !outputs.per_step {
            write(&s, outputs, o);
        }
        finite(o, b)
    })
}

/// The cotangents of every interval's inputs (`windows × n × grad_width`, module docs) given
/// `bar`, those of [`forward`]'s output for the same `x` and `outputs`.
pub fn backward(x: &Windows<'_>, outputs: &Outputs, bar: &[f64], grad: &mut [f64]) -> Result<()> {
    let windows = x.check(outputs)?;
    let (width, records, gw) = (outputs.width(), outputs.records(x.n), x.grad_width());
    if bar.len() != windows * records * width || grad.len() != windows * x.n * gw {
        return Err(Error::RowCount {
            input: windows * records * width,
            output: bar.len(),
        });
    }
    let linear = outputs.linear(x.noise);
    grad.par_chunks_mut(x.n * gw).enumerate().try_for_each(|(b, g)| {
        let x = window(x, b);
        let bar = &bar[b * records * width..(b + 1) * records * width];
        if let Some(q) = x.euler_densities(outputs) {
            euler::backward(&x, q, outputs, bar, g);
            return finite(g, b);
        }
        let mut tape = Tape::new(linear, x.a_end.is_some(), x.n);
        let mut s = State::start();
        for k in 0..x.n {
            tape.push(&s);
            s = step::forward(&s, &x.interval(k), linear);
        }
        let mut cot = read(&bar[(records - 1) * width..], outputs);
        for k in (0..x.n).rev() {
            let (prev, ib) = step::reverse(&tape.get(k), &x.interval(k), &cot, linear);
            let row = &mut g[k * gw..(k + 1) * gw];
            row[0] = ib.h;
            row[1..4].copy_from_slice(ib.w.as_slice());
            row[4..7].copy_from_slice(ib.a.as_slice());
            let mut at = 7;
            if x.a_end.is_some() {
                row[7..10].copy_from_slice(ib.a_end.as_slice());
                at = 10;
            }
            match x.noise {
                Some(Noise::Samples(..)) => {
                    row[at..at + 9].copy_from_slice(ib.cov_g.transpose().as_slice());
                    row[at + 9..at + 18].copy_from_slice(ib.cov_a.transpose().as_slice());
                }
                Some(Noise::Densities(q)) => {
                    // Σ = σ²/h I: σ̄² = tr(Σ̄)/h, h̄ −= σ² tr(Σ̄)/h² on the step the sample owns.
                    let (j, own) = x.own_step(k);
                    if own > 0.0 {
                        let (tg, ta) = (ib.cov_g.trace() / own, ib.cov_a.trace() / own);
                        row[at] = tg;
                        row[at + 1] = ta;
                        g[j * gw] -= (q[0] * tg + q[1] * ta) / own;
                    }
                }
                None => {}
            }
            cot = match outputs.per_step && k > 0 {
                true => add(&prev, &read(&bar[(k - 1) * width..k * width], outputs)),
                false => prev,
            };
        }
        finite(g, b)
    })
}

/// Window `b`'s output is finite: finite input so large that it overflowed is an error.
fn finite(x: &[f64], b: usize) -> Result<()> {
    match x.iter().all(|v| v.is_finite()) {
        true => Ok(()),
        false => Err(Error::Overflow { index: b }),
    }
}
