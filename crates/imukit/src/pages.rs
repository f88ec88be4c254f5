//! Large scratch rows on transparent huge pages.
//!
//! A fresh 4 KiB page costs a fault at its first write: on this project's 2-core VM ~2.6 µs a
//! page, so rows of 48 B per sample cost 33 ns/sample to touch against 5.5 ns/sample on 2 MiB
//! pages (`python bench/bandwidth.py --pages --n 1000000`). Linux backs a mapping advised
//! `MADV_HUGEPAGE` with huge pages when transparent huge pages are in their default "madvise"
//! mode. numpy advises every array of 4 MiB or more (imukit's outputs are on huge pages already);
//! `rows` does the same for the core's own scratch, e.g. the smoother's backward track.
//!
//! Even on huge pages the system clears each fresh page at its first write, on the writing
//! thread (7–24% of a long filter, propagate or simulate run in `perf`). [`populate`] lets another
//! thread take those faults ahead of the writer (the Python glue's `threads::prefaulting`).

/// Below this many bytes a buffer is left as the allocator gives it (numpy's threshold).
const HUGE_FROM: usize = 4 << 20;

/// `n` copies of `value`, the buffer advised for huge pages before its first write (Linux; a
/// plain vector elsewhere or below [`HUGE_FROM`] bytes).
pub(crate) fn rows<T: Clone>(value: T, n: usize) -> Vec<T> {
    let mut v: Vec<T> = Vec::with_capacity(n);
    advise_huge(v.as_ptr().cast(), v.capacity() * std::mem::size_of::<T>());
    v.resize(n, value);
    v
}

#[cfg(target_os = "linux")]
fn advise_huge(start: *const u8, bytes: usize) {
    // A refusal (no THP) leaves the buffer on small pages.
    if bytes >= HUGE_FROM {
        advise(start as usize, bytes, libc::MADV_HUGEPAGE);
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge(_: *const u8, _: usize) {}

/// Faults in the whole pages of `[start, start + bytes)` writable without writing them
/// (`MADV_POPULATE_WRITE`, Linux 5.14), so that the thread that then writes them finds them present
/// and cleared. The contents do not change, so another thread may write the range meanwhile; a
/// page it faulted first is skipped. Whether the system did it: false on an older kernel or
/// another system, where it does nothing.
///
/// The range must lie inside one live allocation of the caller's for the whole call (an address,
/// not a reference, so that the writer may hold the buffer mutably meanwhile).
pub fn populate(start: usize, bytes: usize) -> bool {
    #[cfg(target_os = "linux")]
    return advise(start, bytes, libc::MADV_POPULATE_WRITE);
    #[cfg(not(target_os = "linux"))]
    return false;
}

/// `madvise(advice)` on the whole pages inside `[start, start + bytes)`; whether it was taken (a
/// range without a whole page is, trivially).
#[cfg(target_os = "linux")]
fn advise(start: usize, bytes: usize, advice: libc::c_int) -> bool {
    let Some(page) = page_size() else { return false };
    // madvise wants a page-aligned start: the whole pages inside the buffer.
    let first = start.next_multiple_of(page);
    let end = (start + bytes) & !(page - 1);
    if end <= first {
        return true;
    }
    // SAFETY: the range lies inside the caller's own allocation (both callers' contract).
    // MADV_HUGEPAGE changes how the kernel backs the pages and MADV_POPULATE_WRITE when they are
    // faulted in, never their contents or their validity. A refusal (a kernel without THP or
    // older than 5.14) leaves the buffer as it was.
    #[allow(unsafe_code)]
    let status = unsafe { libc::madvise(first as *mut libc::c_void, end - first, advice) };
    status == 0
}

/// The system's page size, if a power of two.
#[cfg(target_os = "linux")]
fn page_size() -> Option<usize> {
    // SAFETY: sysconf reads a constant of the system.
    #[allow(unsafe_code)]
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    usize::try_from(page).ok().filter(|p| p.is_power_of_two())
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    /// Populating a fresh mapping keeps every value, whether written before it runs, while it runs
    /// (by another thread) or after: advice that dropped pages (`MADV_DONTNEED`, `MADV_FREE`)
    /// would zero them.
    #[test]
    fn populate_keeps_the_contents_while_another_thread_writes() {
        // 48 MB: above glibc's largest mmap threshold, so fresh pages.
        let n = 6 << 20;
        let mut v: Vec<f64> = Vec::with_capacity(n);
        let (addr, bytes) = (v.as_ptr() as usize, n * 8);
        let (before, rest) = v.spare_capacity_mut().split_at_mut(n / 3);
        before.iter_mut().enumerate().for_each(|(i, x)| {
            x.write(i as f64);
        });
        std::thread::scope(|scope| {
            scope.spawn(|| {
                rest.iter_mut().enumerate().for_each(|(i, x)| {
                    x.write((n / 3 + i) as f64);
                });
            });
            populate(addr, bytes);
        });
        // SAFETY: every element of the capacity was written above.
        #[allow(unsafe_code)]
        unsafe {
            v.set_len(n);
        }
        populate(addr, bytes);
        assert!(v.iter().enumerate().all(|(i, &x)| x == i as f64));
    }

    /// Populating a fresh mapping makes its pages resident before anything writes them (where
    /// the kernel takes the advice).
    #[cfg(target_os = "linux")]
    #[test]
    fn populate_makes_fresh_pages_resident() {
        // 64 MB: above glibc's largest mmap threshold, so a fresh mapping, never touched.
        let v: Vec<u8> = Vec::with_capacity(64 << 20);
        let page = page_size().expect("a power-of-two page size");
        let first = (v.as_ptr() as usize).next_multiple_of(page);
        let pages = (v.capacity() - (first - v.as_ptr() as usize)) / page;
        let resident = || {
            let mut flags = vec![0u8; pages];
            // SAFETY: `[first, first + pages·page)` lies inside `v`'s allocation; mincore writes
            // one byte per page into `flags`, which holds `pages` bytes.
            #[allow(unsafe_code)]
            let status = unsafe { libc::mincore(first as *mut libc::c_void, pages * page, flags.as_mut_ptr()) };
            assert_eq!(status, 0);
            flags.iter().filter(|&&f| f & 1 == 1).count()
        };
        assert!(resident() < pages / 2, "a fresh mapping is mostly not resident");
        if populate(v.as_ptr() as usize, v.capacity()) {
            assert_eq!(resident(), pages);
        } else {
            eprintln!("skipped: this kernel refuses MADV_POPULATE_WRITE (Linux < 5.14)");
        }
    }

    /// The rows are `n` copies of the value, small and large (advised) alike.
    #[test]
    fn rows_hold_n_copies() {
        for n in [0, 1, 1000, 1 << 20] {
            let v = rows([1.5, -2.0, 0.25], n);
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|r| *r == [1.5, -2.0, 0.25]));
        }
    }
}
