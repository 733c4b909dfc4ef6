//! The few parallel patterns the builders use, on rayon's threads with the feature `parallel`,
//! and in order on the calling thread without it.
//!
//! rt-core re-exports this crate as `rt_core::par`. Every structure crate has a default-on
//! `parallel` feature that turns on this crate's. A program that leaves it off (`default-features = false`) compiles no thread pool (rayon and
//! the five crates under it) and builds single-threaded; targets without threads, such as
//! `wasm32-unknown-unknown`, build either way.
//!
//! Each function returns the same values in the same order whether it runs in parallel or not,
//! so a structure built with or without the feature, on any number of threads, is the same
//! structure: the builders' determinism tests compare them byte for byte.

#![warn(missing_docs)]

use std::ops::Range;

/// How many threads the parallel functions below may use: rayon's pool size, or 1 without the
/// `parallel` feature. Builders compare it with 1 to skip the cost of splitting work.
#[inline]
pub fn threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}

/// Runs `a` and `b`, possibly at the same time, and returns both results.
#[inline]
pub fn join<RA: Send, RB: Send>(
    a: impl FnOnce() -> RA + Send,
    b: impl FnOnce() -> RB + Send,
) -> (RA, RB) {
    #[cfg(feature = "parallel")]
    {
        rayon::join(a, b)
    }
    #[cfg(not(feature = "parallel"))]
    {
        (a(), b())
    }
}

/// `f(i)` for every `i` in `range`, in order.
pub fn map_range<R: Send>(range: Range<usize>, f: impl Fn(usize) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        range.into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        range.map(f).collect()
    }
}

/// `f(item)` for every item, in order.
pub fn map_vec<T: Send, R: Send>(items: Vec<T>, f: impl Fn(T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.into_iter().map(f).collect()
    }
}

/// `f(chunk)` for each chunk of `size` items (the last may be shorter), in order.
pub fn map_chunks<T: Sync, R: Send>(
    items: &[T],
    size: usize,
    f: impl Fn(&[T]) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_chunks(size).map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.chunks(size).map(f).collect()
    }
}

/// `f(chunk)` for each mutable chunk of `size` items (the last may be shorter), in order.
pub fn map_chunks_mut<T: Send, R: Send>(
    items: &mut [T],
    size: usize,
    f: impl Fn(&mut [T]) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_chunks_mut(size).map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.chunks_mut(size).map(f).collect()
    }
}

/// `f(k, chunk)` for the `k`-th mutable chunk of `size` items (the last may be shorter), in
/// order.
pub fn map_chunks_mut_indexed<T: Send, R: Send>(
    items: &mut [T],
    size: usize,
    f: impl Fn(usize, &mut [T]) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items
            .par_chunks_mut(size)
            .enumerate()
            .map(|(k, c)| f(k, c))
            .collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items
            .chunks_mut(size)
            .enumerate()
            .map(|(k, c)| f(k, c))
            .collect()
    }
}

/// `f(input_chunk, output_chunk)` for matching chunks of `size` items of `input` and `out` (as
/// many items as both have; the last chunk may be shorter). In order on the calling thread when
/// rayon's current pool has one thread.
pub fn zip_chunks_mut<T: Sync, U: Send>(
    input: &[T],
    out: &mut [U],
    size: usize,
    f: impl Fn(&[T], &mut [U]) + Sync + Send,
) {
    let n = input.len().min(out.len());
    let (input, out) = (&input[..n], &mut out[..n]);
    // A pool of one thread would only move the work to its thread: the calling thread does it.
    #[cfg(feature = "parallel")]
    if threads() > 1 {
        use rayon::prelude::*;
        input
            .par_chunks(size)
            .zip(out.par_chunks_mut(size))
            .for_each(|(i, o)| f(i, o));
        return;
    }
    input
        .chunks(size)
        .zip(out.chunks_mut(size))
        .for_each(|(i, o)| f(i, o));
}

/// Folds chunks of `size` items into accumulators made by `init` and combines those with
/// `reduce` (`init()` for no items). The grouping of chunks into accumulators is not fixed, so
/// `fold` and `reduce` must give the same answer for any grouping (sums, minima and maxima).
pub fn fold_chunks<T: Sync, A: Send>(
    items: &[T],
    size: usize,
    init: impl Fn() -> A + Sync + Send,
    fold: impl Fn(A, &[T]) -> A + Sync + Send,
    reduce: impl Fn(A, A) -> A + Sync + Send,
) -> A {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        let folded = items.par_chunks(size).fold(&init, fold);
        folded.reduce_with(reduce).unwrap_or_else(init)
    }
    #[cfg(not(feature = "parallel"))]
    {
        let _ = reduce;
        items.chunks(size).fold(init(), fold)
    }
}

/// Calls `f` on every item, in parallel pieces of at least `min_len` items (in order on the
/// calling thread when rayon's current pool has one thread).
pub fn for_each_mut<T: Send>(items: &mut [T], min_len: usize, f: impl Fn(&mut T) + Sync + Send) {
    // A pool of one thread would only move the work to its thread: the calling thread does it.
    #[cfg(feature = "parallel")]
    if threads() > 1 {
        use rayon::prelude::*;
        items.par_iter_mut().with_min_len(min_len).for_each(f);
        return;
    }
    let _ = min_len;
    items.iter_mut().for_each(f);
}

/// Sorts `items` (unstable: equal items may change places, which for a total order on distinct
/// keys, as the builders use, changes nothing).
pub fn sort_unstable<T: Ord + Send>(items: &mut [T]) {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_sort_unstable();
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.sort_unstable();
    }
}

/// Appends `f(i)` for every `i` in `range` to `out`, in order, each written in its place.
pub fn extend_range<T: Send>(
    out: &mut Vec<T>,
    range: Range<usize>,
    f: impl Fn(usize) -> T + Sync + Send,
) {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        out.par_extend(range.into_par_iter().map(f));
    }
    #[cfg(not(feature = "parallel"))]
    {
        out.extend(range.map(f));
    }
}

/// Output storage that a batch splits among threads: a slice, one slot per item, or a tuple of
/// up to six slices of the same length (one array per field of an answer, as numpy callers
/// want them). Each piece of a split owns its slots, so threads write them without locks.
pub trait Slots: Send + Sized {
    /// How many items the storage holds slots for (the shortest slice's length for a tuple).
    fn slots(&self) -> usize;
    /// The slots of items `..mid` and of items `mid..`.
    fn split_at(self, mid: usize) -> (Self, Self);
}

impl<T: Send> Slots for &mut [T] {
    #[inline]
    fn slots(&self) -> usize {
        self.len()
    }

    #[inline]
    fn split_at(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
}

macro_rules! slots_tuple {
    ($($s:ident $i:tt),+) => {
        impl<$($s: Slots),+> Slots for ($($s,)+) {
            #[inline]
            fn slots(&self) -> usize {
                [$(self.$i.slots()),+].into_iter().min().unwrap_or(0)
            }

            #[inline]
            #[allow(non_snake_case)]
            fn split_at(self, mid: usize) -> (Self, Self) {
                $(let $s = self.$i.split_at(mid);)+
                (($($s.0,)+), ($($s.1,)+))
            }
        }
    };
}
slots_tuple!(A 0, B 1);
slots_tuple!(A 0, B 1, C 2);
slots_tuple!(A 0, B 1, C 2, D 3);
slots_tuple!(A 0, B 1, C 2, D 3, E 4);
slots_tuple!(A 0, B 1, C 2, D 3, E 4, F 5);

/// `f(range, slots)` for consecutive ranges of at most `size` items covering `0..n`, where
/// `n` is the number of items `out` holds slots for, each call given the slots of its range.
/// The ranges start at multiples of `size`. On rayon's threads by halving (with the feature
/// `parallel` and a pool of more than one thread), else in order on the calling thread.
pub fn split_slots<S: Slots>(out: S, size: usize, f: impl Fn(Range<usize>, S) + Sync + Send) {
    let size = size.max(1);
    let n = out.slots();
    if n == 0 {
        return;
    }
    #[cfg(feature = "parallel")]
    if threads() > 1 {
        split_join(0, n, out, size, &f);
        return;
    }
    let mut rest = out;
    let mut start = 0;
    while start < n {
        let end = (start + size).min(n);
        let (here, after) = rest.split_at(end - start);
        f(start..end, here);
        (start, rest) = (end, after);
    }
}

#[cfg(feature = "parallel")]
fn split_join<S: Slots>(
    start: usize,
    end: usize,
    out: S,
    size: usize,
    f: &(impl Fn(Range<usize>, S) + Sync + Send),
) {
    let chunks = (end - start).div_ceil(size);
    if chunks <= 1 {
        let (out, _) = out.split_at(end - start);
        return f(start..end, out);
    }
    let mid = chunks / 2 * size;
    let (a, b) = out.split_at(mid);
    rayon::join(
        || split_join(start, start + mid, a, size, f),
        || split_join(start + mid, end, b, size, f),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every function gives the sequential answer, whichever way this crate was built.
    #[test]
    fn answers_as_in_order() {
        let items: Vec<u64> = (0..10_000).map(|i| (i * 7919) % 10_007).collect();
        assert_eq!(
            map_range(3..9, |i| i * i),
            (3..9).map(|i| i * i).collect::<Vec<_>>()
        );
        assert_eq!(map_vec(vec![1, 2, 3], |x| x + 1), vec![2, 3, 4]);
        let sums = map_chunks(&items, 1000, |c| c.iter().sum::<u64>());
        assert_eq!(sums.len(), 10);
        assert_eq!(sums.iter().sum::<u64>(), items.iter().sum::<u64>());
        let mut copy = items.clone();
        let lens = map_chunks_mut(&mut copy, 3000, |c| {
            c.reverse();
            c.len()
        });
        assert_eq!(lens, vec![3000, 3000, 3000, 1000]);
        assert_eq!(copy[0], items[2999]);
        let total = fold_chunks(
            &items,
            64,
            || 0u64,
            |a, c| a + c.iter().sum::<u64>(),
            |a, b| a + b,
        );
        assert_eq!(total, items.iter().sum());
        assert_eq!(
            fold_chunks(&[] as &[u64], 64, || 5, |a, _| a, |a, b| a + b),
            5
        );
        let mut doubled = items.clone();
        for_each_mut(&mut doubled, 16, |x| *x *= 2);
        assert!(doubled.iter().zip(&items).all(|(d, i)| *d == 2 * i));
        let mut sorted = items.clone();
        sort_unstable(&mut sorted);
        assert!(sorted.windows(2).all(|w| w[0] <= w[1]));
        let mut out = vec![7];
        extend_range(&mut out, 0..4, |i| i * 10);
        assert_eq!(out, vec![7, 0, 10, 20, 30]);
        assert_eq!(join(|| 1, || "two"), (1, "two"));
        assert!(threads() >= 1);
    }

    /// `split_slots` hands each range its own slots, for a slice and a tuple, whatever the
    /// lengths, and gives a tuple the shortest slice's items.
    #[test]
    fn split_slots_cover_every_item_once() {
        for n in [0, 1, 63, 64, 65, 1000] {
            let mut a = vec![0usize; n];
            let mut b = vec![[0u8; 2]; n + 3];
            split_slots((&mut a[..], &mut b[..]), 64, |r, (a, b)| {
                assert!(r.start % 64 == 0 && r.len() <= 64 && r.len() == a.len());
                assert_eq!(a.len(), b.len());
                for (i, (a, b)) in r.zip(a.iter_mut().zip(b.iter_mut())) {
                    *a += i + 1;
                    b[1] += 1;
                }
            });
            assert_eq!(a, (1..=n).collect::<Vec<_>>());
            assert!(b[..n].iter().all(|b| b == &[0, 1]) && b[n..].iter().all(|b| b == &[0, 0]));
        }
    }
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
