//! A counting global allocator for the zero-allocation tests: while `ENABLED` is set on a
//! thread, every allocation that thread makes (alloc, alloc_zeroed, realloc) adds one to its
//! `COUNT`; frees are not counted. A test crate includes this file once (directly, or through
//! `counted_driver.rs`), since a crate has one global allocator.
#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    /// Whether this thread's allocations are being counted.
    pub static ENABLED: Cell<bool> = const { Cell::new(false) };
    /// This thread's allocations counted so far.
    pub static COUNT: Cell<u64> = const { Cell::new(0) };
}

fn note_alloc() {
    if ENABLED.try_with(Cell::get).unwrap_or(false) {
        let _ = COUNT.try_with(|c| c.set(c.get() + 1));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_alloc();
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note_alloc();
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_alloc();
        System.realloc(ptr, layout, new_size)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs `f` with counting on (adding to `COUNT`, which it does not reset).
pub fn counted<T>(f: impl FnOnce() -> T) -> T {
    ENABLED.with(|e| e.set(true));
    let out = f();
    ENABLED.with(|e| e.set(false));
    out
}

/// Runs `f` and returns how many allocations this thread made meanwhile (resets `COUNT`).
pub fn allocations_in(f: impl FnOnce()) -> u64 {
    COUNT.with(|c| c.set(0));
    counted(f);
    COUNT.with(Cell::get)
}

/// Sets whether this thread's allocations are counted.
pub fn set_counting(on: bool) {
    ENABLED.with(|e| e.set(on));
}

/// Zeroes this thread's count.
pub fn reset_count() {
    COUNT.with(|c| c.set(0));
}

/// This thread's count.
pub fn count() -> u64 {
    COUNT.with(Cell::get)
}

/// Checks that the counter sees an allocation (so that a count of 0 means something).
pub fn counter_works() {
    let before = count();
    let b = counted(|| std::hint::black_box(Box::new(7u64)));
    drop(b);
    assert!(count() > before, "the counting allocator saw no allocation");
}
