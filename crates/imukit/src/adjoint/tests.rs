//! The reverse sweep against central differences of the forward kernel, and the forward kernel
//! against the streaming [`Preintegrator`].

use nalgebra::Vector3;

use super::*;
use crate::imu;
use crate::preint::Preintegrator;

/// A reproducible stream in [-1, 1).
fn numbers(count: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..count)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

struct Data {
    h: Vec<f64>,
    w: Vec<f64>,
    a: Vec<f64>,
    a_end: Vec<f64>,
    g: Vec<f64>,
    c: Vec<f64>,
    /// Variance densities `[σ_g², σ_a²]` per window.
    q: Vec<f64>,
}

fn data(windows: usize, n: usize) -> Data {
    let m = windows * n;
    Data {
        h: numbers(m, 1).iter().map(|x| 0.05 + 0.02 * x).collect(),
        w: numbers(3 * m, 2).iter().map(|x| 2.0 * x).collect(),
        a: numbers(3 * m, 3).iter().map(|x| 5.0 * x).collect(),
        a_end: numbers(3 * m, 4).iter().map(|x| 5.0 * x).collect(),
        g: numbers(9 * m, 5),
        c: numbers(9 * m, 6),
        q: numbers(2 * windows, 8).iter().map(|x| 1e-3 * (1.5 + x)).collect(),
    }
}

fn windows<'a>(d: &'a Data, n: usize, midpoint: bool, densities: bool) -> Windows<'a> {
    Windows {
        n,
        h: &d.h,
        w: &d.w,
        a: &d.a,
        a_end: midpoint.then_some(&d.a_end[..]),
        noise: Some(match densities {
            true => Noise::Densities(&d.q),
            false => Noise::Samples(&d.g, &d.c),
        }),
    }
}

/// `⟨bar, forward(x)⟩`.
fn loss(x: &Windows<'_>, outputs: &Outputs, bar: &[f64]) -> Result<f64> {
    let mut out = vec![0.0; bar.len()];
    forward(x, outputs, &mut out)?;
    Ok(out.iter().zip(bar).map(|(o, b)| o * b).sum())
}

/// `data` with a window's first interval an identity step (a padded midpoint window: its first
/// sample owns the next interval's step).
fn padded(count: usize, n: usize) -> Data {
    let mut d = data(count, n);
    d.h[n] = 0.0;
    d
}

fn check(midpoint: bool, per_step: bool, densities: bool) -> Result<()> {
    check_outputs(
        midpoint,
        densities,
        Outputs {
            per_step,
            covariance: true,
            jacobian: true,
        },
    )
}

fn check_outputs(midpoint: bool, densities: bool, outputs: Outputs) -> Result<()> {
    let (count, n) = (2, 4);
    let d = padded(count, n);
    let x = windows(&d, n, midpoint, densities);
    let bar = numbers(count * outputs.records(n) * outputs.width(), 7);
    let mut grad = vec![0.0; count * n * x.grad_width()];
    backward(&x, &outputs, &bar, &mut grad)?;
    let gw = x.grad_width();
    // Each buffer, its width, and where its cotangent sits in a grad row.
    let mut fields: Vec<(&str, usize, usize)> = vec![("h", 1, 0), ("w", 3, 1), ("a", 3, 4)];
    let at = if midpoint {
        fields.push(("a_end", 3, 7));
        10
    } else {
        7
    };
    if densities {
        fields.push(("q", 2, at));
    } else {
        fields.extend([("g", 9, at), ("c", 9, at + 9)]);
    }
    for (name, width, offset) in fields {
        // A window's density cotangent is the sum of its intervals' shares.
        let rows = if name == "q" { 1 } else { n };
        for i in 0..count * rows * width {
            if name == "h" && i == n {
                continue; // the identity step: steps are ≥ 0 (and σ²/h has a kink at 0)
            }
            let eps = 1e-6;
            let at = |delta: f64| {
                let mut e = padded(count, n);
                let buffer = match name {
                    "h" => &mut e.h,
                    "w" => &mut e.w,
                    "a" => &mut e.a,
                    "a_end" => &mut e.a_end,
                    "g" => &mut e.g,
                    "q" => &mut e.q,
                    _ => &mut e.c,
                };
                buffer[i] += delta;
                loss(&windows(&e, n, midpoint, densities), &outputs, &bar)
            };
            let numeric = (at(eps)? - at(-eps)?) / (2.0 * eps);
            let got = match rows {
                1 => (0..n)
                    .map(|k| grad[((i / width) * n + k) * gw + offset + i % width])
                    .sum(),
                _ => grad[(i / width) * gw + offset + i % width],
            };
            let tol = 1e-6 * (1.0 + numeric.abs());
            assert!(
                (numeric - got).abs() < tol,
                "{name}[{i}]: numeric {numeric}, reverse {got}"
            );
        }
    }
    Ok(())
}

#[test]
fn reverse_matches_central_differences_euler_with_covariance() -> Result<()> {
    check(false, false, false)?;
    check(false, true, false)
}

#[test]
fn reverse_matches_central_differences_with_noise_densities() -> Result<()> {
    for (midpoint, per_step) in [(false, false), (false, true), (true, false), (true, true)] {
        check(midpoint, per_step, true)?;
    }
    Ok(())
}

/// `euler.rs`'s path (lie_euler, densities, final covariance without the Jacobian).
#[test]
fn reverse_matches_central_differences_euler_densities_final() -> Result<()> {
    let outputs = Outputs {
        per_step: false,
        covariance: true,
        jacobian: false,
    };
    check_outputs(false, true, outputs)
}

/// `euler.rs` (covariance in the start frame) equals `step.rs` (body frame, the path taken with
/// the bias Jacobian): records and input cotangents, over 200 intervals with a padded start.
#[test]
fn euler_densities_path_equals_the_general_step() -> Result<()> {
    let (count, n) = (3, 200);
    let d = padded(count, n);
    let x = windows(&d, n, false, true);
    let fast = Outputs {
        per_step: false,
        covariance: true,
        jacobian: false,
    };
    let general = Outputs { jacobian: true, ..fast };
    let (wf, wg) = (fast.width(), general.width());
    let mut rf = vec![0.0; count * wf];
    let mut rg = vec![0.0; count * wg];
    forward(&x, &fast, &mut rf)?;
    forward(&x, &general, &mut rg)?;
    // The general record with the Jacobian's 54 numbers dropped.
    let rg_cut: Vec<f64> = rg.chunks(wg).flat_map(|r| r[..wf].to_vec()).collect();
    let close = |a: &[f64], b: &[f64], what: &str| {
        let scale = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let worst = a.iter().zip(b).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(worst <= 1e-13 * scale, "{what}: {worst} of {scale}");
    };
    for w in 0..count {
        let (a, b) = (&rf[w * wf..(w + 1) * wf], &rg_cut[w * wf..(w + 1) * wf]);
        close(&a[..15], &b[..15], "deltas");
        close(&a[15..], &b[15..], "covariance");
    }
    // Cotangents: the same numbers on the shared fields, zero on the Jacobian.
    let bar = numbers(count * wf, 7);
    let bar_g: Vec<f64> = bar
        .chunks(wf)
        .flat_map(|r| r.iter().copied().chain([0.0; 54]))
        .collect();
    let gw = x.grad_width();
    let (mut gf, mut gg) = (vec![0.0; count * n * gw], vec![0.0; count * n * gw]);
    backward(&x, &fast, &bar, &mut gf)?;
    backward(&x, &general, &bar_g, &mut gg)?;
    for (field, range) in [("h", 0..1), ("w", 1..4), ("a", 4..7), ("q", 7..9)] {
        let pick = |g: &[f64]| -> Vec<f64> { g.chunks(gw).flat_map(|r| r[range.clone()].to_vec()).collect() };
        close(&pick(&gf), &pick(&gg), field);
    }
    Ok(())
}

#[test]
fn reverse_matches_central_differences_midpoint_with_covariance() -> Result<()> {
    check(true, false, false)?;
    check(true, true, false)
}

/// Euler deltas, covariance and bias Jacobian equal the streaming preintegrator's (isotropic
/// white noise `σ²/h`, given per sample or as densities), per step.
#[test]
fn forward_equals_preintegrator() -> Result<()> {
    let n = 50;
    let d = data(1, n);
    let (sg, sa) = (0.01, 0.2);
    let iso = |s: f64| -> Vec<f64> {
        d.h.iter()
            .flat_map(|h| {
                let v = s * s / h;
                [v, 0.0, 0.0, 0.0, v, 0.0, 0.0, 0.0, v]
            })
            .collect()
    };
    let (g, c, q) = (iso(sg), iso(sa), [sg * sg, sa * sa]);
    for noise in [Noise::Samples(&g, &c), Noise::Densities(&q)] {
        let x = Windows {
            noise: Some(noise),
            ..windows(&d, n, false, false)
        };
        let outputs = Outputs {
            per_step: true,
            covariance: true,
            jacobian: true,
        };
        let mut out = vec![0.0; n * outputs.width()];
        forward(&x, &outputs, &mut out)?;
        let densities = imu::Noise {
            gyro_density: sg,
            accel_density: sa,
            gyro_random_walk: 0.0,
            accel_random_walk: 0.0,
        };
        let mut p = Preintegrator::new(Vector3::zeros(), Vector3::zeros(), densities);
        for k in 0..n {
            let v = |s: &[f64]| Vector3::new(s[3 * k], s[3 * k + 1], s[3 * k + 2]);
            p.integrate_measurement(&v(&d.a), &v(&d.w), d.h[k]);
            let s = read(&out[k * outputs.width()..(k + 1) * outputs.width()], &outputs);
            let close = |a: &[f64], b: &[f64], what: &str| {
                let scale = b.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
                let worst = a.iter().zip(b).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(worst < 1e-12 * scale, "{what} at {k}: {worst}");
            };
            close(s.r.as_slice(), p.delta_rotation.as_slice(), "ΔR");
            close(s.v.as_slice(), p.delta_velocity.as_slice(), "Δv");
            close(s.p.as_slice(), p.delta_position.as_slice(), "Δp");
            close(s.cov.as_slice(), p.covariance().as_slice(), "covariance");
            close(s.jac.as_slice(), p.bias_jacobian().as_slice(), "bias Jacobian");
        }
    }
    Ok(())
}

#[test]
fn refuses_bad_input() {
    let d = data(1, 3);
    let mut h = d.h.clone();
    h[1] = -0.1;
    let x = Windows {
        h: &h,
        ..windows(&d, 3, false, false)
    };
    let outputs = Outputs {
        per_step: false,
        covariance: true,
        jacobian: false,
    };
    let mut out = vec![0.0; outputs.width()];
    assert_eq!(
        forward(&x, &outputs, &mut out).map_err(|e| e.argument()),
        Err(Some("dt"))
    );
    let mut w = d.w.clone();
    w[4] = f64::NAN;
    let x = Windows {
        w: &w,
        ..windows(&d, 3, false, false)
    };
    let err = forward(&x, &outputs, &mut out).err();
    assert_eq!(err.map(|e| (e.argument(), e.index())), Some((Some("gyro"), Some(1))));
}
