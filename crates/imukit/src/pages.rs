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

/// Faults in every page that holds a byte of `[start, start + bytes)` writable without writing
/// it (`MADV_POPULATE_WRITE`, Linux 5.14), so that the thread that then writes the range finds the
/// pages present and cleared. On anonymous memory (numpy's arrays, `Vec`s) the contents do not
/// change, so another thread may write the range meanwhile; a page it faulted first is skipped. On
/// a file mapping the pages would be dirtied (shared) or detached from the file (private): not for
/// those. Whether the system did it: false on an older kernel, under a memory limit, or on another
/// system, where it does nothing.
///
/// The range must lie inside one live allocation of the caller's for the whole call (an address,
/// not a reference, so that the writer may hold the buffer mutably meanwhile). The pages at its
/// ends are faulted whole: they hold part of the range, so they are mapped, and populating leaves
/// the neighbours' bytes as they are.
pub fn populate(start: usize, bytes: usize) -> bool {
    #[cfg(target_os = "linux")]
    {
        let Some(page) = page_size() else { return false };
        if bytes == 0 {
            return true;
        }
        let first = start & !(page - 1);
        let end = (start + bytes).next_multiple_of(page);
        madvise(first, end - first, libc::MADV_POPULATE_WRITE)
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (start, bytes);
        false
    }
}

/// `madvise(advice)` on the whole pages inside `[start, start + bytes)`; whether it was taken (a
/// range without a whole page is, trivially).
#[cfg(target_os = "linux")]
fn advise(start: usize, bytes: usize, advice: libc::c_int) -> bool {
    let Some(page) = page_size() else { return false };
    // madvise wants a page-aligned start: the whole pages inside the buffer.
    let first = start.next_multiple_of(page);
    let end = (start + bytes) & !(page - 1);
    end <= first || madvise(first, end - first, advice)
}

/// `madvise` on page-aligned `[first, first + len)`, pages of the caller's mapped buffers; whether
/// it was taken.
#[cfg(target_os = "linux")]
fn madvise(first: usize, len: usize, advice: libc::c_int) -> bool {
    // SAFETY: the pages are mapped memory of the caller's (both callers' contract). MADV_HUGEPAGE
    // changes how the kernel backs them and MADV_POPULATE_WRITE when they are faulted in, never
    // their contents on anonymous memory or their validity. A refusal (a kernel without THP or
    // older than 5.14) leaves them as they were.
    #[allow(unsafe_code)]
    let status = unsafe { libc::madvise(first as *mut libc::c_void, len, advice) };
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
    /// (by another thread, in no set order with it) or after: advice that dropped pages
    /// (`MADV_DONTNEED`) would zero them.
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

    /// Linux's version as (major, minor), from uname.
    #[cfg(target_os = "linux")]
    fn kernel_version() -> (u32, u32) {
        let release = std::fs::read_to_string("/proc/sys/kernel/osrelease").expect("the kernel's release");
        let mut parts = release.trim().split(['.', '-']).map(|p| p.parse::<u32>().unwrap_or(0));
        (parts.next().unwrap_or(0), parts.next().unwrap_or(0))
    }

    /// Populating a fresh mapping gives every page of the range, the partial pages at its ends
    /// included, a private page of its own before anything writes it: `/proc/self/pagemap`'s
    /// "present" and "exclusively mapped" bits (a read fault, `MADV_POPULATE_READ`, maps the
    /// shared zero page: present, not exclusive). Linux ≥ 5.14 must take the advice.
    #[cfg(target_os = "linux")]
    #[test]
    fn populate_gives_every_page_of_the_range_its_own_page() {
        use std::io::{Read, Seek, SeekFrom};
        // 64 MB: above glibc's largest mmap threshold, so a fresh mapping, never touched.
        let v: Vec<u8> = Vec::with_capacity(64 << 20);
        let page = page_size().expect("a power-of-two page size");
        // A range that starts and ends inside a page.
        let (start, bytes) = (v.as_ptr() as usize + 3 * page + 100, 40 * page);
        let pages = (start - (start & !(page - 1)) + bytes).div_ceil(page);
        let flags = || {
            let mut file = std::fs::File::open("/proc/self/pagemap").expect("pagemap");
            file.seek(SeekFrom::Start((start / page * 8) as u64)).expect("seek");
            let mut raw = vec![0u8; pages * 8];
            file.read_exact(&mut raw).expect("read");
            let entries: Vec<u64> = raw.as_chunks::<8>().0.iter().map(|b| u64::from_le_bytes(*b)).collect();
            let count = |bit: u32| entries.iter().filter(|&&e| e >> bit & 1 == 1).count();
            (count(63), count(56))
        };
        assert_eq!(flags(), (0, 0), "a fresh mapping is not present");
        let taken = populate(start, bytes);
        if kernel_version() < (5, 14) {
            assert!(!taken, "kernels before 5.14 do not know MADV_POPULATE_WRITE");
            return;
        }
        assert!(taken, "Linux {:?} refused MADV_POPULATE_WRITE", kernel_version());
        assert_eq!(flags(), (pages, pages));
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
