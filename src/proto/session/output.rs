//! What the session asks of the shell: I/O requests, bytes and datagrams to send, the next
//! deadline and the work due at it (time-outs, connection attempts, replay pacing).

use std::net::SocketAddrV4;
use std::time::Instant;

use super::{Kind, Session};
use crate::proto::buffers::DatagramQueue;
use crate::proto::endpoint::Phase;
use crate::proto::{DropReason, IoRequest, NoticeKind, PeerId, Severity};
use crate::time::Now;

impl Session {
    // ------------------------------------------------------------------ output

    /// The next thing the shell must do.
    pub fn poll_io(&mut self) -> Option<IoRequest> {
        self.io.pop_front()
    }

    /// The text of a connection request (`IP PORT` and a NUL).
    pub fn request_text(&self) -> &[u8] {
        &self.request[..self.request_len]
    }

    /// Reliable bytes waiting for `peer`.
    pub fn tcp_pending(&self, peer: PeerId) -> &[u8] {
        match self.peer(peer) {
            Some(p) if p.phase != Phase::Connecting => p.tx.pending(),
            _ => &[],
        }
    }

    /// `n` bytes of [`tcp_pending`](Self::tcp_pending) were written.
    pub fn tcp_sent(&mut self, peer: PeerId, n: usize) {
        if let Some(p) = self.peer_mut(peer) {
            p.tx.consume(n);
        }
    }

    /// The oldest datagram waiting for `peer`. Without an outbound UDP socket, queued
    /// datagrams are discarded (unreliable).
    pub fn udp_front(&mut self, peer: PeerId) -> Option<&[u8]> {
        let p = self.peer_mut(peer)?;
        if !p.udp_ready {
            p.udp_tx.clear();
            return None;
        }
        p.udp_tx.front()
    }

    /// The datagrams waiting for `peer` over an open channel, if any: for a send that batches
    /// every peer's datagrams into one system call. Take out what went with
    /// [`udp_consume`](Self::udp_consume).
    #[inline]
    pub(crate) fn udp_queue(&self, peer: PeerId) -> Option<&DatagramQueue> {
        self.peer(peer)
            .filter(|p| p.udp_ready && !p.udp_tx.is_empty())
            .map(|p| &p.udp_tx)
    }

    /// Up to `n` of the datagrams [`udp_queue`](Self::udp_queue) showed went out (or were
    /// lost); returns how many were taken out.
    #[inline]
    pub(crate) fn udp_consume(&mut self, peer: PeerId, n: usize) -> usize {
        match self.peer_mut(peer) {
            Some(p) if p.udp_ready => {
                let k = n.min(p.udp_tx.len());
                p.udp_tx.pop_many(k);
                k
            }
            _ => 0,
        }
    }

    /// The datagram from [`udp_front`](Self::udp_front) went out (or was lost).
    pub fn udp_sent(&mut self, peer: PeerId) {
        if let Some(p) = self.peer_mut(peer) {
            p.udp_tx.pop_front();
        }
    }

    /// The earliest time [`handle_timeout`](Self::handle_timeout) has work to do.
    #[inline]
    pub fn poll_timeout(&self) -> Option<Instant> {
        match self.timeout_cache.get() {
            Some(known) => known,
            None => self.timeout_changed(),
        }
    }

    #[inline(never)]
    fn timeout_changed(&self) -> Option<Instant> {
        let d = self.work_out_timeout();
        self.timeout_cache.set(Some(d));
        d
    }

    fn work_out_timeout(&self) -> Option<Instant> {
        let mut d: Option<Instant> = None;
        let mut at = |t: Instant| d = Some(d.map_or(t, |x| x.min(t)));
        for p in self.peers.iter().flatten() {
            if let Some(t) = p.deadline {
                at(t);
            }
            if let Some(t) = p.clock.as_deref().and_then(|c| c.next_deadline()) {
                at(t);
            }
            // A clock translation is reused until its limit: a deadline, so that no pass
            // reads the clock to check it.
            if let Some(pass) = &p.clock_pass {
                at(pass.until);
            }
            if let Some(t) = p.udp_held_until {
                at(t);
            }
        }
        match &self.kind {
            Kind::Client(c) if self.peers.iter().flatten().next().is_none() => {
                at(c.next_attempt);
                if !c.tcp_only && !c.warned_no_answer {
                    at(c.waiting_since + self.limits.no_answer_warning);
                }
            }
            Kind::Server(p) => {
                if let Some(t) = p.next_deadline() {
                    at(t);
                }
            }
            _ => {}
        }
        d
    }

    /// Does what is due at `now`: connect and greeting time-outs, the client's next attempt
    /// and its "no answer" explanation, the server's request summary, the replay clock.
    pub fn handle_timeout(&mut self, now: Now) {
        self.timeouts_changed();
        for p in self.peers.iter_mut().flatten() {
            if p.clock_pass.is_some_and(|pass| now.mono >= pass.until) {
                p.clock_pass = None;
            }
            if p.udp_held_until.is_some_and(|t| now.mono >= t) {
                p.udp_held_until = None;
                p.udp_hold_probe = None;
            }
        }
        for slot in 0..self.peers.len() {
            let Some(p) = self.peers[slot].as_ref() else {
                continue;
            };
            if !p.deadline.is_some_and(|d| now.mono >= d) {
                continue;
            }
            let (id, who, phase) = (p.id, p.label.clone(), p.phase);
            let is_client = matches!(self.kind, Kind::Client(_));
            let (text, reason) = match phase {
                Phase::Connecting => (
                    format!("TCP connection to {who} timed out"),
                    DropReason::ConnectTimeout,
                ),
                _ if is_client => (
                    format!(
                        "{who} accepted the connection but sent no VRPN greeting within {:?}: \
                         is a VRPN server (and not another program) listening there? (will keep \
                         retrying every {:?})",
                        self.limits.handshake_timeout, self.limits.retry_interval
                    ),
                    DropReason::NoGreeting,
                ),
                _ => (
                    format!(
                        "dropped {who}: no VRPN greeting within {:?} \
                         (Limits::handshake_timeout)",
                        self.limits.handshake_timeout
                    ),
                    DropReason::NoGreeting,
                ),
            };
            self.drop_peer(now, id, reason, text);
        }
        self.send_clock_queries(now);
        let limits = self.limits;
        let idle = self.peers.iter().flatten().next().is_none();
        match &mut self.kind {
            Kind::Client(c) if idle => {
                let explain = c.no_answer_due(now.mono, &limits).then(|| {
                    let listen = c.listen.map_or_else(|| "?".to_string(), |l| l.to_string());
                    let text = format!(
                        "no answer from the VRPN server at {host}:{port} after {wait:?}: \
                         either no server runs there, or it cannot connect back to this \
                         machine at {listen} (a firewall or NAT). If the server runs, use \
                         DEVICE@tcp://{host}:{port} to connect over TCP only",
                        host = c.host,
                        port = c.server.port(),
                        wait = limits.no_answer_warning
                    );
                    (c.server_text(), text)
                });
                let due = now.mono >= c.next_attempt;
                if let Some((server, text)) = explain {
                    self.notice(Severity::Warning, NoticeKind::NoAnswer { server }, text);
                }
                if due {
                    self.attempt(now);
                }
            }
            Kind::Server(_) => self.request_summary(now.mono),
            Kind::Client(_) | Kind::File(_) | Kind::Loopback => {}
        }
    }

    /// Client: starts a connection attempt.
    fn attempt(&mut self, now: Now) {
        self.timeouts_changed();
        let limits = self.limits;
        let Kind::Client(c) = &mut self.kind else {
            return;
        };
        c.attempted(now.mono, &limits);
        let server = c.server;
        if c.tcp_only {
            let id = self.alloc_peer(true, server);
            if let Some(p) = self.peer_mut(id) {
                p.deadline = Some(now.mono + limits.connect_timeout);
            }
            self.io.push_back(IoRequest::Connect {
                peer: id,
                addr: server,
            });
        } else {
            self.io.push_back(IoRequest::SendRequest { to: server });
        }
    }

    /// Client: a connection request could not be sent.
    pub fn report_request_error(&mut self, now: Now, to: SocketAddrV4, error: &std::io::Error) {
        self.timeouts_changed();
        let limits = self.limits;
        let Kind::Client(c) = &mut self.kind else {
            return;
        };
        let reason = DropReason::RequestFailed(error.kind());
        if c.failed(now.mono, reason, &limits) {
            let text = format!("cannot send a connection request to {to}: {error}");
            let peer = c.server_text();
            self.notice(
                Severity::Warning,
                NoticeKind::PeerDropped { peer, reason },
                text,
            );
        }
    }

    /// Whether a peer used up its message budget in the last pass, so input may be waiting in
    /// its buffers or sockets that no poll will announce again: a wait must not block.
    pub fn input_buffered(&self) -> bool {
        let budget = self.limits.max_messages_per_peer_per_loop;
        self.peers.iter().flatten().any(|p| p.budget >= budget)
    }

    /// Starts a new loop pass at `now`: every peer gets its full message budget again, and a
    /// replay's clock advances (C++ model: each pass plays what became due since the last).
    pub fn begin_pass(&mut self, now: &dyn crate::time::TimeSource) {
        for p in self.peers.iter_mut().flatten() {
            // A peer that used up its budget last pass may still have input buffered.
            if p.budget >= self.limits.max_messages_per_peer_per_loop {
                self.input_pending = true;
            }
            p.budget = 0;
        }
        if let Kind::File(r) = &mut self.kind {
            r.tick(now.now().mono);
        }
    }

    /// Sends every clock query that is due (each to its own peer only, never logged: it is
    /// the session's own traffic).
    fn send_clock_queries(&mut self, now: Now) {
        let due = self.peers.iter().flatten().any(|p| {
            p.phase == Phase::Connected
                && p.clock
                    .as_deref()
                    .and_then(|c| c.next_deadline())
                    .is_some_and(|t| t <= now.mono)
        });
        if !due {
            return;
        }
        let Some(ids) = self.ensure_clock_ids(now) else {
            return;
        };
        for p in self.peers.iter_mut().flatten() {
            if p.phase != Phase::Connected {
                continue;
            }
            let Some(mut c) = p.clock.take() else {
                continue;
            };
            while let Some(q) = c.poll_query(now) {
                p.note_clock_query(q.id);
                let mut buf = [0u8; crate::wire::payload::clock::Query::LEN];
                let n = q.encode(&mut buf);
                let _ = p.pack(
                    now.wall,
                    ids.sender,
                    ids.query,
                    &buf[..n],
                    crate::wire::class::LOW_LATENCY,
                );
            }
            p.clock = Some(c);
        }
    }

    /// The clock estimate of the first connected peer (a client's server), if sync is in
    /// effect.
    pub fn clock_estimate(&self, now: Now) -> Option<crate::proto::clock::Estimate> {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.phase == Phase::Connected)
            .find_map(|p| p.clock.as_deref().and_then(|c| c.estimate(now)))
    }

    /// Each connected peer's address and clock estimate (`None` while sync is not in effect
    /// with it: not yet, stale, or a peer that does not answer, such as C++ VRPN).
    pub fn peer_clocks(&self, now: Now) -> Vec<(String, Option<crate::proto::clock::Estimate>)> {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.phase == Phase::Connected && !self.is_replay_peer(p))
            .map(|p| {
                (
                    p.label.clone(),
                    p.clock.as_deref().and_then(|c| c.estimate(now)),
                )
            })
            .collect()
    }
}
