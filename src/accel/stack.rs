//! The traversals' stack of nodes still to visit, and the closest-hit traversal's ordered push
//! of a node's hit children onto it.
//!
//! A fixed array and its length: room is checked once per node, not once per child, and the
//! insertion sort moves entries without a bounds check per step (an `ArrayVec` checked each
//! push and each slice index). The length stays a field beside the array: kept apart from
//! it (the array borrowed, so that the length could live in a register) the traversals took
//! more instructions, not fewer (docs/measurements.md, "The traversal stack without bounds
//! checks").

use std::mem::MaybeUninit;

use super::wide::{WIDTH, WideNode};

/// Up to `N` entries of `T`, last in first out.
///
/// Aligned to a cache line so that the traversal holding it realigns its frame: its AVX
/// values kept on the stack (the ray's broadcasts for the box and leaf tests, 32 bytes each)
/// are then read from 32-byte-aligned slots whatever the caller's stack pointer. Without it
/// the traversals' speed followed the caller's stack offset modulo 32: at the offsets where
/// those slots split across cache lines the any-hit traversal ran 4-5 % slower, and any
/// change to the callers could move a traversal from one offset to the other
/// (docs/measurements.md, "The traversals' frame aligned").
#[repr(align(64))]
pub(super) struct Stack<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    /// An empty stack (nothing written: a zeroed array would cost a short ray its set-up).
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// Stops the traversal unless `k` more entries fit. The traversals' bound makes this
    /// unreachable (at most seven entries per level of a tree of fewer than 64 levels, eight
    /// for a moment while a node's children are sorted; see `STACK` in the BVH), as the
    /// `ArrayVec` it replaces panicked on a push beyond its capacity.
    #[inline(always)]
    fn reserve(&self, k: usize) {
        if self.len + k > N {
            overflow();
        }
    }

    /// Pushes one entry.
    #[inline(always)]
    pub(super) fn push(&mut self, item: T) {
        self.reserve(1);
        // SAFETY: `reserve` made sure `len < N`.
        unsafe { self.items.get_unchecked_mut(self.len).write(item) };
        self.len += 1;
    }

    /// Pops the top entry.
    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push` or `push_far_to_near`.
        Some(unsafe { self.items.get_unchecked(self.len).assume_init() })
    }
}

impl<const N: usize> Stack<u32, N> {
    /// Pushes the children of `node` in the slots of `mask`'s set bits, lowest slot first
    /// (room checked once for the node).
    #[inline(always)]
    pub(super) fn push_children(&mut self, node: &WideNode, mask: u32) {
        self.reserve(WIDTH);
        let mut bits = mask & ((1 << WIDTH) - 1);
        while bits != 0 {
            let slot = bits.trailing_zeros() as usize & (WIDTH - 1);
            bits &= bits - 1;
            // SAFETY: `reserve` made room for eight entries, and at most eight bits are set.
            unsafe {
                self.items
                    .get_unchecked_mut(self.len)
                    .write(node.child[slot])
            };
            self.len += 1;
        }
    }
}

#[cold]
#[inline(never)]
fn overflow() -> ! {
    panic!("BVH traversal stack overflow: the tree is deeper than the build's bound")
}

/// Pushes the hit children of a node (mask and entry distances from the box test) onto
/// `stack` ordered far to near, the nearest on top (on equal distances, the higher slot
/// nearer). Each child is sorted into place among the node's entries already pushed (an
/// insertion sort on the stack itself: sorting into a separate array and copying it over cost
/// a second pass per node).
#[inline(always)]
pub(super) fn push_far_to_near<const N: usize>(
    node: &WideNode,
    mask: u32,
    near: &[f32; WIDTH],
    stack: &mut Stack<(u32, f32), N>,
) {
    stack.reserve(WIDTH);
    let base = stack.len;
    let items = stack.items.as_mut_ptr().cast::<(u32, f32)>();
    let mut top = base;
    // (Only the eight slots' bits: at most eight entries, the room reserved.)
    let mut bits = mask & ((1 << WIDTH) - 1);
    while bits != 0 {
        // (`& 7` tells the compiler the index is in range: an AND, not a compare and branch.)
        let slot = bits.trailing_zeros() as usize & (WIDTH - 1);
        bits &= bits - 1;
        let entry = (node.child[slot], near[slot]);
        let mut at = top;
        // SAFETY: `reserve` made room for eight entries from `base`, and `top - base` counts
        // the set bits handled so far, fewer than eight; the entries from `base` to `top`
        // were written above.
        unsafe {
            while at > base && (*items.add(at - 1)).1 < entry.1 {
                *items.add(at) = *items.add(at - 1);
                at -= 1;
            }
            *items.add(at) = entry;
        }
        top += 1;
    }
    stack.len = top;
}

#[cfg(test)]
mod tests {
    use super::{Stack, WIDTH, push_far_to_near};
    use crate::accel::wide::WideNode;
    use crate::sampling::Rng;

    /// The hit children go on top of what the stack held (left untouched), far to near, the
    /// higher slot nearer on equal distances (-0 and +0 equal): what a stable sort by distance
    /// gives.
    #[test]
    fn children_are_pushed_far_to_near() {
        let mut rng = Rng::new(3);
        let node = WideNode::with_children(std::array::from_fn(|k| 100 + k as u32));
        for _ in 0..5000 {
            let mask = (rng.f32() * 256.0) as u32 & 0xff;
            // Few distinct distances, so that ties are common (-0 and +0 among them).
            let near: [f32; WIDTH] = std::array::from_fn(|k| {
                let x = (rng.f32() * 4.0).floor();
                if x == 0.0 && k % 2 == 0 { -0.0 } else { x }
            });
            let below = (rng.f32() * 5.0) as usize;
            let mut stack = Stack::<(u32, f32), 64>::new();
            for k in 0..below {
                stack.push((k as u32, -1.0 - k as f32));
            }
            push_far_to_near(&node, mask, &near, &mut stack);
            let mut want: Vec<(u32, f32)> =
                (0..below).map(|k| (k as u32, -1.0 - k as f32)).collect();
            let mut hit: Vec<(u32, f32)> = (0..WIDTH)
                .filter(|&k| mask & (1 << k) != 0)
                .map(|k| (100 + k as u32, near[k]))
                .collect();
            // Bottom to top: farthest first; equal distances keep slot order (higher on top).
            // (-0 and +0 are equal distances.)
            hit.sort_by(|a, b| b.1.partial_cmp(&a.1).expect("no NaN"));
            want.extend(hit);
            let mut got = Vec::new();
            while let Some(e) = stack.pop() {
                got.push(e);
            }
            got.reverse();
            assert_eq!(got, want, "mask {mask:#x}, near {near:?}");
        }
    }

    /// Every stack is aligned to a cache line (what makes the traversals realign their
    /// frames; see `Stack`), whatever its entries and length.
    #[test]
    fn stacks_are_aligned_to_a_cache_line() {
        assert_eq!(std::mem::align_of::<Stack<u32, 1>>(), 64);
        assert_eq!(std::mem::align_of::<Stack<(u32, f32), 100>>(), 64);
        let stack = Stack::<u32, 3>::new();
        assert_eq!(std::ptr::addr_of!(stack) as usize % 64, 0);
    }

    /// A stack filled to its capacity gives its entries back last in first out, then nothing.
    #[test]
    fn a_full_stack_pops_in_reverse() {
        let mut stack = Stack::<u32, 16>::new();
        for k in 0..16 {
            stack.push(k);
        }
        for k in (0..16).rev() {
            assert_eq!(stack.pop(), Some(k));
        }
        assert_eq!(stack.pop(), None);
    }
}
