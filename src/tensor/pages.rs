//! Large buffers on 2 MB pages where the kernel allows it.
//!
//! A 256³ `f32` volume is 16384 pages of 4 KB: the first pass over a fresh buffer takes
//! a page fault for each, and every pass a TLB miss for each. The buffers the engine
//! allocates itself (its scratch, [`super::Array::zeros`]) ask Linux for transparent huge
//! pages (`madvise(MADV_HUGEPAGE)`, the `madvise` mode of
//! `/sys/kernel/mm/transparent_hugepage/enabled`, as NumPy does for its large arrays)
//! before anything touches them. It is advice: contents and behaviour do not change, and
//! where the kernel declines (or off Linux) the buffer keeps small pages. Arrays that the
//! caller passes in keep their own pages. `tuning` turns the advice off
//! (`MRA_HUGE_PAGES=off`: every buffer on the pages the allocator gives, as a plain `Vec`'s).
//!
//! The gain is largest on the first transform of a process, whose scratch is faulted in
//! page by page otherwise; later runs gain a few percent (`examples/pyramid_timing`).

/// `len` default (zero) samples in a fresh allocation advised onto huge pages.
pub fn zeroed_vec<T: Clone + Default>(len: usize) -> Vec<T> {
    // `vec!` of zeros is calloc: a large block comes freshly mapped, its pages not yet
    // touched, so the advice applies before their first fault (a block reused from the
    // heap is already backed, and keeps the pages it has)
    let mut v = vec![T::default(); len];
    advise_huge_pages(&mut v);
    v
}

/// Whether the advice is on ([`crate::tuning::Tuning::huge_pages`], `MRA_HUGE_PAGES`).
fn huge_pages_on() -> bool {
    crate::tuning::get().huge_pages
}

/// Ask for huge pages over the whole 2 MB pages inside `v` (nothing for smaller buffers,
/// nothing with `MRA_HUGE_PAGES=off`).
pub fn advise_huge_pages<T>(v: &mut [T]) {
    #[cfg(target_os = "linux")]
    if huge_pages_on() {
        extern "C" {
            fn madvise(addr: *mut std::ffi::c_void, len: usize, advice: i32) -> i32;
        }
        const MADV_HUGEPAGE: i32 = 14;
        const HUGE: usize = 2 << 20;
        let start = v.as_mut_ptr() as usize;
        let end = start + std::mem::size_of_val(v);
        let (a, b) = (start.div_ceil(HUGE) * HUGE, end / HUGE * HUGE);
        if b > a {
            // SAFETY: [a, b) is whole pages inside `v`'s allocation, which `v` borrows
            // exclusively; the advice changes how those pages are backed, never what
            // they hold. Its result is ignored: declining leaves small pages.
            unsafe { madvise(a as *mut std::ffi::c_void, b - a, MADV_HUGEPAGE) };
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advised_buffers_keep_their_contents() {
        for len in [0usize, 1, 1000, 3 << 20] {
            let mut v: Vec<f32> = zeroed_vec(len);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 0.0));
            for (i, x) in v.iter_mut().enumerate() {
                *x = i as f32;
            }
            advise_huge_pages(&mut v);
            assert!(v.iter().enumerate().all(|(i, &x)| x == i as f32));
        }
    }
}
