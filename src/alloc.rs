//! The process's allocator: the system's, with every allocation of a huge page or more
//! advised to the kernel as one to back with transparent huge pages (Linux's
//! `madvise(MADV_HUGEPAGE)`, for the 2 MiB pages wholly inside it).
//!
//! Why: a frame's planes, texels and carried colours are buffers of megabytes, each freshly
//! mapped, faulted in 4 KiB at a time (a 1080p plane is some two thousand faults) and read
//! by gathers whose taps wander over dozens of rows, each row of texels on pages of its own.
//! Most Linux systems leave huge pages to be asked for (`enabled` set to `madvise`, Debian's
//! default). Measured on the two cores (BENCHMARKS.md, "Huge pages"): a whole `blur` of a
//! 1080p frame 5–25 % faster in wall time, the six-light-layer bench's ratio lower, for up
//! to 26 MiB more resident memory where a frame touched its buffers sparsely.
//!
//! Where huge pages are off (`never`), or on other systems, the advice changes nothing.
//! Nothing here allocates, blocks or panics: the advice is one system call, its result
//! ignored (advice, not a requirement).

use std::alloc::{GlobalAlloc, Layout, System};

/// The system's allocator, its large allocations advised to huge pages.
pub struct HugePages;

/// A transparent huge page on x86-64 and most aarch64 kernels.
pub const HUGE_PAGE: usize = 2 << 20;

/// The 2 MiB-aligned pages wholly inside `size` bytes at `p` (start, length), if any.
pub fn huge_span(p: usize, size: usize) -> Option<(usize, usize)> {
    let start = p.checked_add(HUGE_PAGE - 1)? & !(HUGE_PAGE - 1);
    let end = p.checked_add(size)? & !(HUGE_PAGE - 1);
    (end > start).then_some((start, end - start))
}

#[inline]
fn advise(p: *mut u8, size: usize) {
    if p.is_null() || size < HUGE_PAGE {
        return;
    }
    #[cfg(target_os = "linux")]
    if let Some((start, length)) = huge_span(p as usize, size) {
        use nix::sys::mman::{madvise, MmapAdvise};
        if let Some(start) = std::ptr::NonNull::new(start as *mut std::ffi::c_void) {
            // SAFETY: the span lies within the allocation just made (rounded inwards to
            // whole pages); MADV_HUGEPAGE changes how its pages are backed, never their
            // contents. A refusal (huge pages unsupported) leaves them as they were.
            let _ = unsafe { madvise(start, length, MmapAdvise::MADV_HUGEPAGE) };
        }
    }
}

// SAFETY: every call is the system allocator's own; `advise` only advises the kernel about
// memory the allocation owns.
unsafe impl GlobalAlloc for HugePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        advise(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc_zeroed(layout);
        advise(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        System.dealloc(p, layout)
    }

    unsafe fn realloc(&self, p: *mut u8, layout: Layout, size: usize) -> *mut u8 {
        let q = System.realloc(p, layout, size);
        if size > layout.size() {
            advise(q, size);
        }
        q
    }
}

#[global_allocator]
static GLOBAL: HugePages = HugePages;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_span_is_the_whole_huge_pages_inside_the_allocation() {
        let h = HUGE_PAGE;
        assert_eq!(huge_span(h, h), Some((h, h)));
        assert_eq!(huge_span(h + 16, 2 * h), Some((2 * h, h)));
        assert_eq!(huge_span(h + 16, 2 * h - 16), Some((2 * h, h)));
        assert_eq!(huge_span(h + 16, 2 * h - 17), None);
        assert_eq!(huge_span(16, 3 * h), Some((h, 2 * h)));
        assert_eq!(huge_span(usize::MAX - 10, h), None);
    }

    /// A large buffer's pages are advised: the kernel marks its mapping `hg` in
    /// /proc/self/smaps (whatever huge pages it then finds).
    #[cfg(target_os = "linux")]
    #[test]
    fn a_large_buffer_is_advised_to_huge_pages() {
        let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap_or_default();
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage").exists()
            || !smaps.contains("VmFlags:")
        {
            eprintln!("skipped: no transparent huge pages, or no mapping flags to read");
            return;
        }
        let flags_at = |address: usize| -> Option<String> {
            let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
            let mut inside = false;
            for line in smaps.lines() {
                if let Some((range, _)) = line.split_once(' ') {
                    if let Some((a, b)) = range.split_once('-') {
                        if let (Ok(a), Ok(b)) =
                            (usize::from_str_radix(a, 16), usize::from_str_radix(b, 16))
                        {
                            inside = a <= address && address < b;
                            continue;
                        }
                    }
                }
                if inside && line.starts_with("VmFlags:") {
                    return Some(line.to_string());
                }
            }
            None
        };
        let buffer = vec![1u8; 16 * HUGE_PAGE];
        let (start, _) = huge_span(buffer.as_ptr() as usize, buffer.len()).expect("a huge page");
        let flags = flags_at(start).expect("the buffer's mapping in /proc/self/smaps");
        assert!(
            flags.split_whitespace().any(|f| f == "hg"),
            "{flags}: not advised"
        );
    }
}
