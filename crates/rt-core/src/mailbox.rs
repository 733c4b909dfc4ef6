//! Per-ray mailboxes: skip re-testing a primitive referenced from several cells.
//!
//! Spatial subdivisions (kd-trees, grids, octrees) reference a primitive from every cell it
//! overlaps, so a ray crossing several of those cells would test it several times. The classic
//! fix stores the last ray id on each primitive (Amanatides & Woo 1987), but that writes to shared
//! scene data on every test: it is not thread-safe and it pulls primitives' cache lines into a
//! modified state. [`Mailbox`] instead keeps the last `N` tested primitive indices in a small
//! ring on the tracing thread's stack. A primitive tested more than `N` tests ago may be tested
//! again, which costs time but never changes the answer: its result was already taken into
//! account, and the best hit so far only gets closer.

/// The last `N` primitive indices tested by one ray. Create one per ray.
///
/// ```
/// use rt_core::Mailbox;
/// let mut mb = Mailbox::<4>::new();
/// assert!(!mb.check_and_insert(7)); // first time: test it
/// assert!(mb.check_and_insert(7)); // again: skip it
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Mailbox<const N: usize> {
    ids: [u32; N],
    next: usize,
}

impl<const N: usize> Default for Mailbox<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Mailbox<N> {
    /// An empty mailbox.
    ///
    /// # Panics
    /// At compile time if `N` is zero.
    #[inline(always)]
    pub const fn new() -> Self {
        const { assert!(N > 0, "a mailbox needs at least one slot") };
        // `u32::MAX` is never a primitive index (structures index at most 2^32 - 1 primitives).
        Self {
            ids: [u32::MAX; N],
            next: 0,
        }
    }

    /// Returns true if `id` was among the last `N` inserted (the test can be skipped); otherwise
    /// records it, evicting the oldest, and returns false.
    #[inline(always)]
    pub fn check_and_insert(&mut self, id: u32) -> bool {
        // A plain scan over all slots, with no early exit, compiles to a few SIMD compares.
        if self.ids.iter().fold(false, |seen, &x| seen | (x == id)) {
            return true;
        }
        self.ids[self.next] = id;
        self.next = if self.next + 1 == N { 0 } else { self.next + 1 };
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_the_last_n_and_forgets_older() {
        let mut mb = Mailbox::<3>::new();
        for id in [1, 2, 3] {
            assert!(!mb.check_and_insert(id));
        }
        assert!(mb.check_and_insert(1) && mb.check_and_insert(2) && mb.check_and_insert(3));
        assert!(!mb.check_and_insert(4)); // evicts 1
        assert!(!mb.check_and_insert(1)); // evicts 2
        assert!(mb.check_and_insert(3));
        assert!(!mb.check_and_insert(2));
    }
}

/// Every primitive one query has been offered, for queries that reach many cells and want each
/// primitive once: box overlap over a kd-tree, grid or octree, where a box that covers many
/// cells meets most of its primitives' references many times, more than a [`Mailbox`] of a few
/// slots can remember.
///
/// One bit per primitive, in a buffer that each thread keeps between queries: a query marks the
/// bits it sets and clears only those when it ends, so its cost follows the primitives it meets,
/// not the scene's size.
///
/// ```
/// use rt_core::Visited;
/// let tested = Visited::with(1000, |seen| {
///     [5, 7, 5, 999, 7].into_iter().filter(|&id| seen.first_visit(id)).count()
/// });
/// assert_eq!(tested, 3);
/// ```
#[derive(Debug, Default)]
pub struct Visited {
    words: Vec<u64>,
    /// The words with a bit set, to clear at the end.
    touched: Vec<u32>,
}

thread_local! {
    /// The buffer of this thread's last query, kept for the next.
    static SPARE: std::cell::Cell<Visited> = std::cell::Cell::new(Visited::default());
}

impl Visited {
    /// Runs `f` with a set for primitive indices below `len`, empty at the start. The thread's
    /// buffer is taken for the call (a query nested inside `f` gets a buffer of its own) and put
    /// back cleared.
    pub fn with<R>(len: usize, f: impl FnOnce(&mut Visited) -> R) -> R {
        let mut set = SPARE.with(|s| s.take());
        let words = len.div_ceil(64);
        if set.words.len() < words {
            set.words.resize(words, 0);
        }
        let result = f(&mut set);
        for &w in &set.touched {
            set.words[w as usize] = 0;
        }
        set.touched.clear();
        SPARE.with(|s| s.set(set));
        result
    }

    /// Returns true the first time `id` is seen by this query, and marks it; false after.
    ///
    /// # Panics
    /// If `id` is not below the `len` given to [`Visited::with`] (rounded up to 64).
    #[inline]
    pub fn first_visit(&mut self, id: u32) -> bool {
        let (w, bit) = ((id / 64) as usize, 1u64 << (id % 64));
        let word = &mut self.words[w];
        if *word & bit != 0 {
            return false;
        }
        if *word == 0 {
            self.touched.push(w as u32);
        }
        *word |= bit;
        true
    }
}
