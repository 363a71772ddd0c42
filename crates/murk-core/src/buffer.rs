//! Large working buffers backed by transparent huge pages where Linux gives them on request
//! (`madvise` mode, a common default): a buffer of tens of MB then faults in 2 MiB at a time instead
//! of 4 KiB.

/// `n` copies of `fill`, with huge pages requested before the allocation is first touched.
pub fn filled<T: Copy>(n: usize, fill: T) -> Vec<T> {
    let mut v = Vec::new();
    grow(&mut v, n, fill);
    v
}

/// `v.resize(n, fill)`, requesting huge pages for a new allocation before it is first touched.
pub fn grow<T: Copy>(v: &mut Vec<T>, n: usize, fill: T) {
    if n > v.capacity() {
        v.reserve_exact(n - v.len());
        advise_huge(
            v.as_mut_ptr() as usize,
            v.capacity() * std::mem::size_of::<T>(),
        );
    }
    v.resize(n, fill);
}

/// Types whose all-zero bit pattern is a valid value, zero itself: what [`zeroed`] may allocate.
///
/// # Safety
/// An implementor must be valid, and mean zero, with every bit clear.
pub unsafe trait Zeroable: Copy {}
// SAFETY: IEEE 0.0 is all bits clear; Complex<T> is #[repr(C)] {re, im}.
unsafe impl Zeroable for f32 {}
unsafe impl Zeroable for f64 {}
unsafe impl<T: Zeroable> Zeroable for num_complex::Complex<T> {}

/// `n` zeros, allocated zeroed: the operating system's fresh pages are zero already, so nothing is
/// written before the buffer is first used (and then by the threads that use it), and huge pages
/// are requested before that. `vec![Complex32::default(); n]` would write every zero on one thread
/// first.
pub fn zeroed<T: Zeroable>(n: usize) -> Vec<T> {
    let layout = std::alloc::Layout::array::<T>(n).expect("a buffer below isize::MAX bytes");
    if layout.size() == 0 {
        return Vec::new();
    }
    // SAFETY: the layout has a nonzero size.
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) };
    if ptr.is_null() {
        std::alloc::handle_alloc_error(layout);
    }
    advise_huge(ptr as usize, layout.size());
    // SAFETY: allocated by the global allocator with the layout of n T, all n initialised (zero
    // bits, a valid T by `Zeroable`).
    unsafe { Vec::from_raw_parts(ptr.cast(), n, n) }
}

/// Asks for huge pages over the 2 MiB-aligned part of `[addr, addr + len)`. Advice only: where the
/// kernel declines (THP off, another OS) nothing changes but speed.
fn advise_huge(addr: usize, len: usize) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = addr.next_multiple_of(HUGE);
        let end = (addr + len) / HUGE * HUGE;
        if end > start {
            // SAFETY: the range lies inside one live allocation of this process; MADV_HUGEPAGE
            // changes how its pages are backed, never their contents or validity.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (addr, len);
}

#[cfg(test)]
mod tests {
    #[test]
    fn filled_and_grown_buffers_hold_their_values() {
        let mut v = super::filled(3 << 20, 1.5f32);
        assert_eq!((v.len(), v[0], v[(3 << 20) - 1]), (3 << 20, 1.5, 1.5));
        v[7] = 2.0;
        super::grow(&mut v, 5 << 20, 4.0);
        assert_eq!((v[7], v[3 << 20], v.len()), (2.0, 4.0, 5 << 20));
        super::grow(&mut v, 10, 0.0);
        assert_eq!(v.len(), 10);
        let mut z: Vec<f64> = super::zeroed(3 << 20);
        assert!(z.len() == 3 << 20 && z.iter().all(|&v| v == 0.0));
        z.push(1.0);
        assert_eq!(z[3 << 20], 1.0);
        assert!(super::zeroed::<f32>(0).is_empty());
    }
}
