//! The sensor error model of the simulator, one triad (gyro or accelerometer) at a time:
//!
//! ```text
//! m_k = Q( S( T u_k + b_k + n_k ) )
//! b_k = b_const + b_on + w_k + g_k
//! ```
//!
//! | term | model | per step of Δt_k = t_{k+1} − t_k |
//! |---|---|---|
//! | `u_k` | the ideal reading (body rate or specific force) | |
//! | `T` | scale factor and misalignment, 3×3 (`I` = none) | |
//! | `b_const` | constant bias | |
//! | `b_on` | turn-on bias, drawn once per run: `N(0, σ_on² I)` | |
//! | `n_k` | white noise of density σ (units/√Hz) | `N(0, σ²/Δt_k I)` |
//! | `w_k` | bias random walk of density σ_w, `w_0 = 0` | `w_{k+1} = w_k + σ_w √Δt_k ε` |
//! | `g_k` | first-order Gauss–Markov bias, std σ_gm, correlation time τ, stationary from k = 0 | `g_{k+1} = e^{−Δt/τ} g_k + σ_gm √(1 − e^{−2Δt/τ}) ε` |
//! | `S` | saturation: clamp each axis to `±range` (∞ = none) | |
//! | `Q` | quantisation: round to a multiple of `resolution` (0 = none) | |
//!
//! The last sample's Δt is the one before it. The reported true bias is `b_k`.
//!
//! Random numbers: xoshiro256++ (Blackman & Vigna 2021; `rand`'s portable implementation, 64-bit
//! outputs on every platform), one generator per (seed, triad, process, chunk of [`CHUNK`]
//! samples), its 256-bit state four SplitMix64 outputs of the seed and of the stream's number (so
//! distinct streams of a seed start from distinct states); normals by the ziggurat of `rand_distr`.
//! The chunks are fixed by N, so the output does not depend on the thread count, and the same seed
//! gives the same output across runs; the walk and Gauss–Markov recursions are joined across chunks
//! by a prefix pass. (ChaCha8 until issue 20: its 8 bytes per normal cost more than the ziggurat.)

use nalgebra::{Matrix3, Vector3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use crate::error::{Cancel, Error, Result};

/// Samples per random stream and per parallel task.
pub const CHUNK: usize = 1 << 16;

/// Error model of one sensor triad (module docs). `Default` is a perfect sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorModel {
    /// `T`: scale factor and misalignment.
    pub matrix: Matrix3<f64>,
    /// `b_const`.
    pub bias: Vector3<f64>,
    /// σ_on of the turn-on bias.
    pub turn_on_sigma: f64,
    /// σ: white-noise density.
    pub density: f64,
    /// σ_w: bias random-walk density.
    pub random_walk: f64,
    /// σ_gm: stationary std of the Gauss–Markov bias.
    pub gauss_markov_sigma: f64,
    /// τ \[s\]: its correlation time (∞ or 0 with σ_gm = 0: none).
    pub gauss_markov_tau: f64,
    /// Saturation range (∞: none).
    pub range: f64,
    /// Quantisation step (0: none).
    pub resolution: f64,
}

impl Default for SensorModel {
    fn default() -> Self {
        Self {
            matrix: Matrix3::identity(),
            bias: Vector3::zeros(),
            turn_on_sigma: 0.0,
            density: 0.0,
            random_walk: 0.0,
            gauss_markov_sigma: 0.0,
            gauss_markov_tau: f64::INFINITY,
            range: f64::INFINITY,
            resolution: 0.0,
        }
    }
}

impl SensorModel {
    fn check(&self) -> Result<()> {
        let bad = |name: &'static str, expected: &'static str, got: f64| {
            Err(Error::Parameter {
                name,
                expected,
                got: format!("{got}"),
            })
        };
        if !self.matrix.iter().chain(self.bias.iter()).all(|v| v.is_finite()) {
            return bad("matrix", "finite scale/misalignment and bias values", f64::NAN);
        }
        for (name, v) in [
            ("turn_on_sigma", self.turn_on_sigma),
            ("density", self.density),
            ("random_walk", self.random_walk),
            ("gauss_markov_sigma", self.gauss_markov_sigma),
            ("resolution", self.resolution),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, "finite and ≥ 0", v);
            }
        }
        if self.gauss_markov_tau.is_nan() || self.gauss_markov_tau <= 0.0 {
            return bad("gauss_markov_tau", "> 0 (∞ for none)", self.gauss_markov_tau);
        }
        if self.range.is_nan() || self.range <= 0.0 {
            return bad("range", "> 0 (∞ for none)", self.range);
        }
        Ok(())
    }
}

/// Which random process a stream feeds.
#[derive(Clone, Copy)]
enum Process {
    White = 0,
    Walk = 1,
    GaussMarkov = 2,
    TurnOn = 3,
}

/// SplitMix64's output function (Steele, Lea & Flood 2014): a bijection of `u64` that mixes every
/// input bit into every output bit.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator of (triad, process, chunk) for `seed`: two state words from the seed, two from
/// the stream's number, each a bijection of its input, so no two streams of a seed share a state.
fn stream(seed: u64, triad: u64, process: Process, chunk: usize) -> Xoshiro256PlusPlus {
    let id = (triad << 34) | ((process as u64) << 32) | chunk as u64;
    let words = [
        splitmix64(seed),
        splitmix64(seed ^ 0x5851_F42D_4C95_7F2D),
        splitmix64(id),
        splitmix64(id ^ 0x1405_7B7E_F767_814F),
    ];
    let mut bytes = [0u8; 32];
    for (chunk, word) in bytes.chunks_exact_mut(8).zip(words) {
        chunk.copy_from_slice(&word.to_le_bytes());
    }
    Xoshiro256PlusPlus::from_seed(bytes)
}

#[inline(always)]
fn normal3(rng: &mut Xoshiro256PlusPlus) -> Vector3<f64> {
    let mut draw = || -> f64 { StandardNormal.sample(rng) };
    Vector3::new(draw(), draw(), draw())
}

/// `Δt_k` with the last sample's taken from the step before it.
fn step(t: &[f64], k: usize) -> f64 {
    if k + 1 < t.len() {
        t[k + 1] - t[k]
    } else {
        t[k] - t[k - 1]
    }
}

/// One chunk's recursion `x_{k+1} = a_k x_k + e_k` from `x = 0`: the local values, the end state and
/// the product of the `a_k` (to join chunks: `x_k = local_k + (Π a) x_start`).
struct Local {
    end: Vector3<f64>,
    decay: f64,
}

/// Measures `ideal` (flat `3N`, rows `u_k`) at times `t` (strictly increasing, N ≥ 2) with
/// `model`, writing the readings to `out` and the true bias `b_k` to `bias_out` (both flat `3N`).
/// `triad` (0 gyro, 1 accelerometer) selects independent random streams for the same seed.
pub fn measure(
    t: &[f64],
    ideal: &[f64],
    model: &SensorModel,
    seed: u64,
    triad: u64,
    out: &mut [f64],
    bias_out: &mut [f64],
) -> Result<()> {
    if out.len() != ideal.len() {
        let (input, output) = (ideal.len() / 3, out.len() / 3);
        return Err(Error::RowCount { input, output }.in_argument("out"));
    }
    out.copy_from_slice(ideal);
    measure_in_place(t, out, model, seed, triad, bias_out)
}

/// [`measure`] with the ideal readings in `values`, replaced by the measured ones.
pub fn measure_in_place(
    t: &[f64],
    values: &mut [f64],
    model: &SensorModel,
    seed: u64,
    triad: u64,
    bias_out: &mut [f64],
) -> Result<()> {
    measure_in_place_cancellable(t, values, model, (seed, triad), bias_out, &Cancel::new())
}

/// [`measure_in_place`] of the stream `(seed, triad)`, stopping with [`Error::Interrupted`] when
/// `cancel` is set (polled per chunk of [`CHUNK`] samples).
pub fn measure_in_place_cancellable(
    t: &[f64],
    values: &mut [f64],
    model: &SensorModel,
    (seed, triad): (u64, u64),
    bias_out: &mut [f64],
    cancel: &Cancel,
) -> Result<()> {
    model.check()?;
    let n = t.len();
    if n < 2 {
        return Err(Error::Parameter {
            name: "t",
            expected: "at least two samples",
            got: format!("{n}"),
        });
    }
    for (name, len) in [("ideal", values.len()), ("bias_out", bias_out.len())] {
        if len != 3 * n {
            return Err(Error::RowCount {
                input: n,
                output: len / 3,
            }
            .in_argument(name));
        }
    }
    check_increasing(t).map_err(|e| e.in_argument("t"))?;
    if let Some(i) = first_non_finite(values) {
        return Err(Error::NonFinite { index: i / 3 }.in_argument("ideal"));
    }
    let turn_on = normal3(&mut stream(seed, triad, Process::TurnOn, 0)) * model.turn_on_sigma;
    let fixed = model.bias + turn_on;
    let walk_on = model.random_walk > 0.0;
    let gm_on = model.gauss_markov_sigma > 0.0 && model.gauss_markov_tau.is_finite();
    // The once-per-run draws share the turn-on stream: the turn-on bias, then g_0 (stationary).
    let gm_start = normal3(&mut stream(seed, triad, Process::TurnOn, 1)) * model.gauss_markov_sigma;

    // Pass 1 (parallel): the walk and Gauss–Markov recursions of each chunk from zero, into
    // `bias_out`, with each chunk's end state and decay.
    let chunks: Vec<(Local, Local)> = bias_out
        .par_chunks_mut(3 * CHUNK)
        .enumerate()
        .map(|(c, bias)| {
            cancel.check(0)?;
            Ok(bias_chunk(t, model, (seed, triad), c, bias, (walk_on, gm_on)))
        })
        .collect::<Result<_>>()?;

    // Pass 2 (sequential over chunks): the walk and Gauss–Markov states at each chunk's start.
    let mut starts = Vec::with_capacity(chunks.len());
    let (mut w0, mut g0) = (Vector3::zeros(), if gm_on { gm_start } else { Vector3::zeros() });
    for (walk, gm) in &chunks {
        starts.push((w0, g0));
        w0 += walk.end;
        g0 = g0 * gm.decay + gm.end;
    }

    // Pass 3 (parallel): join the chunks, add the fixed bias and the white noise, form the readings.
    bias_out
        .par_chunks_mut(3 * CHUNK)
        .zip(values.par_chunks_mut(3 * CHUNK))
        .enumerate()
        .try_for_each(|(c, (bias, readings))| {
            cancel.check(0)?;
            readings_chunk(t, model, (seed, triad, c), (starts[c], fixed, gm_on), bias, readings);
            Ok(())
        })?;
    match first_non_finite(values) {
        Some(i) => Err(Error::Overflow { index: i / 3 }.in_argument(overflow_culprit(t, model))),
        None => Ok(()),
    }
}

crate::simd_dispatch! {
    /// Pass 1 of [`measure_in_place_cancellable`] on chunk `c` of the stream `(seed, triad)`: the
    /// walk and Gauss–Markov recursions from zero (each where `on` says), into `bias`; the chunk's
    /// end states and the Gauss–Markov decay over it. Per instruction-set path (the same
    /// operations on each: equal bit for bit).
    fn bias_chunk(
        t: &[f64],
        model: &SensorModel,
        stream_of: (u64, u64),
        c: usize,
        bias: &mut [f64],
        on: (bool, bool),
    ) -> (Local, Local) {
        let ((seed, triad), (walk_on, gm_on)) = (stream_of, on);
        let (mut walk_rng, mut gm_rng) = (
            stream(seed, triad, Process::Walk, c),
            stream(seed, triad, Process::GaussMarkov, c),
        );
        let (mut w, mut g, mut decay) = (Vector3::zeros(), Vector3::zeros(), 1.0);
        for (i, b) in bias.chunks_exact_mut(3).enumerate() {
            b.copy_from_slice((w + g).as_slice());
            let h = step(t, c * CHUNK + i);
            if walk_on {
                w += normal3(&mut walk_rng) * (model.random_walk * h.sqrt());
            }
            if gm_on {
                let a = (-h / model.gauss_markov_tau).exp();
                g = g * a + normal3(&mut gm_rng) * (model.gauss_markov_sigma * (1.0 - a * a).sqrt());
                decay *= a;
            }
        }
        (Local { end: w, decay: 1.0 }, Local { end: g, decay })
    }
}

crate::simd_dispatch! {
    /// Pass 3 of [`measure_in_place_cancellable`] on chunk `c` of the stream `(seed, triad)`: the
    /// chunk's walk and Gauss–Markov states at its start and the fixed bias joined to `bias`, and
    /// the readings formed in `readings` (the ideal values in, skipping the terms that are off:
    /// most simulations have neither scale errors nor limits). Per instruction-set path (equal
    /// bit for bit).
    fn readings_chunk(
        t: &[f64],
        model: &SensorModel,
        stream_of: (u64, u64, usize),
        start: ((Vector3<f64>, Vector3<f64>), Vector3<f64>, bool),
        bias: &mut [f64],
        readings: &mut [f64],
    ) -> () {
        let ((seed, triad, c), ((w_start, g_start), fixed, gm_on)) = (stream_of, start);
        let ideal_sensor = model.matrix == Matrix3::identity();
        let clean = model.range == f64::INFINITY && model.resolution == 0.0;
        let limit = |v: f64| quantise(v.clamp(-model.range, model.range), model.resolution);
        let mut white = stream(seed, triad, Process::White, c);
        let mut decay = 1.0;
        for (i, (b, u)) in bias.chunks_exact_mut(3).zip(readings.chunks_exact_mut(3)).enumerate() {
            let h = step(t, c * CHUNK + i);
            let b_k = Vector3::from_column_slice(b) + w_start + g_start * decay + fixed;
            b.copy_from_slice(b_k.as_slice());
            let ideal = Vector3::from_column_slice(u);
            let scaled = if ideal_sensor { ideal } else { model.matrix * ideal };
            let reading = scaled + b_k + normal3(&mut white) * (model.density / h.sqrt());
            let reading = if clean { reading } else { reading.map(limit) };
            u.copy_from_slice(reading.as_slice());
            if gm_on {
                decay *= (-h / model.gauss_markov_tau).exp();
            }
        }
    }
}

/// Values per block of the parallel searches.
const SEARCH_BLOCK: usize = 1 << 16;

/// The first index in `0..n` where `bad` holds, searched block by block on every core; a block
/// that `clean` passes (one pass with no early exit, which vectorises) is not searched. The checks
/// of a run read 64 bytes per sample per triad: an element-wise search was 74 instructions per
/// sample and triad, 18% of `simulate`'s measuring.
fn first_where(
    n: usize,
    clean: impl Fn(std::ops::Range<usize>) -> bool + Sync,
    bad: impl Fn(usize) -> bool + Sync,
) -> Option<usize> {
    (0..n.div_ceil(SEARCH_BLOCK))
        .into_par_iter()
        .filter_map(|b| {
            let block = b * SEARCH_BLOCK..((b + 1) * SEARCH_BLOCK).min(n);
            if clean(block.clone()) {
                return None;
            }
            block.into_iter().find(|&i| bad(i))
        })
        .min()
}

/// The index of the first value that is not finite.
fn first_non_finite(values: &[f64]) -> Option<usize> {
    first_where(
        values.len(),
        |r| super::all_finite(&values[r]),
        |i| !values[i].is_finite(),
    )
}

/// [`crate::time::check_increasing`] (the same error), searched on every core. That one stays
/// serial: it also runs outside the bindings' thread pools, where a parallel search would use
/// rayon's global pool (which a forked child has without its threads).
fn check_increasing(t: &[f64]) -> Result<()> {
    if let Some(index) = first_non_finite(t) {
        return Err(Error::NonFinite { index });
    }
    // Each pair `(t[k − 1], t[k])` of the block's `k`, with `&` rather than `&&` (no early exit).
    let rising = |r: std::ops::Range<usize>| {
        let from = r.start.max(1);
        t[from..r.end]
            .iter()
            .zip(&t[from - 1..])
            .fold(true, |ok, (b, a)| ok & (b > a))
    };
    if let Some(k) = first_where(t.len(), rising, |k| k > 0 && t[k] <= t[k - 1]) {
        return Err(Error::NonIncreasingTime {
            index: k,
            dt: t[k] - t[k - 1],
        });
    }
    Ok(())
}

/// The model field to blame for readings that overflowed: the largest of the white noise's
/// `density/√h`, the walk's `random_walk·√T`, the constant bias and the error model's sigmas (the
/// ideal readings were checked finite), named as [`SensorModel`]'s fields.
fn overflow_culprit(t: &[f64], model: &SensorModel) -> &'static str {
    let shortest = t.windows(2).fold(f64::INFINITY, |m, w| m.min(w[1] - w[0]));
    let span = t[t.len() - 1] - t[0];
    let terms = [
        ("density", model.density / shortest.sqrt()),
        ("random_walk", model.random_walk * span.sqrt()),
        ("bias", model.bias.amax()),
        ("errors", model.turn_on_sigma.max(model.gauss_markov_sigma)),
    ];
    terms
        .iter()
        .fold(("errors", 0.0), |m, t| if t.1 > m.1 { *t } else { m })
        .0
}

fn quantise(v: f64, resolution: f64) -> f64 {
    // From 2^52 steps on every f64 quotient is a whole number: v is on the grid as f64 can hold it
    // (and v / resolution may overflow for a subnormal resolution).
    const WHOLE: f64 = 4_503_599_627_370_496.0;
    let steps = v / resolution;
    if resolution > 0.0 && steps.abs() < WHOLE {
        steps.round() * resolution
    } else {
        v
    }
}
