//! A counting global allocator and a driver wrapper that counts the allocations made inside
//! the driver's own calls, for the drivers' zero-allocation tests (the simulator and the
//! virtual line allocate freely around them).
#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::Instant;

use vrpn::serial::{PortKind, PortOps, SerialDriver};
use vrpn::{Now, TimeVal};

struct Counting;

thread_local! {
    pub static ENABLED: Cell<bool> = const { Cell::new(false) };
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

pub fn counted<T>(f: impl FnOnce() -> T) -> T {
    ENABLED.with(|e| e.set(true));
    let out = f();
    ENABLED.with(|e| e.set(false));
    out
}

/// Counts allocations made inside the wrapped driver's calls only (the simulator and the
/// virtual line allocate freely).
pub struct Counted<D>(pub D);

impl<D: SerialDriver> SerialDriver for Counted<D> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn port_kind(&self) -> PortKind {
        self.0.port_kind()
    }
    fn opened(&mut self, now: Now, port: &mut PortOps) {
        self.0.opened(now, port)
    }
    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        counted(|| self.0.received(bytes, arrived, port))
    }
    fn poll(&mut self, now: Now, port: &mut PortOps) {
        counted(|| self.0.poll(now, port))
    }
    fn next_deadline(&self) -> Option<Instant> {
        counted(|| self.0.next_deadline())
    }
    fn closed(&mut self, now: Now) {
        self.0.closed(now)
    }
}

pub fn start() -> Now {
    Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    }
}
