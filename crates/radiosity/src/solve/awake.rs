//! Keeping the other workers of a rayon pool awake while a shooting method runs, and handing
//! one of them half of a shot's receivers without going through rayon's job queues.
//!
//! Shooting methods alternate 10⁵–10⁶ times between a short parallel step (a row's rays, a
//! shot's receivers) and a short serial one (choosing the next shooter). An idle rayon worker
//! offers its core to the operating system between two looks for work (a `sched_yield`) and
//! sleeps after a few tens of microseconds, and a thread waiting for a stolen job does the
//! same; against halves of a few microseconds that is a large part of each join
//! (docs/notes/solvers.md). While a [`KeepAwake`] lives, the other workers never sleep, and
//! the first of them polls a [`Slot`] between everything else it does: [`join`] posts the
//! second half there, does the first, and then either takes the second back (if the helper
//! has not started it) or spins until the helper is done. Each half is done by exactly one
//! thread and the results are returned in the same order, so nothing computed depends on who
//! did what.
//!
//! Besides the ray caster's and [`crate::hint`]'s, the library's only unsafe code: a posted
//! half borrows from the poster's stack, which the helper may use only while [`join`] waits
//! for it, as `rayon::join` does inside rayon.
#![allow(unsafe_code)]

use std::cell::{Cell, UnsafeCell};
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Nothing posted.
const EMPTY: u8 = 0;
/// A job is posted and nobody has started it.
const POSTED: u8 = 1;
/// The helper is running the posted job.
const TAKEN: u8 = 2;
/// The helper has finished the posted job; the poster has not yet seen it.
const DONE: u8 = 3;

/// A job that one thread posts and the helper may run. The job lives on the poster's stack,
/// which [`join`] does not leave while the helper may still use it.
struct Slot {
    state: AtomicU8,
    /// The posted job, its lifetime erased; written by the poster only while `state` is
    /// EMPTY, read by the helper only after it moved `state` from POSTED to TAKEN.
    job: UnsafeCell<Option<*mut (dyn FnMut() + Send + 'static)>>,
}

// SAFETY: `job` is written by the poster only while no other thread may read it (state EMPTY,
// before the release store of POSTED) and read by the helper only after it won the
// POSTED → TAKEN exchange (acquire); the job it points to is `Send`.
unsafe impl Sync for Slot {}
// SAFETY: as above; the raw pointer is only dereferenced under that protocol.
unsafe impl Send for Slot {}

thread_local! {
    /// The slot of the helper that a [`KeepAwake`] created on this thread keeps polling.
    static HELPER: UnsafeCell<Option<Arc<Slot>>> = const { UnsafeCell::new(None) };
    /// Whether this thread is inside a [`join`] that posted to its helper (whose slot is then
    /// busy until that join returns).
    static POSTING: Cell<bool> = const { Cell::new(false) };
    /// Whether this thread is a helper running a posted half.
    static HELPING: Cell<bool> = const { Cell::new(false) };
}

/// This thread's helper: none, busy with a half this thread posted, or free.
enum Helper {
    None,
    Busy,
    Free(Arc<Slot>),
}

fn helper() -> Helper {
    HELPER.with(|h| {
        // SAFETY: HELPER is written only by `KeepAwake::new` and `drop` on this same thread,
        // never while this reference is alive (it ends inside this closure).
        match unsafe { &*h.get() } {
            None => Helper::None,
            Some(_) if POSTING.with(Cell::get) => Helper::Busy,
            Some(slot) => Helper::Free(slot.clone()),
        }
    })
}

/// Whether a [`KeepAwake`] created on this thread keeps a helper for it (without taking a
/// reference to its slot, as [`helper`] does).
fn has_helper() -> bool {
    // SAFETY: see `helper`.
    HELPER.with(|h| unsafe { (*h.get()).is_some() })
}

/// Whether a [`join`] from this thread could run its halves at once: false on one thread, and
/// on a pool of two while this thread uses its helper or is that helper (both threads then
/// busy), where splitting work further only costs the split.
pub(crate) fn can_split() -> bool {
    match rayon::current_num_threads() {
        1 => false,
        2 if has_helper() => !POSTING.with(Cell::get),
        2 => !HELPING.with(Cell::get),
        _ => true,
    }
}

/// Run `a` here and `b` on the helper that a [`KeepAwake`] keeps for this thread, if there is
/// one and it starts `b` before `a` is done, else here after `a`; returns both results. Where
/// this thread has no helper, or is already using it on a pool of more than two threads,
/// through `rayon::join`; while it uses it on a pool of two, one after the other, the other
/// worker being busy with the outer half. A panic in either half is resumed here once both
/// are finished.
///
/// The slot hands a half over faster than `rayon::join`'s queues (docs/notes/solvers.md).
pub(crate) fn join<A, B, RA, RB>(a: A, b: B) -> (RA, RB)
where
    A: FnOnce() -> RA + Send,
    B: FnOnce() -> RB + Send,
    RA: Send,
    RB: Send,
{
    let slot = match helper() {
        Helper::Free(slot) => slot,
        // Two threads, both busy with a half each.
        Helper::Busy if rayon::current_num_threads() <= 2 => return (a(), b()),
        _ => return rayon::join(a, b),
    };
    let mut b = Some(b);
    let mut rb: Option<std::thread::Result<RB>> = None;
    let mut job = || {
        if let Some(b) = b.take() {
            rb = Some(catch_unwind(AssertUnwindSafe(b)));
        }
    };
    {
        let job: &mut (dyn FnMut() + Send + '_) = &mut job;
        // SAFETY: only the lifetime is erased (the same fat pointer). The helper dereferences
        // it only between taking it (POSTED → TAKEN) and storing DONE, and this function does
        // not return or unwind before it has either taken the job back (POSTED → EMPTY) or
        // seen DONE, so `job` and what it borrows outlive every use.
        let job: *mut (dyn FnMut() + Send + 'static) = unsafe { std::mem::transmute(job) };
        // SAFETY: the state is EMPTY (POSTING was false, and only this thread posts to this
        // slot), so the helper does not read `job` now.
        unsafe { *slot.job.get() = Some(job) };
    }
    POSTING.with(|p| p.set(true));
    slot.state.store(POSTED, Ordering::Release);
    let ra = catch_unwind(AssertUnwindSafe(a));
    if slot
        .state
        .compare_exchange(POSTED, EMPTY, Ordering::Acquire, Ordering::Relaxed)
        .is_ok()
    {
        // Not taken: do it here.
        job();
    } else {
        while slot.state.load(Ordering::Acquire) != DONE {
            std::hint::spin_loop();
        }
        slot.state.store(EMPTY, Ordering::Relaxed);
    }
    POSTING.with(|p| p.set(false));
    let ra = ra.unwrap_or_else(|p| resume_unwind(p));
    let rb = rb
        .expect("the posted job ran")
        .unwrap_or_else(|p| resume_unwind(p));
    (ra, rb)
}

/// Run the job posted to `slot`, if there is one and this thread wins it; true if it ran one.
fn run_posted(slot: &Slot) -> bool {
    if slot.state.load(Ordering::Relaxed) != POSTED
        || slot
            .state
            .compare_exchange(POSTED, TAKEN, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
    {
        return false;
    }
    // SAFETY: this thread won POSTED → TAKEN, so the poster wrote `job` before posting
    // (release, seen by the acquire above) and waits for DONE before the job goes away.
    let job = unsafe { (*slot.job.get()).expect("a posted job") };
    HELPING.with(|h| h.set(true));
    // SAFETY: as above; the job catches its own panics, so DONE is always stored.
    unsafe { (*job)() };
    HELPING.with(|h| h.set(false));
    slot.state.store(DONE, Ordering::Release);
    true
}

/// How long the helper polls its slot without finding work before it offers its core to the
/// operating system once: long against the time between two shots (docs/notes/solvers.md),
/// so that while shots follow one another the helper seldom sits in a system call when a half
/// is posted.
const SPIN: Duration = Duration::from_micros(40);

/// While it lives, the other workers of the caller's thread pool look for work without ever
/// going to sleep: each runs a job that takes whatever work the pool has (`rayon::yield_now`)
/// and, when there is none, yields the core to the operating system (which hands it straight
/// back unless another thread is waiting for it). The first of them also polls the slot that
/// [`join`] posts to from the thread that created the guard, between those looks, and offers
/// its core only after [`SPIN`] without work. Only on a worker of a pool of two or more threads
/// (the CLI runs its command on one); elsewhere nothing is started. The spinning shows as CPU
/// time.
///
/// Shooting methods alternate 10⁵–10⁶ times between a short parallel step and a short serial
/// one; an idle rayon worker sleeps after a few tens of microseconds, so that most parallel
/// steps would find the other worker asleep (docs/notes/solvers.md).
pub(crate) struct KeepAwake {
    stop: Arc<AtomicBool>,
    /// This thread's helper before this guard, put back when it is dropped.
    outer: Option<Option<Arc<Slot>>>,
}

impl KeepAwake {
    /// Start keeping the other workers of the current pool awake.
    pub(crate) fn new() -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let mut outer = None;
        if rayon::current_thread_index().is_some() && rayon::current_num_threads() > 1 {
            let slot = Arc::new(Slot {
                state: AtomicU8::new(EMPTY),
                job: UnsafeCell::new(None),
            });
            for k in 1..rayon::current_num_threads() {
                let stop = stop.clone();
                let slot = (k == 1).then(|| slot.clone());
                rayon::spawn(move || match slot {
                    Some(slot) => help(&slot, &stop),
                    None => {
                        while !stop.load(Ordering::Relaxed) {
                            if rayon::yield_now() != Some(rayon::Yield::Executed) {
                                // Give the core away if another thread wants it: with more
                                // workers than cores, a pure spin would starve the solve.
                                std::thread::yield_now();
                            }
                        }
                    }
                });
            }
            // SAFETY: see `helper`; no reference into HELPER is alive here.
            outer = Some(HELPER.with(|h| unsafe { (*h.get()).replace(slot) }));
        }
        Self { stop, outer }
    }
}

/// The helper's loop: the slot first, then the pool's work, then polling the slot, and the
/// core offered to the operating system after [`SPIN`] without work.
fn help(slot: &Slot, stop: &AtomicBool) {
    let mut idle_since = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        if run_posted(slot) || rayon::yield_now() == Some(rayon::Yield::Executed) {
            idle_since = Instant::now();
            continue;
        }
        for _ in 0..64 {
            if slot.state.load(Ordering::Relaxed) == POSTED {
                break;
            }
            std::hint::spin_loop();
        }
        if slot.state.load(Ordering::Relaxed) != POSTED && idle_since.elapsed() > SPIN {
            std::thread::yield_now();
            idle_since = Instant::now();
        }
    }
}

impl Drop for KeepAwake {
    fn drop(&mut self) {
        if let Some(outer) = self.outer.take() {
            // SAFETY: see `helper`.
            HELPER.with(|h| unsafe { *h.get() = outer });
        }
        self.stop.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Halves joined through the slot give the results (and panics) of running them in turn,
    /// whoever runs them; nested joins run where they are.
    #[test]
    fn joined_halves_are_run_once_each_and_panics_come_back() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| {
            let _awake = KeepAwake::new();
            let mut v = vec![0u64; 4096];
            for round in 0..2000u64 {
                let (lo, hi) = v.split_at_mut(1000 + (round as usize % 1000));
                let (a, b) = join(
                    || {
                        let (x, y) = lo.split_at_mut(lo.len() / 2);
                        let (p, q) = join(
                            || {
                                x.iter_mut()
                                    .map(|e| std::mem::replace(e, *e + 1))
                                    .sum::<u64>()
                            },
                            || {
                                y.iter_mut()
                                    .map(|e| std::mem::replace(e, *e + 1))
                                    .sum::<u64>()
                            },
                        );
                        p + q
                    },
                    || {
                        hi.iter_mut()
                            .map(|e| std::mem::replace(e, *e + 2))
                            .sum::<u64>()
                    },
                );
                let _ = (a, b);
            }
            // Every element was incremented once per round by exactly one of the halves.
            let split = |i: usize, round: usize| i < 1000 + round % 1000;
            for (i, &e) in v.iter().enumerate() {
                let want: u64 = (0..2000).map(|r| if split(i, r) { 1 } else { 2 }).sum();
                assert_eq!(e, want, "element {i}");
            }
            let caught = catch_unwind(AssertUnwindSafe(|| join(|| 1, || panic!("half b"))));
            assert!(caught.is_err());
            let caught = catch_unwind(AssertUnwindSafe(|| {
                join(|| -> u32 { panic!("half a") }, || 2)
            }));
            assert!(caught.is_err());
            // The slot is free again after a panic.
            assert_eq!(join(|| 3, || 4), (3, 4));
        });
    }
}
