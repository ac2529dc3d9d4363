//! Waiting for a connection without holding it: a descriptor and a deadline.
//!
//! A [`Connection`](crate::Connection) belongs to one thread, but waiting for it needs only
//! two plain values: the reactor's poll descriptor (readable while one of its sockets has
//! data, or its timer fired) and the connection's next deadline. A [`Waiter`] carries both,
//! is `Send` and `Copy`, and blocks in `poll(2)` on the descriptor: so a binding can wait
//! with its interpreter lock released, and an event loop (asyncio, a `select` loop, a game
//! engine) can put the same descriptor among its own sources.
//!
//! Polling the descriptor does not consume what it reports: the connection's next
//! `mainloop()` still finds every event.

use std::io;
use std::os::fd::RawFd;
use std::time::{Duration, Instant};

/// What to wait on for a connection: see the module documentation. Made by
/// [`Connection::prepare_wait`](crate::Connection::prepare_wait).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Waiter {
    /// The reactor's descriptor (`None` for connections without sockets: loopback, replay).
    pub(crate) fd: Option<RawFd>,
    /// The connection's next timed work (or the caller's earlier deadline).
    pub(crate) deadline: Option<Instant>,
    /// Work is waiting already (buffered input, queued deliveries, a deadline that passed):
    /// a wait returns at once.
    pub(crate) ready: bool,
}

/// How a [`Waiter::block`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wake {
    /// The descriptor turned readable (data, or the connection's timer), or work was waiting.
    Ready,
    /// The connection's deadline came (without a descriptor to tell).
    Deadline,
    /// The caller's time-out passed.
    TimedOut,
    /// A signal interrupted the wait (check for Ctrl-C, then wait again if you like).
    Interrupted,
}

impl Waiter {
    /// The descriptor to wait on for reading, if the connection has sockets.
    pub fn fd(&self) -> Option<RawFd> {
        self.fd
    }

    /// When the connection next has timed work (connection attempts, liveness pings), if
    /// ever. The descriptor turns readable then as well (through the reactor's timer).
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// True when work is waiting already: call `mainloop()` without waiting.
    pub fn ready(&self) -> bool {
        self.ready
    }

    /// How long a wait of at most `max` may last: zero when work is waiting, else until the
    /// deadline or `max`, whichever is first.
    pub fn timeout(&self, max: Duration) -> Duration {
        if self.ready {
            return Duration::ZERO;
        }
        match self.deadline {
            Some(d) => d.saturating_duration_since(Instant::now()).min(max),
            None => max,
        }
    }

    /// Blocks the calling thread (any thread: this holds no connection) until the descriptor
    /// is readable, the deadline comes, `max` passes or a signal arrives. Touches nothing of
    /// the connection: call its `mainloop()` next, on its own thread.
    pub fn block(&self, max: Duration) -> io::Result<Wake> {
        if self.ready {
            return Ok(Wake::Ready);
        }
        let timeout = self.timeout(max);
        let by_deadline = self.deadline.is_some_and(|d| d <= Instant::now() + timeout);
        let Some(fd) = self.fd else {
            if !timeout.is_zero() {
                std::thread::sleep(timeout);
            }
            return Ok(if by_deadline {
                Wake::Deadline
            } else {
                Wake::TimedOut
            });
        };
        match poll_readable(fd, timeout) {
            Ok(true) => Ok(Wake::Ready),
            Ok(false) if by_deadline => Ok(Wake::Deadline),
            Ok(false) => Ok(Wake::TimedOut),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(Wake::Interrupted),
            Err(e) => Err(e),
        }
    }
}

/// Blocks until any of `waiters` is ready, the earliest deadline comes, `max` passes or a
/// signal arrives: one `poll(2)` over every descriptor, for a program that reads devices on
/// several connections (several hosts) in one loop. Like [`Waiter::block`], it holds nothing
/// of the connections: call their `mainloop()` next.
pub fn block_any(waiters: &[Waiter], max: Duration) -> io::Result<Wake> {
    use nix::poll::{poll, PollFd, PollFlags};
    if waiters.iter().any(|w| w.ready) {
        return Ok(Wake::Ready);
    }
    let timeout = waiters.iter().fold(max, |t, w| w.timeout(t));
    let by_deadline = waiters
        .iter()
        .filter_map(|w| w.deadline)
        .any(|d| d <= Instant::now() + timeout);
    let mut fds: Vec<PollFd> = waiters
        .iter()
        .filter_map(|w| w.fd)
        .map(|fd| PollFd::new(fd, PollFlags::POLLIN))
        .collect();
    let ms = timeout.as_micros().div_ceil(1000).min(i32::MAX as u128) as i32;
    match poll(&mut fds, ms) {
        Ok(0) if by_deadline => Ok(Wake::Deadline),
        Ok(0) => Ok(Wake::TimedOut),
        Ok(_) => Ok(Wake::Ready),
        Err(nix::errno::Errno::EINTR) => Ok(Wake::Interrupted),
        Err(e) => Err(io::Error::from(e)),
    }
}

/// `poll(2)` for one descriptor's readability, with a timeout rounded up to whole
/// milliseconds (a timeout rounded down would wake before the deadline and spin). A
/// descriptor closed meanwhile makes `poll` report `POLLNVAL`, which counts as readable: the
/// caller's next `mainloop()` reports the real problem.
fn poll_readable(fd: RawFd, timeout: Duration) -> io::Result<bool> {
    use nix::poll::{poll, PollFd, PollFlags};
    let ms = timeout.as_micros().div_ceil(1000).min(i32::MAX as u128) as i32;
    let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
    match poll(&mut fds, ms) {
        Ok(0) => Ok(false),
        Ok(_) => Ok(true),
        Err(nix::errno::Errno::EINTR) => Err(io::Error::from(io::ErrorKind::Interrupted)),
        Err(e) => Err(io::Error::from(e)),
    }
}
