//! The rayon pools the kernels run in. A process-wide pool set by `imukit.set_num_threads(n)`
//! (until then: rayon's global pool, one thread per core), and per-call pools for an explicit
//! `threads=` argument. Pools are cached by size: building one spawns its threads, so a call
//! with `threads=4` reuses the pool of the previous one instead of paying that every time.
//!
//! Long kernels run [`interruptible`]: on a thread of their own while the calling thread, waiting
//! with the GIL released, runs Python's signal handlers every [`POLL`], so that Ctrl-C stops them
//! within a few ms instead of when they return (11.6 s on a 25 M-sample `propagate`).

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

use imukit::Cancel;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};

/// Pools by thread count.
static POOLS: Mutex<Option<HashMap<usize, Arc<ThreadPool>>>> = Mutex::new(None);
/// The size set by `set_num_threads`, or `None` for rayon's global pool.
static PROCESS: Mutex<Option<usize>> = Mutex::new(None);

/// A lock that survives a panic in another holder (the guarded data stays consistent: a map
/// insert or a number store).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The cached pool of `n` threads, built on first use.
fn pool(n: usize) -> PyResult<Arc<ThreadPool>> {
    let mut pools = lock(&POOLS);
    let pools = pools.get_or_insert_with(HashMap::new);
    if let Some(p) = pools.get(&n) {
        return Ok(Arc::clone(p));
    }
    let built = ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("imukit-{i}"))
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))?;
    let built = Arc::new(built);
    pools.insert(n, Arc::clone(&built));
    Ok(built)
}

/// Set in a child made by `fork()`: it holds copies of the pools but none of their threads, so a
/// kernel sent to one waited for ever (a `ProcessPoolExecutor` worker on Linux's default start
/// method hung in `integrate`). The child builds its pools afresh, rayon's global pool included.
static FORKED: AtomicBool = AtomicBool::new(false);

/// Called by `os.register_at_fork(after_in_child=…)` (`imukit.threads`): forgets the parent's
/// pools (dropping one would signal threads that do not exist here) and routes the global pool's
/// calls to a fresh one. A pool being built by another thread at the instant of the fork keeps the
/// cache locked; the cache is then left as it is (a kernel sent to one of its pools would wait).
#[pyfunction]
pub(crate) fn after_fork_in_child() {
    FORKED.store(true, Ordering::SeqCst);
    CORES.store(0, Ordering::Relaxed);
    if let Ok(mut pools) = POOLS.try_lock() {
        if let Some(parents) = pools.take() {
            std::mem::forget(parents);
        }
    }
}

/// [`cores`], once read; 0 before. Not a `OnceLock`: a fork while another thread is reading
/// would leave the child's copy "being initialised" for ever; two threads that race both read.
static CORES: AtomicUsize = AtomicUsize::new(0);

/// The CPUs this process may use, read once per process: `available_parallelism` reads the
/// cgroup's quota files on every call (an open, reads and a close, ~40 µs on this project's VM:
/// 2.6× a 200-sample Mahony run when each `run` asked). A forked child reads its own
/// ([`after_fork_in_child`]): it may have been given fewer CPUs.
fn cores() -> usize {
    match CORES.load(Ordering::Relaxed) {
        0 => {
            let n = std::thread::available_parallelism().map_or(1, usize::from);
            CORES.store(n, Ordering::Relaxed);
            n
        }
        n => n,
    }
}

/// Runs `f` (which may use rayon) on `threads` threads when given, else in the process-wide
/// pool. Call it with the GIL released.
pub(crate) fn run_in_pool<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> PyResult<R> {
    // A statement of its own: the lock is released before the kernel runs, so that calls from
    // several Python threads run at once.
    let size = threads
        .or(*lock(&PROCESS))
        .or_else(|| FORKED.load(Ordering::SeqCst).then(cores));
    match size {
        Some(n) => Ok(pool(n)?.install(f)),
        None => Ok(f()),
    }
}

/// Sets the number of threads every parallel kernel uses from now on (`threads=` on a call
/// overrides it). `n` ≥ 1, checked by `imukit.set_num_threads`.
#[pyfunction]
pub(crate) fn set_num_threads(py: Python<'_>, n: usize) -> PyResult<()> {
    py.detach(|| pool(n))?;
    *lock(&PROCESS) = Some(n);
    Ok(())
}

/// The number of threads parallel kernels use when a call does not say.
#[pyfunction]
pub(crate) fn get_num_threads() -> usize {
    match *lock(&PROCESS) {
        Some(n) => n,
        None => rayon::current_num_threads(),
    }
}

/// The instruction-set path the dispatched kernels run (`"baseline"`, `"avx2"`, `"avx512"`;
/// [`imukit::simd`]): `IMUKIT_SIMD`'s choice when set, else the best this CPU has. An unknown
/// `IMUKIT_SIMD` is a `ParameterError` here; the package calls this at import, so that no kernel
/// runs with such a value (the Rust kernels alone would take the best path).
#[pyfunction]
pub(crate) fn simd_path(py: Python<'_>) -> PyResult<&'static str> {
    imukit::simd::requested().map_err(|e| crate::to_py(py, imukit::simd::VARIABLE, e))?;
    Ok(imukit::simd::path().name())
}

/// How often the waiting thread runs the signal handlers.
const POLL: Duration = Duration::from_millis(20);

/// Samples below which a kernel runs on the calling thread: it ends before a Ctrl-C would matter,
/// and starting a thread costs about 20 µs.
pub(crate) const INTERRUPTIBLE_FROM: usize = 4 * Cancel::EVERY;

/// `kernel(cancel)` with the GIL released, stoppable by Ctrl-C: for `n` samples from
/// [`INTERRUPTIBLE_FROM`] it runs on a scoped thread while this one runs Python's signal handlers
/// every [`POLL`]; when one raises (KeyboardInterrupt) the flag is set, the kernel stops at its
/// next poll ([`Cancel::EVERY`] samples), and that exception is returned instead of its result.
pub(crate) fn interruptible<R: Send>(
    py: Python<'_>,
    n: usize,
    kernel: impl FnOnce(&Cancel) -> R + Send,
) -> PyResult<R> {
    let cancel = Cancel::new();
    if n < INTERRUPTIBLE_FROM {
        return Ok(py.detach(|| kernel(&cancel)));
    }
    let (tx, rx) = mpsc::channel();
    std::thread::scope(|scope| {
        let cancel = &cancel;
        scope.spawn(move || {
            // The receiver lives until this thread is joined (end of scope).
            let _ = tx.send(kernel(cancel));
        });
        let mut raised: Option<PyErr> = None;
        let mut rx = rx;
        loop {
            // The receiver is Send, not Sync: it crosses into the GIL-free wait and back.
            let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            match received {
                Ok(result) => return raised.map_or(Ok(result), Err),
                Err(RecvTimeoutError::Timeout) if raised.is_none() => {
                    if let Err(e) = py.check_signals() {
                        cancel.cancel();
                        raised = Some(e);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err("the kernel's thread ended without a result"));
                }
            }
        }
    })
}

/// An output that a kernel fills in order, from its start, at an even pace over its `n` samples
/// (a row per sample, or per `k` samples): its address and its length in bytes (an address, not a
/// slice: the kernel holds the array mutably meanwhile).
#[derive(Clone, Copy)]
pub(crate) struct Fresh {
    addr: usize,
    bytes: usize,
}

impl Fresh {
    /// The output `rows`, which must stay allocated until [`prefaulting`] returns.
    pub(crate) fn of<T>(rows: &[T]) -> Self {
        Self {
            addr: rows.as_ptr() as usize,
            bytes: std::mem::size_of_val(rows),
        }
    }

    /// Faults in the pages of its share of samples `from..to` of `n` (a page that straddles two
    /// shares in both); false where the system refuses.
    fn populate(&self, from: usize, to: usize, n: usize) -> bool {
        let at = |k: usize| (self.bytes as u128 * k as u128 / n as u128) as usize;
        imukit::pages::populate(self.addr + at(from), at(to) - at(from))
    }
}

/// Samples whose outputs [`prefaulting`] faults in at a time: the outputs' shares advance
/// together, in the order the kernel writes them.
const PREFAULT_SAMPLES: usize = 1 << 14;

/// Output bytes from which [`prefaulting`] starts its thread (~20 µs): clearing 8 MiB of fresh
/// pages takes ~1.5 ms on this project's 2-core VM.
const PREFAULT_FROM_BYTES: usize = 8 << 20;

/// Sets its flag when dropped: when [`prefaulting`]'s `f` returns or unwinds.
struct SetOnDrop<'a>(&'a AtomicBool);

impl Drop for SetOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// `f()` while a scoped thread faults in the pages of its `fresh` outputs (`n` samples) ahead of
/// it ([`imukit::pages::populate`]), for outputs of [`PREFAULT_FROM_BYTES`] or more: the kernel's
/// thread then finds them present instead of stopping for the system to clear each fresh page (a
/// tenth to a half of a single-threaded run: a filter's 56 B a sample, propagate's 1.8 kB). The
/// same pages are cleared either way, by the helper; the results do not change. Not where the
/// process has one thread to give (`set_num_threads(1)`, one CPU): there the helper would only
/// take turns with the kernel.
pub(crate) fn prefaulting<R>(n: usize, fresh: &[Fresh], f: impl FnOnce() -> R) -> R {
    // The size first: the other two tests cost more than a short kernel.
    if fresh.iter().map(|o| o.bytes).sum::<usize>() < PREFAULT_FROM_BYTES || cores() < 2 || get_num_threads() < 2 {
        return f();
    }
    // Set when `f` returns or unwinds (an error, Ctrl-C, a panic): the rest would be cleared for
    // nothing.
    let done = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let helper = std::thread::Builder::new()
            .name("imukit-prefault".into())
            .spawn_scoped(scope, || {
                for from in (0..n).step_by(PREFAULT_SAMPLES) {
                    let to = (from + PREFAULT_SAMPLES).min(n);
                    if done.load(Ordering::Relaxed) || !fresh.iter().all(|o| o.populate(from, to, n)) {
                        break; // done, or refused (a kernel before 5.14, a memory limit): the writer faults the rest
                    }
                }
            });
        // No thread to be had: the kernel faults its own pages, as without the helper.
        let _stop = helper.is_ok().then_some(SetOnDrop(&done));
        f()
    })
}
