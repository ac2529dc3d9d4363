//! Waiting for a connection without spinning, in this thread or outside it.
//!
//! [`Connection::wait`] blocks in the reactor's `epoll_wait`. Bindings and event loops that
//! cannot hand the connection to the waiting code (Python releasing its lock, asyncio, a
//! `select` loop, an engine's own poll) use the same two values through a
//! [`Waiter`]: the reactor's descriptor and the connection's next deadline.

use std::os::fd::RawFd;
use std::time::Instant;

use super::Connection;
use crate::net::Waiter;

impl Connection {
    /// The descriptor of the reactor this connection's sockets wait in (`None` for loopback
    /// and replay connections, which have no sockets). It is readable while data waits on one
    /// of the sockets, and, once this has been called, when the connection's next timed
    /// work is due: from then on every [`mainloop`](Self::mainloop) sets the reactor's timer
    /// for it (costing nothing while the deadline stays the same).
    ///
    /// Put it in any poll set (`select`, `poll`, `epoll`, asyncio's `add_reader`) and call
    /// `mainloop()` when it turns readable. Waiting on it consumes nothing. The descriptor
    /// belongs to the connection: do not close it or read from it.
    pub fn fd(&self) -> Option<RawFd> {
        let r = self.inner.reactor.as_ref()?;
        if !self.inner.watched.replace(true) {
            self.arm_wakeup();
        }
        Some(r.fd())
    }

    /// Prepares a wait: what a wait until data arrives, this connection's next deadline, or
    /// `deadline` (the caller's own, if any) needs, as a [`Waiter`] that holds nothing of the
    /// connection and may block on any thread (`Waiter::block`). The reactor's timer is set
    /// for the earlier deadline, so the descriptor alone wakes at it too. Call `mainloop()`
    /// after the wait.
    pub fn prepare_wait(&self, deadline: Option<Instant>) -> Waiter {
        let deadline = match (deadline, self.poll_timeout()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let buffered = {
            let core = self.inner.core.borrow();
            core.session.has_deliveries() || core.session.has_io() || core.session.input_buffered()
        };
        let due = deadline.is_some_and(|d| d <= Instant::now());
        let fd = self.inner.reactor.as_ref().map(|r| {
            if let (Some(d), false) = (deadline, due) {
                r.arm_wakeup(d);
            }
            r.fd()
        });
        Waiter {
            fd,
            deadline,
            ready: buffered || due || self.inner.any_deferred.get(),
        }
    }

    /// Sets the reactor's timer for this connection's next deadline (see [`Self::fd`]).
    pub(super) fn arm_wakeup(&self) {
        if let (Some(r), Some(d)) = (&self.inner.reactor, self.poll_timeout()) {
            r.arm_wakeup(d);
        }
    }
}
