//! Large zeroed buffers that the kernel may back with huge pages.
//!
//! A 4096x4096 float map is 16,384 pages of 4 KiB, and on a virtual machine each first touch of a
//! page costs microseconds: a sixth of a whole integration's time went to page faults. Asking for
//! transparent huge pages (`MADV_HUGEPAGE`, honoured when the system's setting is `madvise` or
//! `always`) makes that 32 faults of 2 MiB. Elsewhere, or when the kernel declines, the buffer is
//! the same, only slower to touch.

/// Smallest buffer worth advising (a few huge pages).
const ADVISE_FROM_BYTES: usize = 8 << 20;

/// A zeroed buffer of `n` floats, advised towards huge pages. A large zeroed allocation comes
/// from fresh pages that the kernel zeroes at their first touch (the allocator does not write
/// them), so the advice comes before any page is touched and nothing is zeroed twice.
pub(crate) fn zeroed(n: usize) -> Vec<f32> {
    let mut v = vec![0f32; n];
    advise_huge_pages(v.as_mut_ptr().cast(), n * size_of::<f32>());
    v
}

#[cfg(target_os = "linux")]
fn advise_huge_pages(start: *mut u8, len: usize) {
    const HUGE: usize = 2 << 20;
    if len < ADVISE_FROM_BYTES {
        return;
    }
    let from = (start as usize).next_multiple_of(HUGE);
    let to = (start as usize + len) / HUGE * HUGE;
    if to > from {
        // SAFETY: [from, to) lies inside the allocation of `len` bytes at `start` that the caller
        // owns and has not yet touched; MADV_HUGEPAGE changes only how the kernel backs those
        // pages, never their contents or validity, and a refusal (an error return) is harmless.
        unsafe {
            libc::madvise(from as *mut libc::c_void, to - from, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_start: *mut u8, _len: usize) {}

#[cfg(test)]
mod tests {
    /// Small and large buffers are zeroed and of the size asked.
    #[test]
    fn buffers_are_zeroed() {
        for n in [0, 1, 1000, 5 << 20] {
            let v = super::zeroed(n);
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|&x| x == 0.0));
        }
    }
}
