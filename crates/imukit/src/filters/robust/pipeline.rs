//! The online run on two threads, bit for bit the run on one.
//!
//! A step is an attitude half ([`step::attitude_half`], [`step::window_due`],
//! [`step::update_bias`]: rest, gyro strapdown, inclination, the bias's Kalman update) and a window
//! half ([`step::window_half`]: the bias window's sums, in 9D the field's gate and heading loop,
//! the output attitude; here also every output row). The window half needs the attitude half's
//! `q6`, inclination correction and rest flag of the same sample and the bias; the attitude half
//! needs the window half only where a bias window ends (its sums, once every `bias_window_s` in
//! motion and every `bias_rest_window_s` at rest), which is also the only place the bias changes.
//! So the calling thread runs the attitude halves and puts each sample's `q6`, correction, step
//! and rest flag in a ring of [`RING`] samples; a second thread (`rayon::join`) runs the window
//! halves from the ring, behind it; where a window ends, the calling thread catches the window
//! side up to that sample under its lock (doing what the second thread has not done yet itself),
//! takes the sums, updates the bias and gives it back.
//!
//! Both sides run the sequential step's functions on their own fields in the same order, so the
//! outputs and the final state are those of one thread, bit for bit (tested). Nothing waits for a
//! thread that may never come: with no second thread free (a pool of one, or every thread busy)
//! the calling thread runs the window halves itself when the ring is full, a block at a time.

use std::hint;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, OnceLock, PoisonError, TryLockError};
use std::thread::{self, Thread};

use nalgebra::{Quaternion, UnitQuaternion, Vector2};

use super::step::{self, Coefs, CoefsCache, Update};
use super::{attitude_half_sum, run_any, window_half_sum, write_bias, Outputs, Robust, RobustState, Sigma, Stepper};
use crate::filters::{row, Inputs};
use crate::{Cancel, Error, Result};

/// Runs of this many samples and more take two threads (rayon's `join` costs a few µs, a
/// sample about 0.2 µs).
pub(super) const FROM: usize = 1024;
/// Samples the window side may lag behind (64 B each).
const RING: usize = 1024;
/// Samples made visible to the window side at a time (~2 µs of the calling thread's work: the
/// window side is that far behind when a window ends and the calling thread waits for it).
const BLOCK: usize = 16;
/// Empty polls of the ring before the window thread sleeps (~0.1–1 ms).
const SPINS: u32 = 1 << 14;

/// One sample's hand-off as bits: `q6` as x, y, z, w, the inclination correction x, y, the step
/// (0: no step) and the rest flag (1 or 0).
type Slot = [AtomicU64; 8];

/// The window side: its copy of the state (it writes only the window half's fields; the bias
/// and its covariance are handed to it at each update) and the output rows, all of them written
/// here.
struct WindowSide<'o> {
    state: RobustState,
    cache: CoefsCache,
    /// Samples done.
    done: usize,
    /// The first sample whose window half overflowed (index in the whole record).
    overflow: Option<usize>,
    out: Outputs<'o>,
    sigma: Sigma,
}

impl WindowSide<'_> {
    /// Row `j` from the state (`rest` is the attitude half's, carried by the ring).
    #[inline(always)]
    fn write(&mut self, j: usize, rest: bool) {
        let s = &self.state;
        self.out.q[j] = s.q.coords.into();
        self.out.mag_disturbed[j] = s.mag_disturbed;
        self.out.rest[j] = rest;
        write_bias(self.out.bias, self.out.bias_sigma, &mut self.sigma, j, s);
    }
}

/// A value on cache lines of its own (128 B: the adjacent-line prefetcher pairs lines): the
/// fields one thread writes and the other polls would otherwise move a line between the cores
/// at every write, with the read-only fields beside them.
#[repr(align(128))]
struct Line<T>(T);

impl<T> std::ops::Deref for Line<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.0
    }
}

/// What the two sides share.
struct Shared<'a, 'o> {
    filter: &'a Robust,
    gyro: &'a [[f64; 3]],
    mags: Option<&'a [[f64; 3]]>,
    /// Index of the part's first row in the whole record (for errors).
    first: usize,
    ring: Box<[Slot]>,
    /// Samples put in the ring and visible to the window thread.
    published: Line<AtomicUsize>,
    /// Samples the window side has done (mirrors `WindowSide::done`, read without the lock).
    consumed: Line<AtomicUsize>,
    /// Set when the attitude side has put its last sample: it then finishes the window side.
    finished: Line<AtomicBool>,
    /// The window thread sleeps (or is about to).
    parked: Line<AtomicBool>,
    worker: OnceLock<Thread>,
    window: Line<Mutex<WindowSide<'o>>>,
}

impl<'o> Shared<'_, 'o> {
    /// The window side, waited for by polling: the other side holds it only while it runs a
    /// few dozen samples (a few µs), less than sleeping and being woken would cost (a futex wait
    /// and wake per bias window was a tenth of a run). A panic elsewhere leaves it as consistent
    /// as the panic left it; the panic itself reaches the caller through `join`.
    fn lock(&self) -> MutexGuard<'_, WindowSide<'o>> {
        loop {
            match self.window.try_lock() {
                Ok(h) => return h,
                Err(TryLockError::Poisoned(h)) => return h.into_inner(),
                Err(TryLockError::WouldBlock) => hint::spin_loop(),
            }
        }
    }

    /// Makes samples `..to` visible to the window thread, waking it if it sleeps.
    fn publish(&self, to: usize) {
        self.published.store(to, Ordering::SeqCst);
        self.wake();
    }

    fn wake(&self) {
        if self.parked.load(Ordering::SeqCst) {
            if let Some(t) = self.worker.get() {
                t.unpark();
            }
        }
    }

    /// Runs the window halves of samples `h.done..to` (all in the ring) and writes their rows.
    #[inline(always)]
    fn catch_up(&self, h: &mut WindowSide<'_>, to: usize) {
        let p = &self.filter.params;
        for j in h.done..to {
            let [x, y, z, w, cx, cy, dt, rest] = self.ring[j % RING]
                .each_ref()
                .map(|a| f64::from_bits(a.load(Ordering::Relaxed)));
            if dt > 0.0 {
                let c = h.cache.for_dt(p, dt);
                let q6 = UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z));
                let mag = self.mags.map(|m| row(&m[j]));
                let gyro = row(&self.gyro[j]);
                let corr = Vector2::new(cx, cy);
                step::window_half(
                    p,
                    self.filter.world,
                    &c,
                    &mut h.state,
                    (&q6, &corr),
                    mag.as_ref(),
                    &gyro,
                );
                if h.overflow.is_none() && !window_half_sum(&h.state).is_finite() {
                    h.overflow = Some(self.first + j);
                }
            }
            h.write(j, rest != 0.0);
        }
        h.done = h.done.max(to);
        self.consumed.store(h.done, Ordering::Release);
    }

    /// A bias update `u` is due at sample `k`: the window side caught up to it, its sums moved
    /// into `s`, the update made, and the new bias and the emptied sums given back.
    #[inline(always)]
    fn window_ends(&self, k: usize, s: &mut RobustState, u: Update) {
        self.publish(k + 1);
        let mut h = self.lock();
        self.catch_up(&mut h, k + 1);
        take_window(s, &h.state);
        step::update_bias(&self.filter.params, s, u);
        take_window(&mut h.state, s);
        (h.state.bias, h.state.bias_cov) = (s.bias, s.bias_cov);
        // Row k holds the bias after the update.
        h.write(k, s.rest);
    }

    /// The window thread: runs what is published until the attitude side has finished (which
    /// then does the rest itself); polls, then sleeps until woken.
    #[inline(always)]
    fn work(&self) {
        // Set before `parked` can be: `wake` finds the handle whenever it reads `parked` true.
        let _ = self.worker.set(thread::current());
        let mut idle = 0;
        loop {
            let available = self.published.load(Ordering::SeqCst);
            if available > self.consumed.load(Ordering::Acquire) {
                let mut h = self.lock();
                self.catch_up(&mut h, available);
                idle = 0;
            } else if self.finished.load(Ordering::SeqCst) {
                return;
            } else if idle < SPINS {
                idle += 1;
                hint::spin_loop();
            } else {
                self.parked.store(true, Ordering::SeqCst);
                // Rechecked after `parked` is set: a publish or finish before it is seen here, one
                // after it sees `parked` and unparks (a token `park` then returns on at once).
                if self.published.load(Ordering::SeqCst) == available && !self.finished.load(Ordering::SeqCst) {
                    thread::park();
                }
                self.parked.store(false, Ordering::SeqCst);
                idle = 0;
            }
        }
    }
}

/// The bias window's sums, from `h` into `s`.
fn take_window(s: &mut RobustState, h: &RobustState) {
    (s.win_rot, s.win_off, s.win_corr, s.win_mag_time) = (h.win_rot, h.win_off, h.win_corr, h.win_mag_time);
}

/// Every field the window half writes, from the window side's state `h` into `s`.
fn take_window_half(s: &mut RobustState, h: &RobustState) {
    take_window(s, h);
    s.q = h.q;
    (s.loop_rot1, s.loop_rot2, s.loop_bias1, s.loop_bias2) = (h.loop_rot1, h.loop_rot2, h.loop_bias1, h.loop_bias2);
    s.loop_dt = h.loop_dt;
    (s.heading, s.heading_angle) = (h.heading, h.heading_angle);
    (s.loop_head_rot, s.loop_head_bias) = (h.loop_head_rot, h.loop_head_bias);
    (s.mag_ready, s.mag_norm, s.mag_dip) = (h.mag_ready, h.mag_norm, h.mag_dip);
    (s.cand_norm, s.cand_dip, s.cand_time) = (h.cand_norm, h.cand_dip, h.cand_time);
    (s.mag_rejected, s.mag_disturbed) = (h.mag_rejected, h.mag_disturbed);
}

/// Sets `finished` and wakes the window thread when dropped.
struct Finish<'s, 'a, 'o>(&'s Shared<'a, 'o>);

impl Drop for Finish<'_, '_, '_> {
    fn drop(&mut self) {
        self.0.finished.store(true, Ordering::SeqCst);
        self.0.wake();
    }
}

/// The calling thread's side: the attitude halves and the ring's writing end.
struct AttitudeSide<'s, 'a, 'o> {
    shared: &'s Shared<'a, 'o>,
    /// Samples put in the ring.
    written: usize,
    /// Samples below this index have a free slot (the window side has done the slot's last).
    room: usize,
}

impl AttitudeSide<'_, '_, '_> {
    #[inline(always)]
    fn put(&mut self, k: usize, values: [f64; 8]) {
        if k >= self.room {
            self.make_room(k);
        }
        for (slot, x) in self.shared.ring[k % RING].iter().zip(values) {
            slot.store(x.to_bits(), Ordering::Relaxed);
        }
        self.written = k + 1;
        if self.written.is_multiple_of(BLOCK) {
            self.shared.publish(self.written);
        }
    }

    /// The ring is full up to sample `k`: the window side's oldest samples are done here if the
    /// window thread has not done them.
    #[inline(always)]
    fn make_room(&mut self, k: usize) {
        let shared = self.shared;
        if k >= shared.consumed.load(Ordering::Acquire) + RING {
            shared.publish(k);
            let mut h = shared.lock();
            shared.catch_up(&mut h, k);
        }
        self.room = shared.consumed.load(Ordering::Acquire) + RING;
    }
}

impl Stepper for AttitudeSide<'_, '_, '_> {
    #[inline(always)]
    fn step(
        &mut self,
        k: usize,
        c: &Coefs,
        s: &mut RobustState,
        gyro: &nalgebra::Vector3<f64>,
        accel: &nalgebra::Vector3<f64>,
        _: Option<&nalgebra::Vector3<f64>>,
    ) {
        let p = &self.shared.filter.params;
        let (corr, q6) = step::attitude_half(p, c, s, gyro, accel);
        let rest = f64::from(u8::from(s.rest));
        self.put(k, [q6.i, q6.j, q6.k, q6.w, corr.x, corr.y, c.dt, rest]);
        if let Some(u) = step::window_due(p, c, s, gyro) {
            self.shared.window_ends(k, s, u);
        }
    }

    #[inline(always)]
    fn skip(&mut self, k: usize, s: &RobustState) {
        self.put(k, [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, f64::from(u8::from(s.rest))]);
    }

    /// The window side writes every row.
    #[inline(always)]
    fn write(&mut self, _: usize, _: &RobustState) {}

    /// The attitude half's fields only: this thread's copies of the window half's are stale
    /// (the window side checks them, [`Shared::catch_up`]). The window half's state overflows
    /// only from a non-finite `q6`, which the attitude half's shows first.
    #[inline(always)]
    fn overflowed(&self, s: &RobustState) -> bool {
        !attitude_half_sum(s).is_finite()
    }
}

/// [`Robust::run_part`]'s run with the attitude written, on two threads where rayon's pool has
/// them free; `start` is `(first, continued)`. An uninitialised state's first sample (it
/// initialises the attitude, and the heading from the field) runs alone first.
pub(super) fn run(
    f: &Robust,
    state: &mut RobustState,
    inputs: &Inputs<'_>,
    (first, continued): (usize, bool),
    out: &mut Outputs<'_>,
    cancel: &Cancel,
) -> Result<()> {
    if state.initialized || inputs.t.is_empty() {
        return run_split(f, state, inputs, (first, continued), out, cancel);
    }
    let (mut head, mut tail) = out.split_at(1);
    let n = inputs.t.len();
    let (one, rest) = (part(inputs, 0..1), part(inputs, 1..n));
    run_any(f, state, &one, (first, continued), true, &mut head, cancel)?;
    run_split(f, state, &rest, (first + 1, true), &mut tail, cancel)
}

/// Rows `rows` of `inputs`.
fn part<'a>(inputs: &Inputs<'a>, rows: std::ops::Range<usize>) -> Inputs<'a> {
    Inputs {
        t: &inputs.t[rows.clone()],
        gyro: &inputs.gyro[rows.clone()],
        accel: &inputs.accel[rows.clone()],
        mag: inputs.mag.map(|m| &m[rows]),
    }
}

/// The two sides over a run on an initialised state.
fn run_split(
    f: &Robust,
    state: &mut RobustState,
    inputs: &Inputs<'_>,
    start: (usize, bool),
    out: &mut Outputs<'_>,
    cancel: &Cancel,
) -> Result<()> {
    let shared = Shared {
        filter: f,
        gyro: inputs.gyro,
        mags: inputs.mag,
        first: start.0,
        ring: (0..RING).map(|_| Slot::default()).collect(),
        published: Line(AtomicUsize::new(0)),
        consumed: Line(AtomicUsize::new(0)),
        finished: Line(AtomicBool::new(false)),
        parked: Line(AtomicBool::new(false)),
        worker: OnceLock::new(),
        window: Line(Mutex::new(WindowSide {
            state: *state,
            cache: CoefsCache::new(Coefs::new(&f.params, 0.0)),
            done: 0,
            overflow: None,
            out: out.split_at(0).1, // every row
            sigma: Sigma::default(),
        })),
    };
    let mut side = AttitudeSide {
        shared: &shared,
        written: 0,
        room: RING,
    };
    let (result, ()) = rayon::join(
        || attitude_side(f, state, inputs, start, &mut side, cancel),
        || window_side(&shared),
    );
    let h = shared.window.0.into_inner().unwrap_or_else(PoisonError::into_inner);
    take_window_half(state, &h.state);
    result?;
    match h.overflow {
        Some(index) => Err(Error::Overflow { index }),
        None => Ok(()),
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// The calling thread's loop, then the window side finished (its thread may have stopped
    /// polling, or never started).
    fn attitude_side(
        f: &Robust,
        state: &mut RobustState,
        inputs: &Inputs<'_>,
        start: (usize, bool),
        side: &mut AttitudeSide<'_, '_, '_>,
        cancel: &Cancel
    ) -> Result<()> {
        // Whatever ends the loop, a panic too, ends the window thread's wait: `join` waits for
        // it before it passes the panic on.
        let finish = Finish(side.shared);
        // The field is the window side's: the loop reads it only to check it.
        let result = match inputs.mag {
            Some(m) => f.run_loop::<true, _>(state, inputs, m, start, side, cancel),
            None => f.run_loop::<false, _>(state, inputs, &[], start, side, cancel),
        };
        let shared = side.shared;
        shared.published.store(side.written, Ordering::SeqCst);
        // Before the last catch-up, so that the window thread stops polling meanwhile.
        drop(finish);
        let mut h = shared.lock();
        shared.catch_up(&mut h, side.written);
        result
    }
}

crate::simd_dispatch! {
    widest = avx2;
    /// The window thread's loop.
    fn window_side(shared: &Shared<'_, '_>) -> () {
        shared.work();
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::filters::robust::{RobustParams, Track};
    use crate::filters::{Fields, World};
    use nalgebra::Vector3;
    use std::sync::atomic::AtomicBool;

    /// 9D record of `n` samples at 200 Hz: rests of 5 s in every 20 s (rest updates of the bias),
    /// turning between (motion windows), the field 1.5 times as strong and turned from 30 s to
    /// 50 s (rejected, then used slowly), with a little noise; the stamps in float seconds (their
    /// steps differ in the last bits).
    struct Record {
        t: Vec<f64>,
        gyro: Vec<[f64; 3]>,
        accel: Vec<[f64; 3]>,
        mag: Vec<[f64; 3]>,
    }

    fn record(n: usize) -> Record {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut noise = move |scale: f64| {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            scale * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        };
        let mut q = UnitQuaternion::from_euler_angles(0.2, -0.1, 0.4);
        let mut r = Record {
            t: Vec::new(),
            gyro: Vec::new(),
            accel: Vec::new(),
            mag: Vec::new(),
        };
        for k in 0..n {
            let t = k as f64 / 200.0;
            let w = if t % 20.0 < 5.0 {
                Vector3::zeros()
            } else {
                Vector3::new(0.8 * (1.3 * t).sin(), 0.6 * (0.7 * t).cos(), 1.1 * (0.3 * t).sin())
            };
            q *= UnitQuaternion::from_scaled_axis(w / 200.0);
            let field = if (30.0..50.0).contains(&t) {
                Vector3::new(14.0, 28.0, -60.0)
            } else {
                Vector3::new(0.0, 20.0, -40.0)
            };
            let (a, m) = (q.inverse() * Vector3::new(0.0, 0.0, 9.81), q.inverse() * field);
            let bias = Vector3::new(0.01, -0.02, 0.015);
            r.t.push(t);
            r.gyro.push((w + bias).map(|x| x + noise(0.01)).into());
            r.accel.push(a.map(|x| x + noise(0.05)).into());
            r.mag.push(m.map(|x| x + noise(0.3)).into());
        }
        r
    }

    fn inputs(r: &Record, rows: std::ops::Range<usize>, nine: bool) -> Inputs<'_> {
        Inputs {
            t: &r.t[rows.clone()],
            gyro: &r.gyro[rows.clone()],
            accel: &r.accel[rows.clone()],
            mag: nine.then(|| &r.mag[rows]),
        }
    }

    /// The run on one thread: rows and final state.
    fn sequential(f: &Robust, s: &mut RobustState, i: &Inputs<'_>, continued: bool) -> (Track, Result<()>) {
        let mut track = Track::new(i.t.len());
        let result = run_any(f, s, i, (0, continued), true, &mut track.outputs(), &Cancel::new());
        (track, result)
    }

    fn piped(f: &Robust, s: &mut RobustState, i: &Inputs<'_>, continued: bool) -> (Track, Result<()>) {
        let mut track = Track::new(i.t.len());
        let result = run(f, s, i, (0, continued), &mut track.outputs(), &Cancel::new());
        (track, result)
    }

    fn bits(s: &RobustState) -> Vec<u64> {
        s.values().iter().map(|x| x.to_bits()).collect()
    }

    fn pool() -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap()
    }

    /// Each start (an uninitialised state, an initialised one not continued, a continued one),
    /// 9D and 6D, gives the rows and the final state of the run on one thread, bit for bit, on the
    /// second thread of a pool of two, and with that thread busy, where the calling thread does the
    /// window side itself whenever the ring fills. The record has rest and motion updates of the
    /// bias and a disturbed field, so the window side's sums and gate are in the state.
    #[test]
    fn two_threads_give_the_run_on_one_bit_for_bit() {
        let r = record(20_000);
        let f = Robust::new(RobustParams::default(), World::Ned).unwrap();
        let pool = pool();
        for nine in [true, false] {
            let mut warm = RobustState::default();
            let (_, ok) = sequential(&f, &mut warm, &inputs(&r, 0..4_000, nine), false);
            ok.unwrap();
            let starts = [
                (RobustState::default(), 0..20_000, false),
                // Ends with the field disturbed: the gate's fields are mid-rejection.
                (RobustState::default(), 0..8_000, false),
                (warm, 4_000..20_000, false),
                (warm, 4_000..20_000, true),
            ];
            for (start, rows, continued) in starts {
                let i = inputs(&r, rows.clone(), nine);
                let at = format!("9D {nine}, rows {rows:?}, continued {continued}");
                let (mut s1, mut s2, mut s3) = (start, start, start);
                let (one, ok) = sequential(&f, &mut s1, &i, continued);
                ok.unwrap();
                assert!(
                    one.rest.iter().any(|&d| d) && one.mag_disturbed.iter().any(|&d| d) == nine,
                    "{at}"
                );
                let (two, ok) = pool.install(|| piped(&f, &mut s2, &i, continued));
                ok.unwrap();
                assert_eq!(two, one, "{at}: two threads");
                assert_eq!(bits(&s2), bits(&s1), "{at}: two threads' state");
                let done = AtomicBool::new(false);
                let (alone, ()) = pool.install(|| {
                    rayon::join(
                        || {
                            let out = piped(&f, &mut s3, &i, continued);
                            done.store(true, Ordering::SeqCst);
                            out
                        },
                        || {
                            while !done.load(Ordering::SeqCst) {
                                hint::spin_loop();
                            }
                        },
                    )
                });
                let (alone, ok) = alone;
                ok.unwrap();
                assert_eq!(alone, one, "{at}: the second thread busy");
                assert_eq!(bits(&s3), bits(&s1), "{at}: its state");
            }
        }
    }

    /// Every output row as bits (NaN rows compare too).
    fn row_bits(t: &Track) -> Vec<u64> {
        let flags = t.rest.iter().chain(&t.mag_disturbed).map(|&b| u64::from(b));
        let numbers =
            t.q.iter()
                .flatten()
                .chain(t.bias.iter().flatten())
                .chain(t.bias_sigma.iter().flatten());
        numbers.map(|x| x.to_bits()).chain(flags).collect()
    }

    /// Finite input so large that the state overflows at row 4321: both runs name that row, and
    /// leave the same rows (row 4321 written, with the step's non-finite values) and state.
    #[test]
    fn an_overflow_stops_both_at_the_same_row_with_the_same_rows() {
        let mut r = record(6_000);
        r.gyro[4_321] = [1e300; 3];
        let f = Robust::new(RobustParams::default(), World::Enu).unwrap();
        for nine in [true, false] {
            let i = inputs(&r, 0..6_000, nine);
            let (mut s1, mut s2) = (RobustState::default(), RobustState::default());
            let (one, e1) = sequential(&f, &mut s1, &i, false);
            let (two, e2) = pool().install(|| piped(&f, &mut s2, &i, false));
            let (e1, e2) = (e1.unwrap_err().to_string(), e2.unwrap_err().to_string());
            assert!(e1.contains("4321") && e1.contains("overflow"), "{e1}");
            assert_eq!(e2, e1);
            assert_ne!(
                one.q[4_321].map(f64::to_bits),
                [0; 4],
                "9D {nine}: row 4321 not written"
            );
            assert_eq!(one.q[4_322], [0.0; 4], "9D {nine}: a row after it written");
            assert_eq!(row_bits(&two), row_bits(&one), "9D {nine}");
            assert_eq!(bits(&s2), bits(&s1), "9D {nine}");
        }
    }

    /// A panic on the calling thread (here a gyro shorter than the stamps, which the checked
    /// entry points refuse before) reaches the caller instead of leaving the window thread
    /// waiting for the end of the run, and `join` for it.
    #[test]
    fn a_panic_on_the_calling_thread_reaches_the_caller() {
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let r = record(6_000);
            let f = Robust::new(RobustParams::default(), World::Enu).unwrap();
            let i = Inputs {
                gyro: &r.gyro[..3_000],
                ..inputs(&r, 0..6_000, true)
            };
            let mut track = Track::new(6_000);
            // Initialised: the run goes straight to the two threads.
            let mut s = f.state_at(&UnitQuaternion::identity(), 0.0);
            let pool = pool();
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| run(&f, &mut s, &i, (0, false), &mut track.outputs(), &Cancel::new()))
            }));
            let _ = sender.send(outcome.is_err());
        });
        let got = receiver.recv_timeout(std::time::Duration::from_secs(60));
        assert_eq!(got, Ok(true), "the run hung, or returned instead of panicking");
    }

    /// A non-finite sample stops both runs with the same error at the same row, the rows before
    /// it and the state after the last good sample equal.
    #[test]
    fn an_error_stops_both_at_the_same_row() {
        let mut r = record(6_000);
        r.gyro[4_321][1] = f64::NAN;
        let f = Robust::new(RobustParams::default(), World::Enu).unwrap();
        let i = inputs(&r, 0..6_000, true);
        let (mut s1, mut s2) = (RobustState::default(), RobustState::default());
        let (one, e1) = sequential(&f, &mut s1, &i, false);
        let (two, e2) = pool().install(|| piped(&f, &mut s2, &i, false));
        let (e1, e2) = (e1.unwrap_err().to_string(), e2.unwrap_err().to_string());
        assert!(e1.contains("4321"), "{e1}");
        assert_eq!(e2, e1);
        assert_eq!(two, one);
        assert_eq!(bits(&s2), bits(&s1));
    }

    /// A cancelled run stops at its first polled row on one thread and on two (the window thread
    /// is released, not left waiting), naming the row in the whole record; an uncancelled flag
    /// changes nothing.
    #[test]
    fn a_cancelled_run_stops_on_both_paths() {
        let r = record(3_000);
        let f = Robust::new(RobustParams::default(), World::Enu).unwrap();
        let i = inputs(&r, 0..3_000, true);
        let cancel = Cancel::new();
        cancel.cancel();
        for threads in [1, 2] {
            let mut track = Track::new(3_000);
            // Initialised: on two threads the run goes straight to the split.
            let mut s = f.state_at(&UnitQuaternion::identity(), 0.0);
            let e = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| f.run_part_cancellable(&mut s, &i, (500, false), &mut track.outputs(), &cancel))
                .unwrap_err();
            assert!(matches!(e, Error::Interrupted { index: 500 }), "{threads} threads: {e}");
        }
        let mut s = RobustState::default();
        let (one, _) = sequential(&f, &mut s, &i, false);
        let mut track = Track::new(3_000);
        let mut s2 = RobustState::default();
        pool()
            .install(|| f.run_part_cancellable(&mut s2, &i, (0, false), &mut track.outputs(), &Cancel::new()))
            .unwrap();
        assert_eq!(track, one);
    }
}
