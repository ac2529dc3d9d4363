//! The liveness cycle every remote device runs (C++ `vrpn_BaseClass` client side): ping the
//! server's device, and say so when it does not answer for 3 s (warning) and 10 s (error).
//!
//! - A cycle starts when the remote is created, and again on every (re)connection and every
//!   drop: one ping at once, then one per second while unanswered.
//! - While unanswered, each re-ping checks the time since the cycle started: from 3 s a
//!   warning "No response from server for >= 3 seconds" (level = whole seconds), from 10 s an
//!   error "... >= 10 seconds" and the device counts as flatlined.
//! - A pong ends the cycle; after a flatline it brings "Server connection re-established!".
//!
//! C++ restarts the cycle at the drop only, so a reconnect that takes a second or two is
//! followed by a false "no response" warning about one second after the server is back. Here a
//! completed handshake restarts the clock, and pings are not sent while disconnected (a C++
//! connection discards them anyway).

use std::time::{Duration, Instant};

use crate::time::TimeVal;

/// Interval between pings while one is unanswered.
pub const PING_INTERVAL: Duration = Duration::from_secs(1);
/// Unanswered time after which a warning is sent.
pub const WARN_AFTER: Duration = Duration::from_secs(3);
/// Unanswered time after which an error is sent and the device counts as flatlined.
pub const ERROR_AFTER: Duration = Duration::from_secs(10);

/// Text of the 3 s warning.
pub const WARN_TEXT: &str = "No response from server for >= 3 seconds";
/// Text of the 10 s error.
pub const ERROR_TEXT: &str = "No response from server for >= 10 seconds";
/// Text sent when a flatlined server answers again.
pub const BACK_TEXT: &str = "Server connection re-established!";

/// What the cycle asks for on a poll.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PingAction {
    /// Nothing to do.
    Idle,
    /// Send a ping.
    Ping,
    /// Send a ping and a warning text (level = whole seconds unanswered).
    PingAndWarn(u32),
    /// Send a ping and an error text (level = whole seconds unanswered).
    PingAndError(u32),
}

/// One remote's liveness cycle, fed the time by its caller.
#[derive(Clone, Debug, Default)]
pub struct PingCycle {
    unanswered: bool,
    flatlined: bool,
    cycle_start: Option<Instant>,
    last_ping: Option<Instant>,
    quiet: bool,
    last_pong: Option<TimeVal>,
}

impl PingCycle {
    /// A cycle that starts at the first [`poll`](Self::poll).
    pub fn new() -> PingCycle {
        PingCycle {
            unanswered: true,
            ..PingCycle::default()
        }
    }

    fn restart(&mut self, now: Instant) {
        self.unanswered = true;
        self.cycle_start = Some(now);
        self.last_ping = None;
    }

    /// The connection completed a handshake: start the clock again and ping at once.
    pub fn on_connected(&mut self, now: Instant) {
        self.restart(now);
    }

    /// The connection was lost: a new cycle starts unless one is running (C++).
    pub fn on_dropped(&mut self, now: Instant) {
        if !self.unanswered {
            self.restart(now);
        }
    }

    /// A pong arrived (stamped `time` by the server). Returns true when it ends a flatline:
    /// the caller sends [`BACK_TEXT`].
    pub fn on_pong(&mut self, time: TimeVal) -> bool {
        self.last_pong = Some(time);
        let was_unanswered = std::mem::replace(&mut self.unanswered, false);
        was_unanswered && std::mem::replace(&mut self.flatlined, false)
    }

    /// What to do now; `connected` says whether a ping can reach the server.
    pub fn poll(&mut self, now: Instant, connected: bool) -> PingAction {
        if !self.unanswered {
            return PingAction::Idle;
        }
        let start = *self.cycle_start.get_or_insert(now);
        let due = self.last_ping.map_or(true, |last| {
            now.saturating_duration_since(last) >= PING_INTERVAL
        });
        if !due {
            return PingAction::Idle;
        }
        let first = self.last_ping.is_none();
        self.last_ping = Some(now);
        if first || self.quiet {
            return if connected {
                PingAction::Ping
            } else {
                PingAction::Idle
            };
        }
        let elapsed = now.saturating_duration_since(start);
        let secs = elapsed.as_secs() as u32;
        if elapsed >= ERROR_AFTER {
            self.flatlined = true;
            PingAction::PingAndError(secs)
        } else if elapsed >= WARN_AFTER {
            PingAction::PingAndWarn(secs)
        } else if connected {
            PingAction::Ping
        } else {
            PingAction::Idle
        }
    }

    /// When [`poll`](Self::poll) next has something to do.
    pub fn next_deadline(&self) -> Option<Instant> {
        if !self.unanswered {
            return None;
        }
        match self.last_ping {
            Some(last) => Some(last + PING_INTERVAL),
            None => self.cycle_start,
        }
    }

    /// True while a ping waits for its pong.
    pub fn waiting_for_pong(&self) -> bool {
        self.unanswered
    }

    /// Time of the last pong (the server's clock).
    pub fn last_pong(&self) -> Option<TimeVal> {
        self.last_pong
    }

    /// Suppresses (or re-enables) the warning and error texts; pings still go out.
    pub fn set_quiet(&mut self, quiet: bool) {
        self.quiet = quiet;
    }

    /// True after the 10 s error until a pong arrives.
    pub fn flatlined(&self) -> bool {
        self.flatlined
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn secs(s: f64) -> Duration {
        Duration::from_secs_f64(s)
    }

    #[test]
    fn warns_at_three_and_errs_at_ten_seconds() {
        let t0 = Instant::now();
        let mut c = PingCycle::new();
        assert_eq!(c.poll(t0, true), PingAction::Ping);
        assert_eq!(c.next_deadline(), Some(t0 + secs(1.0)));
        assert_eq!(c.poll(t0 + secs(0.5), true), PingAction::Idle);
        assert_eq!(c.poll(t0 + secs(1.0), true), PingAction::Ping);
        assert_eq!(c.poll(t0 + secs(2.0), true), PingAction::Ping);
        assert_eq!(c.poll(t0 + secs(3.0), true), PingAction::PingAndWarn(3));
        let mut t = t0 + secs(3.0);
        for _ in 0..6 {
            t += secs(1.0);
            assert!(matches!(c.poll(t, true), PingAction::PingAndWarn(_)));
        }
        assert_eq!(c.poll(t + secs(1.0), true), PingAction::PingAndError(10));
        assert!(c.flatlined());
        assert!(c.on_pong(TimeVal::new(5, 0)));
        assert_eq!(c.poll(t + secs(5.0), true), PingAction::Idle);
        assert_eq!(c.next_deadline(), None);
    }

    #[test]
    fn a_reconnect_restarts_the_clock() {
        let t0 = Instant::now();
        let mut c = PingCycle::new();
        assert_eq!(c.poll(t0, true), PingAction::Ping);
        assert!(!c.on_pong(TimeVal::ZERO));
        // Dropped at 10 s; reconnected at 12.5 s: no warning 1 s later, the pong comes first.
        c.on_dropped(t0 + secs(10.0));
        assert_eq!(c.poll(t0 + secs(10.0), false), PingAction::Idle);
        assert_eq!(c.poll(t0 + secs(11.0), false), PingAction::Idle);
        c.on_connected(t0 + secs(12.5));
        assert_eq!(c.poll(t0 + secs(12.5), true), PingAction::Ping);
        assert_eq!(c.poll(t0 + secs(13.5), true), PingAction::Ping);
        c.on_pong(TimeVal::ZERO);
        assert_eq!(c.poll(t0 + secs(14.5), true), PingAction::Idle);
    }

    #[test]
    fn a_long_outage_warns_while_disconnected() {
        let t0 = Instant::now();
        let mut c = PingCycle::new();
        c.on_dropped(t0);
        let mut warned = false;
        for s in 0..5 {
            if let PingAction::PingAndWarn(level) = c.poll(t0 + secs(s as f64), false) {
                warned = true;
                assert!(level >= 3);
            }
        }
        assert!(warned);
    }

    #[test]
    fn quiet_cycles_only_ping() {
        let t0 = Instant::now();
        let mut c = PingCycle::new();
        c.set_quiet(true);
        for s in 0..12 {
            assert_eq!(c.poll(t0 + secs(s as f64), true), PingAction::Ping);
        }
    }
}
