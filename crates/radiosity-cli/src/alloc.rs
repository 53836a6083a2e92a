//! The program's global allocator: the system allocator, counting the bytes in use and their
//! peak, so that `radiosity experiment complexity` can report each case's peak heap memory
//! exactly (the library cannot own the allocator). Two relaxed atomic operations per
//! allocation; the engine's hot loops do not allocate.
//!
//! On Linux it also asks for transparent huge pages (`madvise(MADV_HUGEPAGE)`) for the whole
//! 2 MiB pages inside every allocation of at least `HUGE` bytes: the per-patch arrays, the
//! mesh and the BVH, which the solvers and the ray caster read at random. With 4 KiB pages
//! nearly every such read at 10⁵–10⁶ patches also misses the TLB, and with huge pages far
//! fewer do (docs/notes/workbench.md). Where the system's setting is `never`, the advice is
//! ignored; where it is `always`, it changes nothing. With the optional Embree binding
//! (`embree.rs`), this is the only unsafe code in the project: `GlobalAlloc` is an unsafe trait.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

static CURRENT: AtomicU64 = AtomicU64::new(0);
static PEAK: AtomicU64 = AtomicU64::new(0);

/// The counting allocator.
pub struct Counting;

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Allocations at least this large get the huge-page advice.
const HUGE: usize = 4 << 20;

/// Advise huge pages for the 2 MiB pages wholly inside `[p, p + size)`.
#[cfg(target_os = "linux")]
fn advise(p: *mut u8, size: usize) {
    const PAGE: usize = 2 << 20;
    if size < HUGE {
        return;
    }
    let start = (p as usize).next_multiple_of(PAGE);
    let end = (p as usize + size) / PAGE * PAGE;
    if end > start {
        // SAFETY: the range lies inside an allocation that was just made for the caller;
        // MADV_HUGEPAGE only changes how the kernel backs it, never its contents, and a
        // failure (no transparent huge pages) leaves it as it was.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_: *mut u8, _: usize) {}

fn grow(bytes: usize) {
    let now = CURRENT.fetch_add(bytes as u64, Relaxed) + bytes as u64;
    PEAK.fetch_max(now, Relaxed);
}

fn shrink(bytes: usize) {
    CURRENT.fetch_sub(bytes as u64, Relaxed);
}

// SAFETY: every method forwards to `System` with the caller's layout and pointer unchanged;
// the counters are only bookkeeping.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` is passed on unchanged.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grow(layout.size());
            advise(p, layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grow(layout.size());
            advise(p, layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator (hence from `System`) with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as for `dealloc`; `new_size` is the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                grow(new_size - layout.size());
                advise(p, new_size);
            } else {
                shrink(layout.size() - new_size);
            }
        }
        p
    }
}

/// The counters as the library's memory probe.
pub struct Probe;

impl radiosity_experiments::MemoryProbe for Probe {
    fn current(&self) -> u64 {
        CURRENT.load(Relaxed)
    }

    fn reset_peak(&self) {
        PEAK.store(CURRENT.load(Relaxed), Relaxed);
    }

    fn peak(&self) -> u64 {
        PEAK.load(Relaxed)
    }
}
