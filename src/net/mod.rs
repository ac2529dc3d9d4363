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

thread_local! {
    /// Set by [`interrupt_pass`]: the delivery loop running on this thread stops after the
    /// callback that is running.
    static INTERRUPT: Cell<bool> = const { Cell::new(false) };
}

/// Asks the `mainloop()` pass (or replay control) running on this thread to return after the
/// callback that is running now; what remains is delivered by the next call. For a runtime
/// that must act between callbacks: the Python module calls it when a callback was
/// interrupted by a signal (Ctrl-C), so that `KeyboardInterrupt` surfaces at once.
pub fn interrupt_pass() {
    INTERRUPT.with(|i| i.set(true));
}

/// Forgets an interruption asked for outside any pass.
pub(crate) fn clear_interrupt() {
    INTERRUPT.with(|i| i.set(false));
}

/// Bounds one delivery loop: it stops once it has delivered for `limit` (when there is one),
/// or when [`interrupt_pass`] asks (looked for with the clock, or after every delivery when
/// there is no limit). The clock is read only from the second delivery of a loop on (a pass that delivers one message reads none), then at intervals that double
/// while little of the budget is spent and shrink to every delivery once an eighth of it is,
/// so the loop overshoots its limit by at most a sixteenth of it plus one callback, whether
/// callbacks take nanoseconds or seconds.
#[derive(Debug)]
pub(crate) struct PassBudget {
    limit: Option<std::time::Duration>,
    delivered: u32,
    next_check: u32,
    interval: u32,
    start: Option<std::time::Instant>,
}

impl PassBudget {
    /// Most deliveries between two checks (of the clock and of an interruption).
    const MAX_INTERVAL: u32 = 64;

    /// A budget of `limit` (`None`: only an interruption stops the loop).
    pub(crate) fn new(limit: Option<std::time::Duration>) -> PassBudget {
        PassBudget {
            limit,
            delivered: 0,
            next_check: 1,
            interval: 1,
            start: None,
        }
    }

    /// One delivery is done: false when the loop must stop now.
    #[inline]
    pub(crate) fn spend(&mut self) -> bool {
        self.delivered += 1;
        self.delivered < self.next_check || self.check()
    }

    #[inline(never)]
    fn check(&mut self) -> bool {
        if INTERRUPT.with(|i| i.replace(false)) {
            return false;
        }
        let Some(limit) = self.limit else {
            // No clock to read: look for an interruption after every delivery.
            self.next_check = self.delivered + 1;
            return true;
        };
        if self.delivered < 2 {
            // A single delivery costs no clock reading.
            self.next_check = 2;
            return true;
        }
        let now = std::time::Instant::now();
        let Some(start) = self.start else {
            self.start = Some(now);
            self.next_check = self.delivered + 1;
            return true;
        };
        let spent = now.saturating_duration_since(start);
        if spent >= limit {
            return false;
        }
        self.interval = if spent < limit / 8 {
            (self.interval * 2).min(Self::MAX_INTERVAL)
        } else {
            1
        };
        self.next_check = self.delivered + self.interval;
        true
    }
}

#[cfg(test)]
mod budget_tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn slow_deliveries_stop_near_the_limit() {
        // Judged by the times of the calls, not by how many fit: a loaded machine stretches
        // the 4 ms sleeps, which changes the count but not the rule (two deliveries without a
        // clock reading, the budget's clock starting at the second, and a stop at the first
        // check that finds the limit spent).
        const LIMIT: Duration = Duration::from_millis(20);
        let mut b = PassBudget::new(Some(LIMIT));
        let mut calls = Vec::new();
        loop {
            let before = std::time::Instant::now();
            let go = b.spend();
            calls.push((before, std::time::Instant::now(), go));
            if !go {
                break;
            }
            std::thread::sleep(Duration::from_millis(4));
            assert!(calls.len() < 100, "never stopped");
        }
        assert!(
            calls.len() >= 3,
            "stopped within the two unmeasured deliveries"
        );
        let (clock_from_before, clock_from_after, _) = calls[1];
        let (&(_, stopped_after, _), went_on) = calls.split_last().unwrap();
        for &(before, _, go) in &went_on[2..] {
            assert!(go);
            assert!(
                before.duration_since(clock_from_after) < LIMIT,
                "a delivery went ahead after the limit was spent"
            );
        }
        assert!(
            stopped_after.duration_since(clock_from_before) >= LIMIT,
            "stopped before the limit was spent"
        );
    }

    #[test]
    fn fast_deliveries_check_the_clock_rarely_and_interruptions_stop_them() {
        let mut b = PassBudget::new(Some(Duration::from_secs(3600)));
        for _ in 0..10_000 {
            assert!(b.spend());
        }
        assert_eq!(b.interval, PassBudget::MAX_INTERVAL);
        interrupt_pass();
        let mut more = 0;
        while b.spend() {
            more += 1;
        }
        assert!(
            more < PassBudget::MAX_INTERVAL,
            "{more} deliveries after the interruption"
        );
        // Taken by that loop: the next one runs.
        assert!(PassBudget::new(None).spend());
    }
}
