//! Large scratch rows on transparent huge pages.
//!
//! A fresh 4 KiB page costs a fault at its first write: on this project's 2-core VM ~2.6 µs a
//! page, so rows of 48 B per sample cost 33 ns/sample to touch against 5.5 ns/sample on 2 MiB
//! pages (`python bench/bandwidth.py --pages --n 1000000`). Linux backs a mapping advised
//! `MADV_HUGEPAGE` with huge pages when transparent huge pages are in their default "madvise"
//! mode. numpy advises every array of 4 MiB or more (imukit's outputs are on huge pages already);
//! [`rows`] does the same for the core's own scratch, e.g. the smoother's backward track.

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
    if bytes < HUGE_FROM {
        return;
    }
    // SAFETY: sysconf reads a constant of the system.
    #[allow(unsafe_code)]
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    let Ok(page) = usize::try_from(page) else { return };
    if !page.is_power_of_two() {
        return;
    }
    // madvise wants a page-aligned start: the whole pages inside the buffer.
    let first = (start as usize).next_multiple_of(page);
    let end = (start as usize + bytes) & !(page - 1);
    if end > first {
        // SAFETY: the range lies inside the vector's own allocation, and MADV_HUGEPAGE is advice:
        // it changes how the kernel backs the pages, never their contents or their validity. A
        // refusal (a kernel without THP) leaves the buffer as it was, so the result is ignored.
        #[allow(unsafe_code)]
        unsafe {
            libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge(_: *const u8, _: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

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
