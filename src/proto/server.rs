//! The server's policy for connection requests (the UDP datagram "call me back at IP PORT").
//!
//! C++ starts a blocking call-back connect for every request, to whatever address it names.
//! That lets one datagram aim the server's connect (and its cookie) at any host, and a flood of
//! requests makes the server connect thousands of times. Here a request:
//!
//! - is called back at the address it **came from** (with the port it names), unless the
//!   server was set up for multi-homed clients ([`Limits::callback_to_named_address`]);
//! - is coalesced: while a call-back to that address is in progress, or a peer at that address
//!   is still greeting, further requests for it are ignored (a waiting client re-sends every
//!   second);
//! - is rate-limited ([`Limits::max_requests_per_second`], a token bucket that holds a whole
//!   server's worth of requests, [`Limits::max_connections`], so that a room of clients
//!   started together is called back at once) and bounded in flight
//!   ([`Limits::max_pending_callbacks`]); when that many call-backs are still connecting, one
//!   that has been connecting for longer than [`CALLBACK_PATIENCE`] (a host that drops SYNs
//!   makes it hang) is given up for the new one, so hanging call-backs cannot shut out a client
//!   whose call-back completes in a round trip, while call-backs that are about to complete are
//!   never given up;
//! - is never resolved: a named host that is not a dotted quad is not looked up in the loop.
//!
//! Ignored requests are counted and reported in one notice at most every
//! [`NOTICE_INTERVAL`], so a flood cannot flood the log either.

use std::net::{Ipv4Addr, SocketAddrV4};
use std::time::{Duration, Instant};

use super::Limits;
use crate::wire::lob::Request;

/// Shortest time between two notices about ignored requests.
pub const NOTICE_INTERVAL: Duration = Duration::from_secs(5);

/// A call-back still connecting after this long may be given up to make room for a new
/// request: a connect completes in a round trip (well under this even between continents),
/// so one that has not is likely aimed at a host that drops SYNs.
pub const CALLBACK_PATIENCE: Duration = Duration::from_millis(500);

/// Why a request was not called back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ignored {
    /// The datagram is not a connection request.
    Malformed,
    /// Over the rate limit.
    RateLimited,
    /// A call-back to that address is already in progress.
    Duplicate,
    /// Too many call-backs in progress.
    TooManyPending,
    /// The server serves its maximum of clients.
    Full,
}

/// What to do with one request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Decision {
    CallBack(SocketAddrV4),
    Ignore(Ignored),
}

/// Counts of ignored requests since the last notice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct IgnoredCounts {
    pub(crate) malformed: u32,
    pub(crate) rate_limited: u32,
    pub(crate) duplicate: u32,
    pub(crate) pending: u32,
    pub(crate) full: u32,
    /// Hanging call-backs given up to make room for new ones.
    pub(crate) abandoned: u32,
}

impl IgnoredCounts {
    fn total(&self) -> u32 {
        self.malformed
            + self.rate_limited
            + self.duplicate
            + self.pending
            + self.full
            + self.abandoned
    }
}

/// Request admission state of one server.
#[derive(Debug)]
pub(crate) struct RequestPolicy {
    tokens: f64,
    refilled: Option<Instant>,
    ignored: IgnoredCounts,
    last_notice: Option<Instant>,
    /// The first malformed request is explained with its source and problem.
    explained_malformed: bool,
}

impl RequestPolicy {
    pub(crate) fn new() -> RequestPolicy {
        RequestPolicy {
            tokens: 0.0,
            refilled: None,
            ignored: IgnoredCounts::default(),
            last_notice: None,
            explained_malformed: false,
        }
    }

    /// Takes one request's token. The bucket refills at the rate and holds the larger of one
    /// second's worth and a full server's worth of requests: a burst of every client the
    /// server can take is called back at once, a flood gets that once and then the rate.
    fn take_token(&mut self, now: Instant, limits: &Limits) -> bool {
        let rate = f64::from(limits.max_requests_per_second.max(1));
        let burst = rate.max(limits.max_connections as f64);
        let elapsed = match self.refilled {
            Some(t) => now.saturating_duration_since(t).as_secs_f64(),
            None => f64::INFINITY,
        };
        self.refilled = Some(now);
        self.tokens = (self.tokens + elapsed * rate).min(burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }

    /// The address to call back for a request from `from`.
    pub(crate) fn target(from: SocketAddrV4, req: &Request<'_>, limits: &Limits) -> SocketAddrV4 {
        if limits.callback_to_named_address {
            if let Ok(ip) = req.host.parse::<Ipv4Addr>() {
                return SocketAddrV4::new(ip, req.port);
            }
        }
        SocketAddrV4::new(*from.ip(), req.port)
    }

    /// Decides about a well-formed request. `busy(addr)` says whether a call-back or a greeting
    /// peer already exists for that address; `pending` counts call-backs in progress and
    /// `live` the peers with a TCP connection.
    pub(crate) fn decide(
        &mut self,
        now: Instant,
        target: SocketAddrV4,
        busy: bool,
        pending: usize,
        live: usize,
        limits: &Limits,
    ) -> Decision {
        let why = if busy {
            Some(Ignored::Duplicate)
        } else if live >= limits.max_connections {
            Some(Ignored::Full)
        } else if pending >= limits.max_pending_callbacks {
            Some(Ignored::TooManyPending)
        } else if !self.take_token(now, limits) {
            Some(Ignored::RateLimited)
        } else {
            None
        };
        match why {
            Some(w) => {
                self.count(w);
                Decision::Ignore(w)
            }
            None => Decision::CallBack(target),
        }
    }

    /// Counts an ignored request. Returns true for the first malformed one, which deserves
    /// its own notice.
    pub(crate) fn count(&mut self, why: Ignored) -> bool {
        let c = &mut self.ignored;
        match why {
            Ignored::Malformed => {
                c.malformed += 1;
                return !std::mem::replace(&mut self.explained_malformed, true);
            }
            Ignored::RateLimited => c.rate_limited += 1,
            Ignored::Duplicate => c.duplicate += 1,
            Ignored::TooManyPending => c.pending += 1,
            Ignored::Full => c.full += 1,
        }
        false
    }

    /// Counts a call-back given up unfinished to make room for a newer one.
    pub(crate) fn count_abandoned(&mut self) {
        self.ignored.abandoned += 1;
    }

    /// A summary of what was ignored, when one is due. Duplicates alone are normal (clients
    /// re-send every second while their call-back is in progress) and not reported.
    pub(crate) fn summary(&mut self, now: Instant) -> Option<String> {
        let c = self.ignored;
        if c.total() == c.duplicate {
            return None;
        }
        if self
            .last_notice
            .is_some_and(|t| now.saturating_duration_since(t) < NOTICE_INTERVAL)
        {
            return None;
        }
        self.last_notice = Some(now);
        self.ignored = IgnoredCounts::default();
        let mut parts = Vec::new();
        for (n, what) in [
            (
                c.rate_limited,
                "over the rate limit (Limits::max_requests_per_second)",
            ),
            (
                c.pending,
                "while too many call-backs were in progress (Limits::max_pending_callbacks)",
            ),
            (
                c.full,
                "while the server was full (Limits::max_connections)",
            ),
            (c.duplicate, "for a call-back already in progress"),
            (
                c.abandoned,
                "whose call-backs were still connecting after 500 ms when newer ones needed \
                 room (Limits::max_pending_callbacks)",
            ),
            (c.malformed, "that were not connection requests"),
        ] {
            if n > 0 {
                parts.push(format!("{n} {what}"));
            }
        }
        Some(format!("ignored connection requests: {}", parts.join(", ")))
    }

    /// When the next summary is due, if ignored requests wait to be reported (the first
    /// summary goes out as soon as there is something to say; later ones an interval apart).
    pub(crate) fn next_deadline(&self) -> Option<Instant> {
        let c = self.ignored;
        if c.total() == c.duplicate {
            return None;
        }
        self.last_notice.map(|t| t + NOTICE_INTERVAL)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addr(port: u16) -> SocketAddrV4 {
        SocketAddrV4::new(Ipv4Addr::LOCALHOST, port)
    }

    #[test]
    fn requests_are_rate_limited_and_summarised() {
        let limits = Limits {
            max_requests_per_second: 10,
            max_connections: 10,
            ..Limits::default()
        };
        let mut p = RequestPolicy::new();
        let t0 = Instant::now();
        let mut called = 0;
        for i in 0..100 {
            if let Decision::CallBack(_) = p.decide(t0, addr(2000 + i), false, 0, 0, &limits) {
                called += 1;
            }
        }
        assert_eq!(called, 10);
        let s = p.summary(t0).unwrap();
        assert!(s.contains("90 over the rate limit"), "{s}");
        // Within the interval: no second notice.
        p.count(Ignored::RateLimited);
        assert!(p.summary(t0 + Duration::from_secs(1)).is_none());
        assert!(p.summary(t0 + NOTICE_INTERVAL).is_some());
        // Tokens come back with time.
        let later = t0 + Duration::from_secs(1);
        assert!(matches!(
            p.decide(later, addr(1), false, 0, 0, &limits),
            Decision::CallBack(_)
        ));
    }

    #[test]
    fn a_burst_of_a_full_server_is_called_back_at_once_then_the_rate_holds() {
        let limits = Limits {
            max_requests_per_second: 100,
            ..Limits::default()
        };
        let mut p = RequestPolicy::new();
        let t0 = Instant::now();
        let called = |p: &mut RequestPolicy, at: Instant, n: u16| {
            (0..n)
                .filter(|&i| {
                    matches!(
                        p.decide(at, addr(2000 + i), false, 0, 0, &limits),
                        Decision::CallBack(_)
                    )
                })
                .count()
        };
        assert_eq!(called(&mut p, t0, 300), limits.max_connections);
        assert!(p.summary(t0).unwrap().contains("45 over the rate limit"));
        // Afterwards a flood gets the rate, not another burst.
        assert_eq!(called(&mut p, t0 + Duration::from_millis(500), 300), 50);
    }

    #[test]
    fn duplicates_pending_and_full_are_ignored() {
        let limits = Limits::default();
        let mut p = RequestPolicy::new();
        let t0 = Instant::now();
        assert_eq!(
            p.decide(t0, addr(1), true, 0, 0, &limits),
            Decision::Ignore(Ignored::Duplicate)
        );
        assert!(p.summary(t0).is_none(), "duplicates alone are normal");
        assert_eq!(
            p.decide(t0, addr(1), false, limits.max_pending_callbacks, 0, &limits),
            Decision::Ignore(Ignored::TooManyPending)
        );
        assert_eq!(
            p.decide(t0, addr(1), false, 0, limits.max_connections, &limits),
            Decision::Ignore(Ignored::Full)
        );
    }

    #[test]
    fn call_backs_go_to_the_source_unless_configured() {
        let req = Request {
            host: "10.9.9.9",
            port: 4000,
        };
        let from = SocketAddrV4::new(Ipv4Addr::new(127, 0, 0, 2), 5555);
        let l = Limits::default();
        assert_eq!(
            RequestPolicy::target(from, &req, &l),
            SocketAddrV4::new(Ipv4Addr::new(127, 0, 0, 2), 4000)
        );
        let named = Limits {
            callback_to_named_address: true,
            ..Limits::default()
        };
        assert_eq!(
            RequestPolicy::target(from, &req, &named),
            SocketAddrV4::new(Ipv4Addr::new(10, 9, 9, 9), 4000)
        );
        let by_name = Request {
            host: "client.example",
            port: 4000,
        };
        assert_eq!(
            RequestPolicy::target(from, &by_name, &named).ip(),
            from.ip()
        );
    }
}
