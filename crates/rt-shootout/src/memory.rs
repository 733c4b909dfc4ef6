//! Heap accounting for `scale`: a global allocator that counts the bytes in use and their peak.
//!
//! A binary opts in with `#[global_allocator] static A: rt_shootout::memory::Counting =
//! rt_shootout::memory::Counting;` (`xtask` does). Every allocation then adds its size to a
//! counter and raises the peak; every free subtracts. [`reset_peak`] before a build and [`peak`]
//! after it give the most the build ever held at once, scratch and structure together, without
//! sampling and without asking the operating system. Two relaxed atomic operations per
//! allocation: a build that allocates per node pays a few percent; `compare` does not install it.
//!
//! This module holds rt-shootout's only `unsafe` code: forwarding to the system allocator.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static IN_USE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static INSTALLED: AtomicBool = AtomicBool::new(false);

/// The system allocator, counting what is in use and the peak.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counting;

impl Counting {
    fn grew(by: usize) {
        let now = IN_USE.fetch_add(by, Ordering::Relaxed) + by;
        PEAK.fetch_max(now, Ordering::Relaxed);
    }

    fn shrank(by: usize) {
        IN_USE.fetch_sub(by, Ordering::Relaxed);
    }
}

// SAFETY: every method forwards to `System` with the caller's arguments unchanged, so it upholds
// `GlobalAlloc`'s contract exactly as `System` does; the counting touches only atomics and never
// allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's `layout` meets `GlobalAlloc::alloc`'s requirements.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            INSTALLED.store(true, Ordering::Relaxed);
            Self::grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            INSTALLED.store(true, Ordering::Relaxed);
            Self::grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller passes a block this allocator (that is, `System`) returned, with
        // its layout.
        unsafe { System.dealloc(ptr, layout) };
        Self::shrank(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller passes a block `System` returned, its layout, and a valid new size.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                Self::grew(new_size - layout.size());
            } else {
                Self::shrank(layout.size() - new_size);
            }
        }
        p
    }
}

/// Heap bytes in use now, if [`Counting`] is the global allocator.
pub fn in_use() -> Option<usize> {
    INSTALLED
        .load(Ordering::Relaxed)
        .then(|| IN_USE.load(Ordering::Relaxed))
}

/// Starts a new peak at what is in use now, and returns that (if [`Counting`] is installed).
pub fn reset_peak() -> Option<usize> {
    let now = in_use()?;
    PEAK.store(now, Ordering::Relaxed);
    Some(now)
}

/// The most heap bytes in use at once since the last [`reset_peak`] (if [`Counting`] is
/// installed).
pub fn peak() -> Option<usize> {
    in_use().map(|_| PEAK.load(Ordering::Relaxed))
}
