//! The mio shell: the one place that touches sockets and reads the clock.
//!
//! - [`Reactor`]: one poll (and a precise timer) that any number of connections and serial
//!   ports share.
//! - `shell`: the sockets of one connection; it carries out what the protocol layer
//!   ([`crate::proto`]) asks and feeds it what the sockets bring.
//! - `sys`: `recvmmsg`, the one system call mio lacks.
//!
//! Nothing here decides anything about the protocol.

pub mod reactor;
pub(crate) mod shell;
mod sys;

pub use reactor::{Reactor, Ready};

use std::cell::Cell;

use crate::time::{Now, TimeSource};

/// Reads both clocks: the only clock reading in the library (the programs read their own).
#[inline]
pub(crate) fn clock() -> Now {
    Now::read()
}

/// The clock of one loop pass: read the first time something in the pass needs the time, then
/// the same reading until the pass ends. A pass that only moves messages reads no clock.
#[derive(Debug, Default)]
pub(crate) struct PassClock {
    in_pass: Cell<bool>,
    now: Cell<Option<Now>>,
}

impl PassClock {
    /// Starts a pass (forgets the last reading). Returns false when a pass is already running
    /// (a nested call), which then shares the outer pass's time.
    pub(crate) fn begin(&self) -> bool {
        if self.in_pass.replace(true) {
            return false;
        }
        self.now.set(None);
        true
    }

    /// True inside a pass.
    pub(crate) fn in_pass(&self) -> bool {
        self.in_pass.get()
    }

    /// Ends the pass begun by the matching [`begin`](Self::begin) that returned true.
    pub(crate) fn end(&self) {
        self.in_pass.set(false);
        self.now.set(None);
    }
}

impl TimeSource for PassClock {
    fn now(&self) -> Now {
        if !self.in_pass.get() {
            return clock();
        }
        match self.now.get() {
            Some(n) => n,
            None => {
                let n = clock();
                self.now.set(Some(n));
                n
            }
        }
    }
}
