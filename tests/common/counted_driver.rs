//! The counting global allocator (`counting_alloc.rs`) and a driver wrapper that counts the allocations made inside
//! the driver's own calls, for the drivers' zero-allocation tests (the simulator and the
//! virtual line allocate freely around them).
#![allow(dead_code)]

use std::time::Instant;

use vrpn::serial::{PortKind, PortOps, SerialDriver};
use vrpn::{Now, TimeVal};

#[path = "counting_alloc.rs"]
mod counting_alloc;
#[allow(unused_imports)]
pub use counting_alloc::{counted, counter_works, COUNT, ENABLED};

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

/// A start time for a virtual line: now, with a fixed wall clock.
pub fn start() -> Now {
    Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    }
}
