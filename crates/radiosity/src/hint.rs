//! Hints to the memory system: data that will be read soon.
//!
//! The ray caster asks for the children a node visit meets, and the relaxation solvers for the
//! receivers of a shot a few entries ahead: both read scattered memory that no cache holds
//! once the scene has 10⁵–10⁶ patches, and a hint lets several of those misses overlap.
#![allow(unsafe_code)]

/// Ask for the `lines` cache lines from `p` on to be brought to the cache closest to the
/// core. It never faults and changes nothing observable, whatever `p` is.
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T, lines: usize) {
    #[cfg(target_arch = "x86_64")]
    for k in 0..lines {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: `prefetch` only hints; it reads nothing architecturally and does not
        // fault on any address, and SSE is part of every x86-64 CPU.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((p as *const i8).wrapping_add(64 * k)) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, lines);
}

/// [`prefetch`] of the line holding `slice[i]`, if `i` is in bounds (nothing otherwise).
#[inline(always)]
pub(crate) fn prefetch_at<T>(slice: &[T], i: usize) {
    if i < slice.len() {
        prefetch(slice.as_ptr().wrapping_add(i), 1);
    }
}
