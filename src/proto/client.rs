//! The client's schedule: when to (re)try reaching the server, and what to tell the user
//! about it.
//!
//! Every failed attempt — no answer, a refused or timed-out connect, a peer that closes or
//! greets with something that is not a VRPN cookie — waits [`Limits::retry_interval`] before
//! the next one. Only a connection that was established for at least that long is retried at
//! once when it drops. So a port that accepts and closes costs one connection per interval,
//! not tens of thousands per second. Each kind of failure is explained once, until the next
//! success.

use std::net::SocketAddrV4;
use std::time::Instant;

use super::{DropReason, Limits};

/// Connection attempts of a client.
#[derive(Debug)]
pub(crate) struct ClientSchedule {
    /// The server's address.
    pub(crate) server: SocketAddrV4,
    /// The host as the user wrote it, for messages.
    pub(crate) host: String,
    pub(crate) tcp_only: bool,
    /// Our call-back listener, as announced in connection requests (UDP path).
    pub(crate) listen: Option<SocketAddrV4>,
    pub(crate) next_attempt: Instant,
    pub(crate) waiting_since: Instant,
    pub(crate) ever_connected: bool,
    pub(crate) warned_no_answer: bool,
    /// The last failure explained to the user (not repeated until a success).
    pub(crate) last_failure: Option<DropReason>,
    /// Failures since the last success.
    pub(crate) failures: u32,
    /// Sequence numbers carried across reconnects, as a C++ client does.
    pub(crate) seq: (u32, u32),
}

impl ClientSchedule {
    pub(crate) fn new(
        server: SocketAddrV4,
        host: &str,
        tcp_only: bool,
        listen: Option<SocketAddrV4>,
        now: Instant,
    ) -> ClientSchedule {
        ClientSchedule {
            server,
            host: host.to_string(),
            tcp_only,
            listen,
            next_attempt: now,
            waiting_since: now,
            ever_connected: false,
            warned_no_answer: false,
            last_failure: None,
            failures: 0,
            seq: (0, 0),
        }
    }

    /// `host:port` as the user named the server.
    pub(crate) fn server_text(&self) -> String {
        format!("{}:{}", self.host, self.server.port())
    }

    /// An attempt starts now; the next one is due an interval later unless this one succeeds.
    pub(crate) fn attempted(&mut self, now: Instant, limits: &Limits) {
        self.next_attempt = now + limits.retry_interval;
    }

    /// The handshake completed.
    pub(crate) fn connected(&mut self) {
        self.ever_connected = true;
        self.warned_no_answer = false;
        self.last_failure = None;
        self.failures = 0;
    }

    /// An attempt failed. Returns true when this failure should be explained (the first of
    /// its kind since the last success).
    pub(crate) fn failed(&mut self, now: Instant, failure: DropReason, limits: &Limits) -> bool {
        self.failures += 1;
        self.next_attempt = self.next_attempt.max(now + limits.retry_interval);
        let fresh = self.last_failure.as_ref() != Some(&failure);
        self.last_failure = Some(failure);
        fresh
    }

    /// An established connection dropped after `lasted`: retry at once if it had been up for
    /// a retry interval, else wait one (a server that accepts and drops at once must not make
    /// the client spin).
    pub(crate) fn dropped(&mut self, now: Instant, connected_at: Instant, limits: &Limits) {
        self.waiting_since = now;
        self.next_attempt = if now.saturating_duration_since(connected_at) >= limits.retry_interval
        {
            now
        } else {
            now + limits.retry_interval
        };
    }

    /// Whether the "no answer" explanation is due.
    pub(crate) fn no_answer_due(&mut self, now: Instant, limits: &Limits) -> bool {
        if self.tcp_only || self.warned_no_answer {
            return false;
        }
        if now.saturating_duration_since(self.waiting_since) >= limits.no_answer_warning {
            self.warned_no_answer = true;
            return true;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::Ipv4Addr;
    use std::time::Duration;

    #[test]
    fn failures_wait_an_interval_and_are_explained_once() {
        let limits = Limits::default();
        let t0 = Instant::now();
        let mut c = ClientSchedule::new(
            SocketAddrV4::new(Ipv4Addr::LOCALHOST, 3883),
            "localhost",
            true,
            None,
            t0,
        );
        c.attempted(t0, &limits);
        let bad = DropReason::BadGreeting;
        assert!(c.failed(t0 + Duration::from_millis(1), bad, &limits));
        assert!(c.next_attempt >= t0 + limits.retry_interval);
        assert!(!c.failed(t0 + Duration::from_millis(2), bad, &limits));
        assert!(c.failed(
            t0 + Duration::from_millis(3),
            DropReason::NoGreeting,
            &limits
        ));
        c.connected();
        assert!(c.failed(t0, DropReason::NoGreeting, &limits));
    }

    #[test]
    fn a_short_lived_connection_is_not_retried_at_once() {
        let limits = Limits::default();
        let t0 = Instant::now();
        let mut c = ClientSchedule::new(
            SocketAddrV4::new(Ipv4Addr::LOCALHOST, 3883),
            "localhost",
            true,
            None,
            t0,
        );
        let t1 = t0 + Duration::from_millis(10);
        c.dropped(t1, t0, &limits);
        assert_eq!(c.next_attempt, t1 + limits.retry_interval);
        let t2 = t0 + Duration::from_secs(30);
        c.dropped(t2, t0, &limits);
        assert_eq!(c.next_attempt, t2);
    }
}
