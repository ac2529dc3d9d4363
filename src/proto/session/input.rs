//! What the shell reports about the sockets: accepted connections, connection requests,
//! completed connects, bytes and datagrams read, closes.

use std::net::SocketAddrV4;
use std::time::Instant;

use super::{Kind, Session};
use crate::proto::buffers::DatagramInbox;
use crate::proto::endpoint::Phase;
use crate::proto::server::{Decision, Ignored, RequestPolicy, CALLBACK_PATIENCE};
use crate::proto::{DropReason, IoRequest, NoticeKind, PeerId, Severity};
use crate::time::Now;
use crate::wire;

impl Session {
    // ------------------------------------------------------------------ server inputs

    /// Server: the TCP listener accepted a client (the TCP-only path: anything accepted on the
    /// TCP port is TCP-only, as in C++). `None`: refused (the shell closes the socket).
    pub fn handle_accept(
        &mut self,
        now: Now,
        from: SocketAddrV4,
        local: SocketAddrV4,
    ) -> Option<PeerId> {
        if self.live_peers() >= self.limits.max_connections && !self.evict_greeting_peer(now) {
            let text = format!(
                "refused TCP client {from}: {} clients already connected (limit)",
                self.limits.max_connections
            );
            self.notice(
                Severity::Warning,
                NoticeKind::ConnectionLimit { from },
                text,
            );
            return None;
        }
        let id = self.alloc_peer(true, from);
        self.open_peer_log(id);
        self.start_greeting(now, id, local);
        Some(id)
    }

    /// Server: a datagram arrived on the server port from `from` — a connection request.
    pub fn handle_request(&mut self, now: Now, from: SocketAddrV4, datagram: &[u8]) {
        self.timeouts_changed();
        let limits = self.limits;
        let req = match wire::lob::parse_request(datagram) {
            Ok(r) => r,
            Err(e) => {
                let first = match &mut self.kind {
                    Kind::Server(p) => p.count(Ignored::Malformed),
                    _ => false,
                };
                if first {
                    let text = format!("ignored a bad connection request from {from}: {e}");
                    self.notice(
                        Severity::Warning,
                        NoticeKind::BadConnectionRequest { from },
                        text,
                    );
                }
                self.request_summary(now.mono);
                return;
            }
        };
        let target = RequestPolicy::target(from, &req, &limits);
        let busy = self.peers.iter().flatten().any(|p| {
            p.callback
                && p.addr == target
                && matches!(p.phase, Phase::Connecting | Phase::AwaitingCookie)
        });
        if !busy && self.live_peers() >= limits.max_connections {
            // Full: the peer greeting longest gives way, as for a TCP connection.
            self.evict_greeting_peer(now);
        }
        if !busy && self.pending_callbacks() >= limits.max_pending_callbacks {
            // Call-backs that hang (a host that drops SYNs) must not hold every slot until
            // their connect times out: the oldest gives way once it has shown it will not
            // complete soon. One that may still complete in a round trip is kept (the new
            // request is ignored, and its client asks again).
            self.abandon_stale_callback(now.mono);
        }
        let (pending, live) = (self.pending_callbacks(), self.live_peers());
        let Kind::Server(policy) = &mut self.kind else {
            return;
        };
        match policy.decide(now.mono, target, busy, pending, live, &limits) {
            Decision::CallBack(addr) => {
                let id = self.alloc_peer(false, addr);
                let ep = self.peer_mut(id).expect("just made");
                ep.callback = true;
                ep.deadline = Some(now.mono + limits.connect_timeout);
                self.open_peer_log(id);
                self.io.push_back(IoRequest::Connect { peer: id, addr });
            }
            Decision::Ignore(_) => {}
        }
        self.request_summary(now.mono);
    }

    /// Makes room for a new connection when every slot is taken: the peer that has been
    /// greeting longest without sending a cookie is dropped (a crowd of silent connections
    /// cannot keep a real client out). Returns false when every peer is connected.
    fn evict_greeting_peer(&mut self, now: Now) -> bool {
        let oldest = self
            .peers
            .iter()
            .flatten()
            .filter(|p| p.phase == Phase::AwaitingCookie)
            .min_by_key(|p| p.deadline)
            .map(|p| (p.id, p.label.clone()));
        let Some((id, who)) = oldest else {
            return false;
        };
        let text = format!(
            "dropped {who}, which had not greeted yet, to make room for a new client \
             (Limits::max_connections)"
        );
        self.drop_peer(now, id, DropReason::MadeRoom, text);
        true
    }

    /// Gives up the call-back that has been connecting longest, if that is longer than
    /// [`CALLBACK_PATIENCE`], without a notice of its own (the request summary counts it).
    fn abandon_stale_callback(&mut self, now: Instant) {
        let connect_timeout = self.limits.connect_timeout;
        let oldest = self
            .peers
            .iter()
            .flatten()
            .filter(|p| p.callback && p.phase == Phase::Connecting)
            .filter_map(|p| Some((p.deadline?, p.id)))
            .min_by_key(|&(deadline, _)| deadline);
        let Some((deadline, id)) = oldest else {
            return;
        };
        // A call-back's deadline is its start plus the connect timeout.
        let started = deadline.checked_sub(connect_timeout).unwrap_or(deadline);
        if now.saturating_duration_since(started) < CALLBACK_PATIENCE {
            return;
        }
        if let Some(slot) = self.peers.get_mut(id.slot) {
            *slot = None;
        }
        self.io.push_back(IoRequest::Close { peer: id });
        if let Kind::Server(policy) = &mut self.kind {
            policy.count_abandoned();
        }
    }

    pub(super) fn request_summary(&mut self, now: Instant) {
        if let Kind::Server(p) = &mut self.kind {
            if let Some(text) = p.summary(now) {
                self.notice(Severity::Warning, NoticeKind::RequestsIgnored, text);
            }
        }
    }

    fn open_peer_log(&mut self, id: PeerId) {
        let Some(make) = self.logs.per_peer.as_mut() else {
            return;
        };
        self.logs.peers_logged += 1;
        match make(self.logs.peers_logged) {
            Ok(w) => {
                if let Some(p) = self.peer_mut(id) {
                    p.log_in = Some(w);
                }
            }
            Err(e) => self.notice(
                Severity::Error,
                NoticeKind::LogFailed,
                format!("cannot open incoming log: {e}"),
            ),
        }
    }

    // ------------------------------------------------------------------ client inputs

    /// Client: the call-back listener accepted a connection from the server. `None`: a peer
    /// already exists (the shell closes this one).
    pub fn handle_callback(
        &mut self,
        now: Now,
        from: SocketAddrV4,
        local: SocketAddrV4,
    ) -> Option<PeerId> {
        if !matches!(self.kind, Kind::Client(_)) || self.peers.iter().flatten().next().is_some() {
            return None;
        }
        let id = self.alloc_peer(false, from);
        self.start_greeting(now, id, local);
        Some(id)
    }

    /// Client: the connection request drew an ICMP "port unreachable".
    pub fn handle_request_refused(&mut self, now: Now) {
        self.timeouts_changed();
        let limits = self.limits;
        let Kind::Client(c) = &mut self.kind else {
            return;
        };
        if c.failed(now.mono, DropReason::Unreachable, &limits) {
            let server = c.server_text();
            self.notice(
                Severity::Warning,
                NoticeKind::PeerDropped {
                    peer: server.clone(),
                    reason: DropReason::Unreachable,
                },
                format!(
                    "no VRPN server at {server}: its UDP port answered 'port unreachable'; \
                     will keep retrying"
                ),
            );
        }
    }

    // ------------------------------------------------------------------ TCP

    /// A TCP connect the session asked for completed.
    pub fn handle_connected(&mut self, now: Now, peer: PeerId, local: SocketAddrV4) {
        if self
            .peer(peer)
            .is_some_and(|p| p.phase == Phase::Connecting)
        {
            self.start_greeting(now, peer, local);
        }
    }

    /// A TCP connect the session asked for failed.
    pub fn handle_connect_failed(&mut self, now: Now, peer: PeerId, error: &std::io::Error) {
        let Some(p) = self.peer(peer) else {
            return;
        };
        let who = p.label.clone();
        let reason = if error.kind() == std::io::ErrorKind::ConnectionRefused {
            DropReason::Refused
        } else {
            DropReason::ConnectFailed(error.kind())
        };
        let text = match &self.kind {
            Kind::Client(_) => match reason {
                DropReason::Refused => format!(
                    "no VRPN server is listening on {who} (connection refused); will keep \
                     retrying every {:?}",
                    self.limits.retry_interval
                ),
                _ => format!("cannot connect to {who}: {error}; will keep retrying"),
            },
            _ => format!(
                "cannot call back client at {who}: {error} (a firewall on the client may block \
                 the call-back; the client can use the tcp:// name form)"
            ),
        };
        self.drop_peer(now, peer, reason, text);
    }

    /// Where the next bytes read from `peer`'s TCP socket go (empty: read nothing now).
    pub fn rx_spare(&mut self, peer: PeerId) -> &mut [u8] {
        let budget = self.limits.max_messages_per_peer_per_loop;
        match self.peer_mut(peer) {
            // Over its budget for this pass, a peer gets no more reads until the next.
            Some(p) if p.budget < budget => p.rx_spare(),
            _ => &mut [],
        }
    }

    /// `n` bytes were read into [`rx_spare`](Self::rx_spare).
    pub fn handle_tcp_data(&mut self, peer: PeerId, n: usize) {
        if let Some(p) = self.peer_mut(peer) {
            p.rx_commit(n);
            self.input_pending = true;
        }
    }

    /// Copies bytes read from `peer` into the session; returns how many it took (it takes no
    /// more than it can buffer: feed the rest after draining deliveries).
    pub fn handle_tcp(&mut self, peer: PeerId, bytes: &[u8]) -> usize {
        let spare = self.rx_spare(peer);
        let n = spare.len().min(bytes.len());
        spare[..n].copy_from_slice(&bytes[..n]);
        self.handle_tcp_data(peer, n);
        n
    }

    /// The peer closed its TCP connection (`None`) or the socket failed.
    pub fn handle_closed(&mut self, now: Now, peer: PeerId, error: Option<&std::io::Error>) {
        let Some(p) = self.peer(peer) else {
            return;
        };
        let who = p.label.clone();
        let greeting = p.phase != Phase::Connected;
        let (text, reason) = match error {
            None if greeting => (
                format!("{who} closed the connection"),
                DropReason::ClosedBeforeGreeting,
            ),
            None => (format!("{who} closed the connection"), DropReason::Closed),
            Some(e) => (
                format!("connection to {who} failed: {e}"),
                DropReason::ReadFailed(e.kind()),
            ),
        };
        let text = if greeting && matches!(self.kind, Kind::Client(_)) {
            format!(
                "{who} accepted the connection and closed it before the VRPN greeting: is a \
                 VRPN server listening on that port? (will keep retrying every {:?})",
                self.limits.retry_interval
            )
        } else {
            text
        };
        self.drop_peer(now, peer, reason, text);
    }

    /// Sending to `peer` failed.
    pub fn handle_send_failed(&mut self, now: Now, peer: PeerId, error: &std::io::Error) {
        let Some(p) = self.peer(peer) else {
            return;
        };
        let text = format!("sending to {} failed: {error}", p.label);
        self.drop_peer(now, peer, DropReason::SendFailed(error.kind()), text);
    }

    /// Whether the session takes TCP bytes from `peer` now.
    pub fn wants_tcp(&self, peer: PeerId) -> bool {
        self.peer(peer).is_some_and(|p| {
            p.phase != Phase::Connecting && p.budget < self.limits.max_messages_per_peer_per_loop
        })
    }

    // ------------------------------------------------------------------ UDP

    /// Our UDP socket for `peer` is bound at `port` (`None`: the bind failed; the peer is
    /// served over TCP only).
    pub fn handle_udp_bound(&mut self, now: Now, peer: PeerId, port: Option<u16>) {
        if self
            .peer(peer)
            .is_some_and(|p| p.phase == Phase::Describing)
        {
            self.finish_handshake(now, peer, port);
        }
    }

    /// The outbound UDP socket to `peer`'s announced address opened (or not).
    pub fn handle_udp_out(&mut self, now: Now, peer: PeerId, ok: bool) {
        let hold = self.limits.udp_after_descriptions;
        if let Some(p) = self.peer_mut(peer) {
            p.udp_ready = ok;
            if ok {
                p.udp_tx.allocate();
            }
            p.hold_udp(now.mono, hold);
        }
        self.timeouts_changed();
    }

    /// Where datagrams received for `peer` go, when the session can take more now.
    pub fn udp_inbox(&mut self, peer: PeerId) -> Option<&mut DatagramInbox> {
        let budget = self.limits.max_messages_per_peer_per_loop;
        let p = self.peer_mut(peer)?;
        if p.phase != Phase::Connected || p.budget >= budget {
            return None;
        }
        p.udp_rx.as_mut().filter(|i| i.is_drained())
    }

    /// Whether [`udp_inbox`](Self::udp_inbox) would take datagrams now.
    pub fn wants_udp(&self, peer: PeerId) -> bool {
        self.peer(peer).is_some_and(|p| {
            p.phase == Phase::Connected
                && p.budget < self.limits.max_messages_per_peer_per_loop
                && p.udp_rx.as_ref().is_some_and(DatagramInbox::is_drained)
        })
    }

    /// Bytes or datagrams were put into a peer's buffers directly (the shell's
    /// [`udp_inbox`](Self::udp_inbox) fast path): walk them.
    #[inline]
    pub(crate) fn note_input(&mut self) {
        self.input_pending = true;
    }

    /// `count` datagrams were received into [`udp_inbox`](Self::udp_inbox).
    pub fn handle_datagrams(&mut self, peer: PeerId, count: usize) {
        if let Some(inbox) = self.peer_mut(peer).and_then(|p| p.udp_rx.as_mut()) {
            inbox.filled(count);
            self.input_pending = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use std::net::Ipv4Addr;
    use std::time::Duration;

    use super::*;
    use crate::proto::Limits;

    fn from(i: u8) -> SocketAddrV4 {
        SocketAddrV4::new(Ipv4Addr::new(127, 0, 1, i), 5000)
    }

    fn connects(s: &mut Session) -> usize {
        std::iter::from_fn(|| s.poll_io())
            .filter(|r| matches!(r, IoRequest::Connect { .. }))
            .count()
    }

    fn closes(s: &mut Session) -> usize {
        std::iter::from_fn(|| s.poll_io())
            .filter(|r| matches!(r, IoRequest::Close { .. }))
            .count()
    }

    #[test]
    fn a_call_back_about_to_complete_is_never_given_up() {
        let limits = Limits {
            max_pending_callbacks: 4,
            ..Limits::default()
        };
        let mut s = Session::server(limits, None);
        let t0 = Now::read();
        for i in 0..4 {
            s.handle_request(t0, from(i), b"127.0.0.1 4000\0");
        }
        assert_eq!(connects(&mut s), 4);
        // Full of young call-backs: the new request waits for its client's next one.
        let soon = t0.plus(CALLBACK_PATIENCE / 2);
        s.handle_request(soon, from(9), b"127.0.0.1 4000\0");
        assert_eq!(closes(&mut s), 0, "a young call-back was given up");
        assert_eq!(s.pending_callbacks(), 4);
        // Once the oldest has hung for longer than the patience, it gives way.
        let late = t0.plus(CALLBACK_PATIENCE + Duration::from_millis(1));
        s.handle_request(late, from(9), b"127.0.0.1 4000\0");
        let io: Vec<IoRequest> = std::iter::from_fn(|| s.poll_io()).collect();
        assert_eq!(
            io.iter()
                .filter(|r| matches!(r, IoRequest::Close { .. }))
                .count(),
            1
        );
        assert!(io.iter().any(|r| matches!(
            r,
            IoRequest::Connect { addr, .. } if *addr == SocketAddrV4::new(*from(9).ip(), 4000)
        )));
        assert_eq!(s.pending_callbacks(), 4);
    }

    #[test]
    fn a_burst_of_every_client_is_called_back_at_once() {
        let mut s = Session::server(Limits::default(), None);
        let t0 = Now::read();
        for i in 0..=254u8 {
            s.handle_request(t0, from(i), b"127.0.0.1 4000\0");
        }
        assert_eq!(connects(&mut s), 255);
        assert!(
            !s.queue
                .iter()
                .any(|d| matches!(d, crate::proto::Delivery::Notice(_))),
            "a notice about a burst of legitimate clients"
        );
    }
}
