//! A fixed-capacity traversal stack whose slots start uninitialised.
//!
//! A traversal's stack is sized for the deepest tree (hundreds of bytes), and most rays use a
//! handful of its slots. An array of plain values must be initialised on every call, unless the
//! compiler proves that no slot is read before it is written (it does for some walks, not for
//! others); this one never is, so a ray pays for the entries it pushes and nothing else. It reads a slot only after writing it,
//! which is the one `unsafe` block here.
#![allow(unsafe_code)]

use std::fmt;
use std::mem::MaybeUninit;

/// A stack of at most `N` values of `T`, allocated in place, whose slots are not zeroed.
///
/// ```
/// use rt_core::Stack;
///
/// let mut stack = Stack::<(u32, f32), 8>::new();
/// stack.push((3, 0.5));
/// stack.push((7, 1.5));
/// assert_eq!(stack.pop(), Some((7, 1.5)));
/// if let Some(top) = stack.last_mut() {
///     top.1 = 2.5;
/// }
/// assert_eq!(stack.len(), 1);
/// assert_eq!(stack.pop(), Some((3, 2.5)));
/// assert_eq!(stack.pop(), None);
/// ```
pub struct Stack<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    /// An empty stack.
    #[inline(always)]
    pub fn new() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// Pushes `v`.
    ///
    /// # Panics
    /// When the stack already holds `N` values. Traversals size `N` from the depth bound their
    /// builder enforces, so that it never does.
    #[inline(always)]
    pub fn push(&mut self, v: T) {
        self.items[self.len] = MaybeUninit::new(v);
        self.len += 1;
    }

    /// Removes and returns the value pushed last, or `None` if the stack is empty.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: slots `0..len` (before the decrement) were each written by `push`, and `len`
        // only grows through `push`, so slot `len` holds a value written by it.
        Some(unsafe { self.items[self.len].assume_init() })
    }

    /// The value pushed last, to change in place, or `None` if the stack is empty.
    #[inline(always)]
    pub fn last_mut(&mut self) -> Option<&mut T> {
        let last = self.len.checked_sub(1)?;
        // SAFETY: slot `len - 1` was written by `push` (slots `0..len` all were, as in `pop`).
        Some(unsafe { self.items[last].assume_init_mut() })
    }

    /// How many values the stack holds.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the stack holds no value.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl<T: Copy, const N: usize> Default for Stack<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy, const N: usize> fmt::Debug for Stack<T, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Stack")
            .field("len", &self.len)
            .field("capacity", &N)
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_reverse_order_and_panics_when_full() {
        let mut s = Stack::<u32, 3>::new();
        assert!(s.is_empty());
        for v in [1, 2, 3] {
            s.push(v);
        }
        assert_eq!(s.len(), 3);
        let full = std::panic::catch_unwind(move || {
            let mut s = s;
            s.push(4);
        });
        assert!(
            full.is_err(),
            "a push beyond the capacity must panic, not write past the end"
        );
        let mut s = Stack::<u32, 3>::new();
        assert_eq!(s.last_mut(), None);
        s.push(5);
        s.push(6);
        *s.last_mut().unwrap() += 1;
        assert_eq!((s.pop(), s.pop(), s.pop()), (Some(7), Some(5), None));
    }
}
