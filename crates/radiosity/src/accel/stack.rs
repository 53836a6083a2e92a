//! The traversal stack: a small fixed array on the machine stack that spills to the heap
//! only for a pathologically deep tree.

use super::WIDTH;
use std::mem::MaybeUninit;

/// Entries of a traversal stack's fixed part (see [`Stack`]).
const STACK: usize = 56;

/// A traversal stack: a fixed array on the machine stack, small enough that setting it up
/// costs little per ray, whose bottom half moves to the heap when a deep tree would overflow
/// it; so nothing is allocated in the common case and no tree is too deep.
///
/// Aligned to a cache line: unaligned, its speed depended on where the thread's machine stack
/// happened to put it (docs/notes/accel.md).
///
/// The array is left uninitialised: zeroing its 448 bytes for every ray took fourteen stores,
/// a measurable cost on small trees (docs/notes/accel.md). Every slot below `sp` has been
/// written since the last [`Stack::clear`]: pushes write at `sp` before counting, a spill
/// moves written slots down, and a refill writes the slots it counts.
#[repr(align(64))]
pub(super) struct Stack<T: Copy> {
    top: [MaybeUninit<T>; STACK],
    sp: usize,
    spill: Vec<T>,
}

#[allow(unsafe_code)]
impl<T: Copy> Stack<T> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Stack {
            // SAFETY: an array of `MaybeUninit` needs no initialisation. (The array
            // expression `[MaybeUninit::uninit(); STACK]` was compiled to zeroing stores.)
            top: unsafe { MaybeUninit::<[MaybeUninit<T>; STACK]>::uninit().assume_init() },
            sp: 0,
            spill: Vec::new(),
        }
    }

    /// Empty it.
    #[inline(always)]
    pub(super) fn clear(&mut self) {
        self.sp = 0;
        self.spill.clear();
    }

    /// Make room for [`WIDTH`] pushes.
    #[inline(always)]
    pub(super) fn reserve(&mut self) {
        if self.sp + WIDTH > STACK {
            self.spill_half();
        }
    }

    #[cold]
    #[inline(never)]
    fn spill_half(&mut self) {
        // Called with `sp > STACK − WIDTH ≥ STACK / 2`: the bottom half is written.
        // SAFETY: slots below `sp` are initialised (the type's invariant).
        let bottom = self.top[..STACK / 2]
            .iter()
            .map(|v| unsafe { v.assume_init() });
        self.spill.extend(bottom);
        self.top.copy_within(STACK / 2..self.sp, 0);
        self.sp -= STACK / 2;
    }

    #[inline(always)]
    pub(super) fn push(&mut self, v: T) {
        self.top[self.sp] = MaybeUninit::new(v);
        self.sp += 1;
    }

    /// Write `v` on top, but count it pushed only if `keep`: a push without a branch.
    #[inline(always)]
    pub(super) fn push_if(&mut self, v: T, keep: bool) {
        self.top[self.sp] = MaybeUninit::new(v);
        self.sp += keep as usize;
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if self.sp == 0 && !self.refill() {
            return None;
        }
        self.sp -= 1;
        // SAFETY: `sp` was above this slot, so it is initialised (the type's invariant).
        Some(unsafe { self.top[self.sp].assume_init() })
    }

    /// Bring back the top of what was spilled; false if nothing was.
    #[cold]
    #[inline(never)]
    fn refill(&mut self) -> bool {
        let k = self.spill.len().min(STACK / 2);
        let from = self.spill.len() - k;
        for (slot, &v) in self.top[..k].iter_mut().zip(&self.spill[from..]) {
            *slot = MaybeUninit::new(v);
        }
        self.spill.truncate(from);
        self.sp = k;
        k > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stack_spills_and_refills_in_order() {
        // Pushes in node-sized batches far beyond the fixed part, interleaved with pops: the
        // stack gives back exactly what a Vec would.
        let mut stack = Stack::<u32>::new();
        let mut model = Vec::new();
        let mut next = 0u32;
        for round in 0..200 {
            stack.reserve();
            for _ in 0..WIDTH {
                stack.push(next);
                model.push(next);
                next += 1;
            }
            if round % 3 == 0 {
                assert_eq!(stack.pop(), model.pop());
            }
        }
        assert!(!stack.spill.is_empty());
        while let Some(v) = model.pop() {
            assert_eq!(stack.pop(), Some(v));
        }
        assert_eq!(stack.pop(), None);
    }
}
