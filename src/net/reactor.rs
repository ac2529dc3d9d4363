//! One poll for a whole process loop: sockets, serial ports and a precise timer wait in it.
//!
//! A [`Reactor`] is a cheap handle (clones share it). Every socket of every connection made
//! on it, and every serial port a server runs, registers here and gets a token; a poll records
//! readiness per token, and each owner takes its own readiness when it next runs. So a
//! `vrpn_server` sleeps in exactly one `epoll_wait` until a client's bytes, a device's bytes,
//! or the earliest deadline of anything in the process.
//!
//! Readiness is edge-triggered (mio registers sockets that way): an owner keeps reading until
//! `WouldBlock` (or a short read, which proves a stream empty) before it waits again.
//!
//! Sockets get their readiness as `ReadyBits` shared with the reactor: a poll sets the bits
//! and the owner clears them when a call proves them stale, so a loop pass asks a socket
//! "readable?" with one load, not a lookup in the reactor (that walk cost a borrow and a slot
//! lookup per socket per pass). Serial ports [`take`](Reactor::take) theirs, with the wake
//! time.

use std::cell::{Cell, RefCell};
use std::io;
use std::rc::Rc;
use std::time::{Duration, Instant};

use mio::event::Source;
use mio::{Events, Interest, Poll, Token};

use super::sys;
use crate::time::{Now, TimeSource};

/// Token of the timer that wakes the poll at a deadline.
const TIMER: Token = Token(0);

/// What a poll saw for one token since its owner last looked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ready {
    /// Data (or a connection, or an error) can be read.
    pub readable: bool,
    /// Room to write (or a connect completed).
    pub writable: bool,
    /// The peer closed its side, or the socket failed: read to the end.
    pub read_closed: bool,
    /// The socket reported an error.
    pub error: bool,
    /// When the poll woke with the first of these events: the arrival time of the first
    /// byte waiting on a serial port.
    pub woke: Option<Now>,
    /// Bytes waiting on a descriptor registered with [`Reactor::register_fd`] when the poll
    /// woke (asked just before the clock was read, so all of them had come by `woke`), where
    /// the descriptor can tell. A read that finds more than this finds bytes that came later.
    pub waiting: Option<usize>,
}

/// Readiness of one socket, shared by the reactor (which sets bits when a poll reports them)
/// and the socket's owner (which clears a bit when a call on the socket proves it stale).
#[derive(Clone, Debug, Default)]
pub(crate) struct ReadyBits(Rc<Cell<u8>>);

impl ReadyBits {
    /// Data (or a connection, or an error) can be read.
    pub(crate) const READABLE: u8 = 1;
    /// Room to write (or a connect completed).
    pub(crate) const WRITABLE: u8 = 2;
    /// The peer closed its side, or the socket failed: read to the end.
    pub(crate) const READ_CLOSED: u8 = 4;

    /// Bits starting as `bits`.
    pub(crate) fn new(bits: u8) -> ReadyBits {
        ReadyBits(Rc::new(Cell::new(bits)))
    }

    #[inline]
    pub(crate) fn readable(&self) -> bool {
        self.0.get() & Self::READABLE != 0
    }

    #[inline]
    pub(crate) fn writable(&self) -> bool {
        self.0.get() & Self::WRITABLE != 0
    }

    #[inline]
    pub(crate) fn read_closed(&self) -> bool {
        self.0.get() & Self::READ_CLOSED != 0
    }

    /// Clears `bits` (a call proved them stale).
    #[inline]
    pub(crate) fn clear(&self, bits: u8) {
        self.0.set(self.0.get() & !bits);
    }

    #[inline]
    fn set(&self, bits: u8) {
        self.0.set(self.0.get() | bits);
    }
}

#[derive(Default)]
struct Slot {
    used: bool,
    /// The owner wants the wake time of readable events (serial ports: first-byte time).
    timed: bool,
    /// The descriptor of a timed registration (asked how many bytes wait at a wake).
    fd: Option<std::os::fd::RawFd>,
    /// Readiness here is not "activity" (listeners: new connections and connection requests
    /// do not need the busy-poll latency that data does, and a flood of them must not keep a
    /// server spinning).
    quiet: bool,
    /// Where a poll puts readiness: the owner's shared bits, or `ready` for [`Reactor::take`].
    shared: Option<ReadyBits>,
    ready: Ready,
}

struct Inner {
    poll: Poll,
    events: Events,
    timer: Option<Timer>,
    /// The deadline the timer is set for, until it fires (see [`Reactor::arm_wakeup`]).
    armed: Option<Instant>,
    slots: Vec<Slot>,
    free: Vec<usize>,
    /// Registrations that want wake times (when none, a poll never reads the clock).
    timed: usize,
}

/// A shared poll: see the module documentation.
#[derive(Clone)]
pub struct Reactor {
    inner: Rc<Shared>,
}

struct Shared {
    state: RefCell<Inner>,
    /// Data arrived since the last [`Reactor::take_activity`] (outside the `RefCell`: every
    /// read that brings data notes it).
    activity: Cell<bool>,
    /// Polls made, for the tests that count them.
    #[cfg(test)]
    polls: Cell<u64>,
}

impl std::fmt::Debug for Reactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let inner = self.inner.state.borrow();
        f.debug_struct("Reactor")
            .field("registered", &inner.slots.iter().filter(|s| s.used).count())
            .finish()
    }
}

impl Reactor {
    /// A new poll instance.
    pub fn new() -> io::Result<Reactor> {
        let poll = Poll::new()?;
        let mut slots = Vec::with_capacity(64);
        slots.push(Slot {
            used: true,
            timed: false,
            fd: None,
            quiet: true,
            shared: None,
            ready: Ready::default(),
        });
        Ok(Reactor {
            inner: Rc::new(Shared {
                state: RefCell::new(Inner {
                    poll,
                    events: Events::with_capacity(256),
                    timer: None,
                    armed: None,
                    slots,
                    free: Vec::new(),
                    timed: 0,
                }),
                activity: Cell::new(false),
                #[cfg(test)]
                polls: Cell::new(0),
            }),
        })
    }

    /// True when both handles are the same reactor.
    pub fn same_as(&self, other: &Reactor) -> bool {
        Rc::ptr_eq(&self.inner, &other.inner)
    }

    fn alloc(inner: &mut Inner) -> Token {
        let i = match inner.free.pop() {
            Some(i) => i,
            None => {
                inner.slots.push(Slot::default());
                inner.slots.len() - 1
            }
        };
        inner.slots[i] = Slot {
            used: true,
            timed: false,
            fd: None,
            quiet: false,
            shared: None,
            ready: Ready::default(),
        };
        Token(i)
    }

    /// Registers a socket (or any mio source) and returns its token.
    pub fn register(&self, source: &mut impl Source, interest: Interest) -> io::Result<Token> {
        let mut inner = self.inner.state.borrow_mut();
        let token = Self::alloc(&mut inner);
        if let Err(e) = inner.poll.registry().register(source, token, interest) {
            inner.slots[token.0].used = false;
            inner.free.push(token.0);
            return Err(e);
        }
        Ok(token)
    }

    /// Registers a listening socket: its readiness does not count as activity (see
    /// [`take_activity`](Self::take_activity)).
    pub fn register_quiet(
        &self,
        source: &mut impl Source,
        interest: Interest,
    ) -> io::Result<Token> {
        let token = self.register(source, interest)?;
        self.inner.state.borrow_mut().slots[token.0].quiet = true;
        Ok(token)
    }

    /// Registers a socket whose readiness a poll puts straight into `bits` (shared with its
    /// owner, see [`ReadyBits`]); `quiet` as for [`register_quiet`](Self::register_quiet).
    pub(crate) fn register_shared(
        &self,
        source: &mut impl Source,
        interest: Interest,
        quiet: bool,
        bits: &ReadyBits,
    ) -> io::Result<Token> {
        let token = self.register(source, interest)?;
        let mut inner = self.inner.state.borrow_mut();
        let slot = &mut inner.slots[token.0];
        slot.quiet = quiet;
        slot.shared = Some(bits.clone());
        Ok(token)
    }

    /// Registers a raw file descriptor (a serial port, an input device) whose readiness
    /// carries the time the poll woke for it ([`Ready::woke`]).
    pub fn register_fd(&self, fd: std::os::fd::RawFd, interest: Interest) -> io::Result<Token> {
        let token = self.register(&mut mio::unix::SourceFd(&fd), interest)?;
        let mut inner = self.inner.state.borrow_mut();
        inner.slots[token.0].timed = true;
        inner.slots[token.0].fd = Some(fd);
        inner.timed += 1;
        Ok(token)
    }

    /// Forgets a registration; the token may be reused.
    pub fn deregister(&self, source: &mut impl Source, token: Token) {
        let mut inner = self.inner.state.borrow_mut();
        let _ = inner.poll.registry().deregister(source);
        if let Some(slot) = inner.slots.get_mut(token.0).filter(|s| s.used) {
            let timed = std::mem::take(&mut slot.timed);
            slot.used = false;
            slot.shared = None;
            slot.ready = Ready::default();
            inner.free.push(token.0);
            inner.timed -= usize::from(timed);
        }
    }

    /// [`deregister`](Self::deregister) for a raw file descriptor.
    pub fn deregister_fd(&self, fd: std::os::fd::RawFd, token: Token) {
        self.deregister(&mut mio::unix::SourceFd(&fd), token);
    }

    /// Takes (and clears) what the polls saw for `token` since the last call.
    pub fn take(&self, token: Token) -> Ready {
        let mut inner = self.inner.state.borrow_mut();
        match inner.slots.get_mut(token.0) {
            Some(s) if s.used => std::mem::take(&mut s.ready),
            _ => Ready::default(),
        }
    }

    /// Checks for readiness without waiting.
    pub fn poll_now(&self) -> io::Result<bool> {
        self.poll(Some(Duration::ZERO))
    }

    /// Waits until something is ready, `deadline` passes (woken precisely through a timer,
    /// not on the poll's millisecond grid) or `max` elapses. Returns whether data arrived on a
    /// socket.
    pub fn wait(&self, deadline: Option<Instant>, max: Duration) -> io::Result<bool> {
        let mut timeout = max;
        if let Some(d) = deadline {
            let until = d.saturating_duration_since(Instant::now());
            if until.is_zero() {
                return self.poll_now();
            }
            if until < max {
                let mut inner = self.inner.state.borrow_mut();
                if inner.timer.is_none() {
                    inner.timer = Timer::new(&inner.poll);
                }
                let armed = inner.timer.as_ref().is_some_and(|t| t.arm(until));
                inner.armed = armed.then_some(d);
                // Without a timer, fall back to the poll's millisecond timeout.
                timeout = if armed { max } else { until };
            }
        }
        self.poll(Some(timeout))
    }

    fn poll(&self, timeout: Option<Duration>) -> io::Result<bool> {
        #[cfg(test)]
        self.inner.polls.set(self.inner.polls.get() + 1);
        let mut inner = self.inner.state.borrow_mut();
        let inner = &mut *inner;
        match inner.poll.poll(&mut inner.events, timeout) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::Interrupted => return Ok(false),
            Err(e) => return Err(e),
        }
        if inner.events.is_empty() {
            return Ok(false);
        }
        // The time the poll woke, read only when a timed source (a serial port) is ready: the
        // arrival time of its first byte. Sockets do without it. Each such source that turns
        // readable is first asked how many bytes wait, so that every one of them had come by
        // the time read after.
        let mut timed_ready = false;
        if inner.timed > 0 {
            for ev in inner.events.iter().filter(|ev| ev.is_readable()) {
                let Some(slot) = inner.slots.get_mut(ev.token().0) else {
                    continue;
                };
                if slot.used && slot.timed {
                    timed_ready = true;
                    if !slot.ready.readable {
                        slot.ready.waiting = slot.fd.and_then(sys::bytes_waiting);
                    }
                }
            }
        }
        let woke = timed_ready.then(Now::read);
        let mut any = false;
        for ev in inner.events.iter() {
            if ev.token() == TIMER {
                if let Some(t) = &inner.timer {
                    t.clear();
                }
                inner.armed = None;
                continue;
            }
            let Some(slot) = inner.slots.get_mut(ev.token().0).filter(|s| s.used) else {
                continue;
            };
            if let Some(bits) = &slot.shared {
                let closed = ev.is_read_closed() || ev.is_error();
                any |= ev.is_readable() && !slot.quiet;
                bits.set(
                    if ev.is_readable() || closed {
                        ReadyBits::READABLE
                    } else {
                        0
                    } | if ev.is_writable() || ev.is_error() {
                        ReadyBits::WRITABLE
                    } else {
                        0
                    } | if closed { ReadyBits::READ_CLOSED } else { 0 },
                );
                continue;
            }
            // Only incoming data on sockets counts as activity: write-space events follow
            // every send, listeners are quiet, and serial bytes need no busy-polling (they
            // carry the wake time; a loop spinning through the busy window on a shared
            // machine gets preempted, and then stamps them late when it polls again).
            any |= ev.is_readable() && !slot.quiet && !slot.timed;
            let timed = slot.timed;
            let r = &mut slot.ready;
            if ev.is_readable() || ev.is_read_closed() || ev.is_error() {
                if !r.readable && timed {
                    r.woke = woke;
                }
                r.readable = true;
            }
            r.read_closed |= ev.is_read_closed() || ev.is_error();
            r.error |= ev.is_error();
            r.writable |= ev.is_writable() || ev.is_error();
        }
        if any {
            self.inner.activity.set(true);
        }
        Ok(any)
    }

    /// The poll's descriptor: readable while a registered socket has unread events or the
    /// reactor's timer fired. Waiting on it (with `poll(2)`, or in another event loop's poll
    /// set) consumes nothing: the next pass still sees every event.
    pub fn fd(&self) -> std::os::fd::RawFd {
        use std::os::fd::AsRawFd;
        self.inner.state.borrow().poll.as_raw_fd()
    }

    /// Makes the descriptor turn readable at `deadline` (through the reactor's timer), unless
    /// the timer is already set for an earlier moment that has not come (several connections
    /// may share a reactor: the earliest wins; a wake-up too early only costs a pass).
    /// Setting the same deadline again costs no system call. False when there is no timer.
    pub fn arm_wakeup(&self, deadline: Instant) -> bool {
        let mut inner = self.inner.state.borrow_mut();
        if let Some(a) = inner.armed {
            if a == deadline || a < deadline && a > Instant::now() {
                return true;
            }
        }
        if inner.timer.is_none() {
            inner.timer = Timer::new(&inner.poll);
        }
        let until = deadline.saturating_duration_since(Instant::now());
        let armed = inner.timer.as_ref().is_some_and(|t| t.arm(until));
        inner.armed = armed.then_some(deadline);
        armed
    }

    /// True if a serial port (a registration with wake times) is readable and its owner has
    /// not taken that yet: a loop must not block before its owner reads (edge-triggered,
    /// the poll will not report it again).
    pub fn timed_pending(&self) -> bool {
        let inner = self.inner.state.borrow();
        inner.timed > 0
            && inner
                .slots
                .iter()
                .any(|s| s.used && s.timed && s.ready.readable)
    }

    /// True once since the last call if data arrived on a socket (for a server's busy-poll
    /// window).
    pub fn take_activity(&self) -> bool {
        self.inner.activity.replace(false)
    }

    /// Polls made so far (`epoll_wait` calls).
    #[cfg(test)]
    pub(crate) fn polls(&self) -> u64 {
        self.inner.polls.get()
    }

    /// Notes that data arrived outside a poll (a read that found more than readiness said).
    #[inline]
    pub(crate) fn note_activity(&self) {
        self.inner.activity.set(true);
    }
}

/// One owner's deadline, watched by a timer in the reactor's poll set: a loop pass learns that
/// the deadline has passed from the poll it makes anyway, without reading the clock. (A
/// session with clock synchronisation always has a deadline; comparing it with the clock on
/// every pass cost two clock readings per pass.)
pub(crate) struct DeadlineTimer {
    timer: Timer,
    fd: std::os::fd::RawFd,
    token: Token,
    /// The timer's readiness: readable once it fired.
    fired: ReadyBits,
    reactor: Reactor,
    /// The deadline the timer is set for.
    armed: Option<Instant>,
    /// The armed deadline has passed.
    passed: bool,
}

impl DeadlineTimer {
    /// A timer in `reactor`'s poll set; `None` where the platform has none.
    pub(crate) fn new(reactor: &Reactor) -> Option<DeadlineTimer> {
        let timer = Timer::unregistered()?;
        let fd = timer.fd();
        let fired = ReadyBits::default();
        let token = reactor
            .register_shared(
                &mut mio::unix::SourceFd(&fd),
                Interest::READABLE,
                true,
                &fired,
            )
            .ok()?;
        Some(DeadlineTimer {
            timer,
            fd,
            token,
            fired,
            reactor: reactor.clone(),
            armed: None,
            passed: false,
        })
    }

    /// Whether `deadline` has passed. The clock is read only when the deadline differs from
    /// the one the timer is set for (to set it); otherwise the poll's readiness answers.
    #[inline]
    pub(crate) fn passed(&mut self, deadline: Instant, clock: &dyn TimeSource) -> bool {
        if self.armed != Some(deadline) {
            return self.rearm(deadline, clock);
        }
        if !self.passed && self.fired.readable() {
            self.fired.clear(ReadyBits::READABLE);
            self.timer.clear();
            self.passed = true;
        }
        self.passed
    }

    #[cold]
    fn rearm(&mut self, deadline: Instant, clock: &dyn TimeSource) -> bool {
        // A new deadline: readiness left from the old one means nothing.
        self.fired.clear(ReadyBits::READABLE);
        let now = clock.now().mono;
        self.passed = now >= deadline;
        self.armed = Some(deadline);
        if !self.passed && !self.timer.arm(deadline - now) {
            // No timer after all: compare with the clock every time.
            self.armed = None;
        }
        self.passed
    }
}

impl Drop for DeadlineTimer {
    fn drop(&mut self) {
        self.reactor.deregister_fd(self.fd, self.token);
    }
}

/// A one-shot monotonic timer in the poll set (Linux timerfd).
#[cfg(any(target_os = "linux", target_os = "android"))]
struct Timer(nix::sys::timerfd::TimerFd);

#[cfg(not(any(target_os = "linux", target_os = "android")))]
struct Timer;

#[cfg(any(target_os = "linux", target_os = "android"))]
impl Timer {
    /// A timer to register with [`Timer::source`].
    fn unregistered() -> Option<Timer> {
        use nix::sys::timerfd::{ClockId, TimerFd, TimerFlags};
        TimerFd::new(ClockId::CLOCK_MONOTONIC, TimerFlags::TFD_NONBLOCK)
            .ok()
            .map(Timer)
    }

    /// The timer's descriptor, to register it.
    fn fd(&self) -> std::os::fd::RawFd {
        use std::os::fd::AsRawFd;
        self.0.as_raw_fd()
    }

    fn new(poll: &Poll) -> Option<Timer> {
        use nix::sys::timerfd::{ClockId, TimerFd, TimerFlags};
        use std::os::fd::AsRawFd;
        let fd = TimerFd::new(ClockId::CLOCK_MONOTONIC, TimerFlags::TFD_NONBLOCK).ok()?;
        poll.registry()
            .register(
                &mut mio::unix::SourceFd(&fd.as_raw_fd()),
                TIMER,
                Interest::READABLE,
            )
            .ok()?;
        Some(Timer(fd))
    }

    /// Fires once after `d`; false if the timer cannot be set.
    fn arm(&self, d: Duration) -> bool {
        use nix::sys::time::TimeSpec;
        use nix::sys::timerfd::{Expiration, TimerSetTimeFlags};
        let d = d.max(Duration::from_nanos(1));
        self.0
            .set(
                Expiration::OneShot(TimeSpec::from_duration(d)),
                TimerSetTimeFlags::empty(),
            )
            .is_ok()
    }

    fn clear(&self) {
        use std::os::fd::AsRawFd;
        let _ = nix::unistd::read(self.0.as_raw_fd(), &mut [0u8; 8]);
    }
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
impl Timer {
    fn unregistered() -> Option<Timer> {
        None
    }
    fn fd(&self) -> std::os::fd::RawFd {
        -1
    }
    fn new(_: &Poll) -> Option<Timer> {
        None
    }
    fn arm(&self, _: Duration) -> bool {
        false
    }
    fn clear(&self) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::fd::AsRawFd;

    /// Polls `r` until `done` holds, failing with `what` after 5 s.
    fn poll_until(r: &Reactor, what: &str, mut done: impl FnMut() -> bool) {
        let start = Instant::now();
        while !done() {
            assert!(start.elapsed() < Duration::from_secs(5), "{what}");
            r.wait(None, Duration::from_millis(50)).unwrap();
        }
    }

    /// Serial bytes are stamped with the wake time and leave the server loop's busy-poll
    /// window alone; until the port's owner takes them they are pending, so the loop does
    /// not block over them. Socket data is activity.
    #[test]
    fn serial_readiness_is_pending_not_activity() {
        let r = Reactor::new().unwrap();
        let (master, slave) = serialport::TTYPort::pair().unwrap();
        let port = r
            .register_fd(slave.as_raw_fd(), Interest::READABLE)
            .unwrap();
        let mut udp = mio::net::UdpSocket::bind("127.0.0.1:0".parse().unwrap()).unwrap();
        let to = udp.local_addr().unwrap();
        let sock = r.register(&mut udp, Interest::READABLE).unwrap();

        nix::unistd::write(master.as_raw_fd(), b"x").unwrap();
        poll_until(&r, "pty never readable", || r.timed_pending());
        assert!(!r.take_activity(), "serial bytes counted as activity");
        let ready = r.take(port);
        assert!(ready.readable && ready.woke.is_some());
        assert!(!r.timed_pending());

        std::net::UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .send_to(b"y", to)
            .unwrap();
        poll_until(&r, "socket never readable", || r.take(sock).readable);
        assert!(r.take_activity());
        assert!(!r.timed_pending());
    }

    /// A shared registration gets its readiness straight from the poll into its bits, which
    /// stay as the owner left them until an event sets them again.
    #[test]
    fn shared_bits_are_set_by_the_poll_and_cleared_by_the_owner() {
        let r = Reactor::new().unwrap();
        let mut udp = mio::net::UdpSocket::bind("127.0.0.1:0".parse().unwrap()).unwrap();
        let to = udp.local_addr().unwrap();
        let bits = ReadyBits::new(0);
        r.register_shared(&mut udp, Interest::READABLE, false, &bits)
            .unwrap();
        r.poll_now().unwrap();
        assert!(!bits.readable(), "readable before anything was sent");

        let sender = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        sender.send_to(b"y", to).unwrap();
        poll_until(&r, "never readable", || bits.readable());
        assert!(r.take_activity(), "socket data is activity");
        let mut buf = [0u8; 8];
        assert_eq!(udp.recv(&mut buf).unwrap(), 1);
        bits.clear(ReadyBits::READABLE);
        r.poll_now().unwrap();
        assert!(!bits.readable(), "a poll without events set the bit again");

        sender.send_to(b"z", to).unwrap();
        poll_until(&r, "second datagram unseen", || bits.readable());
    }
}
