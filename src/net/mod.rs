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

use crate::time::Now;

/// Reads both clocks: the only clock reading in the library (the programs read their own).
#[inline]
pub(crate) fn clock() -> Now {
    Now::read()
}
