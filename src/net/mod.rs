//! The mio shell: the one place that touches sockets and reads the clock.
//!
//! - [`Reactor`]: one poll (and a precise timer) that any number of connections and serial
//!   ports share.
//! - `shell`: the sockets of one connection; it carries out what the protocol layer
//!   ([`crate::proto`]) asks and feeds it what the sockets bring.
//! - `sys`: `recvmmsg`, the one system call mio lacks.
//! - [`Waiter`]: a connection's descriptor and deadline, to wait without holding it.
//!
//! Nothing here decides anything about the protocol.

pub mod reactor;
pub(crate) mod shell;
mod sys;
pub mod wait;

pub use reactor::{Reactor, Ready};
pub use wait::{block_any, Waiter, Wake};

use std::cell::Cell;

use crate::time::{Now, TimeSource, TimeVal};

/// Reads both clocks: with [`wall_clock`], the only clock reading in the library (the programs
/// read their own).
#[inline]
pub(crate) fn clock() -> Now {
    Now::read()
}

/// Reads the wall clock alone (half the cost of [`clock`]: what a pass needs when only message
/// arrival times want the time).
#[inline]
pub(crate) fn wall_clock() -> TimeVal {
    TimeVal::now()
}

/// The clock of one loop pass: read the first time something in the pass needs the time, then
/// the same reading until the pass ends. A pass that only moves messages reads no clock; one
/// that only stamps arrivals reads the wall clock alone.
#[derive(Debug, Default)]
pub(crate) struct PassClock {
    in_pass: Cell<bool>,
    now: Cell<Option<Now>>,
    /// The pass's wall-clock reading (whether [`wall`](Self::wall) or
    /// [`now`](TimeSource::now) read it).
    wall: Cell<Option<TimeVal>>,
}

impl PassClock {
    /// Starts a pass (forgets the last reading). Returns false when a pass is already running
    /// (a nested call), which then shares the outer pass's time.
    pub(crate) fn begin(&self) -> bool {
        if self.in_pass.replace(true) {
            return false;
        }
        self.forget();
        true
    }

    /// True inside a pass.
    #[inline]
    pub(crate) fn in_pass(&self) -> bool {
        self.in_pass.get()
    }

    /// Ends the pass begun by the matching [`begin`](Self::begin) that returned true.
    pub(crate) fn end(&self) {
        self.in_pass.set(false);
        self.forget();
    }

    fn forget(&self) {
        self.now.set(None);
        self.wall.set(None);
    }

    /// The pass's wall-clock time (the clock outside a pass), the same reading as
    /// [`now`](TimeSource::now)'s `wall` within one pass, whichever was asked first.
    #[inline]
    pub(crate) fn wall(&self) -> TimeVal {
        match self.wall.get() {
            Some(w) if self.in_pass.get() => w,
            _ => self.read_wall(),
        }
    }

    #[inline(never)]
    fn read_wall(&self) -> TimeVal {
        let w = wall_clock();
        if self.in_pass.get() {
            self.wall.set(Some(w));
        }
        w
    }
}

impl TimeSource for PassClock {
    fn fresh(&self) -> Now {
        clock()
    }

    fn now(&self) -> Now {
        if !self.in_pass.get() {
            return clock();
        }
        match self.now.get() {
            Some(n) => n,
            None => {
                let mut n = clock();
                // A pass that already stamped arrivals keeps that wall-clock reading.
                match self.wall.get() {
                    Some(w) => n.wall = w,
                    None => self.wall.set(Some(n.wall)),
                }
                self.now.set(Some(n));
                n
            }
        }
    }
}
