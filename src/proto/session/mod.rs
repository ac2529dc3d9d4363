//! A session: every peer of one connection and everything decided about them.
//!
//! # Driving a session
//!
//! The caller (the mio shell in `net/`, or the in-memory pair of the tests) owns the sockets
//! and the clock. Each loop pass it:
//!
//! 1. reports what happened on the sockets: [`handle_accept`](Session::handle_accept),
//!    [`handle_request`](Session::handle_request), [`handle_callback`](Session::handle_callback),
//!    [`handle_connected`](Session::handle_connected), bytes read into
//!    [`rx_spare`](Session::rx_spare) with [`handle_tcp_data`](Session::handle_tcp_data) (or
//!    copied in with [`handle_tcp`](Session::handle_tcp)), datagrams received into
//!    [`udp_inbox`](Session::udp_inbox) with [`handle_datagrams`](Session::handle_datagrams),
//!    [`handle_closed`](Session::handle_closed);
//! 2. calls [`handle_timeout`](Session::handle_timeout) when [`poll_timeout`](Session::poll_timeout)
//!    has passed;
//! 3. carries out every [`poll_io`](Session::poll_io) request and reports its outcome;
//! 4. takes [`poll_delivery`](Session::poll_delivery) until it returns `None`, then reads more
//!    for the peers that [`wants_tcp`](Session::wants_tcp) / [`wants_udp`](Session::wants_udp),
//!    and repeats while reads bring bytes;
//! 5. writes [`tcp_pending`](Session::tcp_pending) / [`udp_front`](Session::udp_front) and
//!    reports what went out.
//!
//! Sending ([`pack`](Session::pack)) and registering names
//! ([`register`](Session::register)) may happen at any time in between.

mod handshake;
mod receive;

use std::collections::VecDeque;
use std::net::{Ipv4Addr, SocketAddrV4};
use std::time::Instant;

use super::buffers::DatagramInbox;
use super::client::{ClientSchedule, Failure};
use super::endpoint::{Channel, Endpoint, LogSink, Phase};
use super::names::{NameLimit, Names};
use super::server::RequestPolicy;
use super::{
    ConnectionEvent, ConnectionState, Delivery, IoRequest, Limits, Notice, PeerId, Severity,
};
use crate::log::replay::Replay;
use crate::time::{Now, TimeVal};
use crate::wire::{self, class, system};

/// What kind of connection a session is.
pub(crate) enum Kind {
    /// The in-process connection: no peers.
    Loopback,
    /// Listens for many peers.
    Server(RequestPolicy),
    /// Reaches one server, forever.
    Client(Box<ClientSchedule>),
    /// Plays a log file through a pseudo-peer in slot 0.
    File(Box<Replay>),
}

/// Makes the incoming log of the N-th peer a server accepts (`vrpn_server -li`).
pub type PeerLogFactory = Box<dyn FnMut(u32) -> Result<LogSink, String>>;

/// Logs a session writes (C++ `.vrpn` format).
#[derive(Default)]
pub(crate) struct Logs {
    /// Everything received (clients: one file across reconnects).
    pub(crate) incoming: Option<LogSink>,
    /// Everything this side packs.
    pub(crate) outgoing: Option<LogSink>,
    /// Server: opens one incoming log per accepted peer.
    pub(crate) per_peer: Option<PeerLogFactory>,
    pub(crate) peers_logged: u32,
    /// A log write failed (reported once).
    pub(crate) failed: bool,
}

/// Names learned from peers may use the id space up to this many ids below the wire limit;
/// the rest stays free for this side's own registrations.
const RESERVED_FOR_LOCAL: usize = 200;

/// Everything one connection decides. See the module documentation for how to drive it.
pub struct Session {
    pub(crate) kind: Kind,
    pub(crate) names: Names,
    pub(crate) peers: Vec<Option<Endpoint>>,
    generation: u32,
    pub(crate) limits: Limits,
    pub(crate) queue: VecDeque<Delivery>,
    pub(crate) io: VecDeque<IoRequest>,
    /// Payload of the last delivered message.
    pub(crate) scratch: Vec<u8>,
    /// Local ids newly learned from peers: to be described to every peer (the C++ echo).
    pub(crate) to_describe: Vec<(bool, i32)>,
    cursor: usize,
    pub(crate) connected: usize,
    reported_state: ConnectionState,
    pub(crate) logs: Logs,
    /// Server: the only interface served (announced in UDP descriptions).
    pub(crate) nic: Option<Ipv4Addr>,
    request: [u8; 64],
    request_len: usize,
    /// Peer names that found no room in the table (reported once per peer).
    pub(crate) names_refused: u64,
    /// A peer whose reliable backlog overflowed while packing, to be dropped.
    backlogged: Option<PeerId>,
}

impl Session {
    fn with_kind(kind: Kind, limits: Limits) -> Session {
        let state = match kind {
            Kind::Server(_) => ConnectionState::Listening,
            Kind::Client(_) => ConnectionState::Connecting,
            Kind::Loopback | Kind::File(_) => ConnectionState::Connected,
        };
        Session {
            kind,
            names: Names::new(),
            peers: Vec::new(),
            generation: 0,
            limits,
            queue: VecDeque::with_capacity(64),
            io: VecDeque::with_capacity(16),
            scratch: vec![0; wire::MAX_TCP_PADDED_PAYLOAD],
            to_describe: Vec::with_capacity(16),
            cursor: 0,
            connected: 0,
            reported_state: state,
            logs: Logs::default(),
            nic: None,
            request: [0; 64],
            request_len: 0,
            names_refused: 0,
            backlogged: None,
        }
    }

    /// The in-process connection: no peers, everything packed goes to local handlers only.
    pub fn loopback(limits: Limits) -> Session {
        Session::with_kind(Kind::Loopback, limits)
    }

    /// A server; `nic` is the one interface it serves, if any.
    pub fn server(limits: Limits, nic: Option<Ipv4Addr>) -> Session {
        let mut s = Session::with_kind(Kind::Server(RequestPolicy::new()), limits);
        s.nic = nic;
        s
    }

    /// A client of the server at `server` (`host` is the name the user gave, for messages).
    /// On the default path, `listen` is where the server should call back; `None` selects the
    /// TCP-only path. The first attempt is due at once.
    pub fn client(
        server: SocketAddrV4,
        host: &str,
        listen: Option<SocketAddrV4>,
        limits: Limits,
        now: Now,
    ) -> Session {
        let tcp_only = listen.is_none();
        let sched = ClientSchedule::new(server, host, tcp_only, listen, now.mono);
        let mut s = Session::with_kind(Kind::Client(Box::new(sched)), limits);
        if let Some(l) = listen {
            s.request_len =
                wire::lob::encode_request(&mut s.request, &l.ip().to_string(), l.port());
        }
        s
    }

    /// A replay of a log file, its entries fed through the same translation as a live peer's
    /// messages. `label` names the file in messages.
    pub fn file(replay: Replay, label: &str, limits: Limits) -> Session {
        let mut s = Session::with_kind(Kind::File(Box::new(replay)), limits);
        let id = s.alloc_peer(true, SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0));
        let ep = s.peer_mut(id).expect("just made");
        ep.phase = Phase::Connected;
        ep.label = format!("file:{label}");
        ep.rx = None;
        s
    }

    // ------------------------------------------------------------------ peers

    fn alloc_peer(&mut self, tcp_only: bool, addr: SocketAddrV4) -> PeerId {
        let slot = match self.peers.iter().position(Option::is_none) {
            Some(s) => s,
            None => {
                self.peers.push(None);
                self.peers.len() - 1
            }
        };
        self.generation = self.generation.wrapping_add(1);
        let id = PeerId {
            slot,
            generation: self.generation,
        };
        let mut ep = Endpoint::new(id, tcp_only, addr, self.limits.max_pending_output);
        if let Kind::Client(c) = &self.kind {
            ep.seq_tcp = c.seq.0;
            ep.seq_udp = c.seq.1;
        }
        self.peers[slot] = Some(ep);
        id
    }

    /// The peer `id`, if it still exists.
    pub(crate) fn peer(&self, id: PeerId) -> Option<&Endpoint> {
        self.peers
            .get(id.slot)
            .and_then(Option::as_ref)
            .filter(|p| p.id == id)
    }

    pub(crate) fn peer_mut(&mut self, id: PeerId) -> Option<&mut Endpoint> {
        self.peers
            .get_mut(id.slot)
            .and_then(Option::as_mut)
            .filter(|p| p.id == id)
    }

    /// The peer in `slot`, if any.
    pub fn peer_at(&self, slot: usize) -> Option<PeerId> {
        self.peers.get(slot).and_then(Option::as_ref).map(|p| p.id)
    }

    /// Number of peer slots (some may be empty).
    pub fn slots(&self) -> usize {
        self.peers.len()
    }

    fn is_replay(&self) -> bool {
        matches!(self.kind, Kind::File(_))
    }

    /// Peers with a TCP connection (greeting or connected): what the connection limit counts.
    fn live_peers(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.phase != Phase::Connecting)
            .count()
    }

    /// Call-backs in progress.
    fn pending_callbacks(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.callback && p.phase == Phase::Connecting)
            .count()
    }

    // ------------------------------------------------------------------ notices and state

    pub(crate) fn notice(&mut self, severity: Severity, text: String) {
        self.queue
            .push_back(Delivery::Notice(Notice { severity, text }));
    }

    /// What the connection is doing now.
    pub fn state(&self) -> ConnectionState {
        match &self.kind {
            Kind::Loopback | Kind::File(_) => ConnectionState::Connected,
            Kind::Server(_) if self.connected > 0 => ConnectionState::Connected,
            Kind::Server(_) => ConnectionState::Listening,
            Kind::Client(_) if self.connected > 0 => ConnectionState::Connected,
            Kind::Client(c) if c.ever_connected => ConnectionState::Reconnecting,
            Kind::Client(_) => ConnectionState::Connecting,
        }
    }

    /// Queues a state-change delivery when the state differs from the last one reported.
    pub(crate) fn note_state(&mut self) {
        let now = self.state();
        if now != self.reported_state {
            self.reported_state = now;
            self.queue.push_back(Delivery::State(now));
        }
    }

    // ------------------------------------------------------------------ server inputs

    /// Server: the TCP listener accepted a client (the TCP-only path: anything accepted on the
    /// TCP port is TCP-only, as in C++). `None`: refused (the shell closes the socket).
    pub fn handle_accept(
        &mut self,
        now: Now,
        from: SocketAddrV4,
        local: SocketAddrV4,
    ) -> Option<PeerId> {
        if self.live_peers() >= self.limits.max_connections {
            let text = format!(
                "refused TCP client {from}: {} clients already connected (limit)",
                self.limits.max_connections
            );
            self.notice(Severity::Warning, text);
            return None;
        }
        let id = self.alloc_peer(true, from);
        self.open_peer_log(id);
        self.start_greeting(now, id, local);
        Some(id)
    }

    /// Server: a datagram arrived on the server port from `from` — a connection request.
    pub fn handle_request(&mut self, now: Now, from: SocketAddrV4, datagram: &[u8]) {
        let limits = self.limits;
        let req = match wire::lob::parse_request(datagram) {
            Ok(r) => r,
            Err(e) => {
                let first = match &mut self.kind {
                    Kind::Server(p) => p.count(super::server::Ignored::Malformed),
                    _ => false,
                };
                if first {
                    let text = format!("ignored a bad connection request from {from}: {e}");
                    self.notice(Severity::Warning, text);
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
        let (pending, live) = (self.pending_callbacks(), self.live_peers());
        let Kind::Server(policy) = &mut self.kind else {
            return;
        };
        match policy.decide(now.mono, target, busy, pending, live, &limits) {
            super::server::Decision::CallBack(addr) => {
                let id = self.alloc_peer(false, addr);
                let ep = self.peer_mut(id).expect("just made");
                ep.callback = true;
                ep.deadline = Some(now.mono + limits.connect_timeout);
                self.open_peer_log(id);
                self.io.push_back(IoRequest::Connect { peer: id, addr });
            }
            super::server::Decision::Ignore(_) => {}
        }
        self.request_summary(now.mono);
    }

    fn request_summary(&mut self, now: Instant) {
        if let Kind::Server(p) = &mut self.kind {
            if let Some(text) = p.summary(now) {
                self.notice(Severity::Warning, text);
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
            Err(e) => self.notice(Severity::Error, format!("cannot open incoming log: {e}")),
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
        let limits = self.limits;
        let Kind::Client(c) = &mut self.kind else {
            return;
        };
        if c.failed(now.mono, Failure::Unreachable, &limits) {
            let server = c.server_text();
            self.notice(
                Severity::Warning,
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
        let failure = if error.kind() == std::io::ErrorKind::ConnectionRefused {
            Failure::Refused
        } else {
            Failure::Other(error.to_string())
        };
        let text = match &self.kind {
            Kind::Client(_) => match &failure {
                Failure::Refused => format!(
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
        self.drop_peer(now, peer, text, Some(failure));
    }

    /// Where the next bytes read from `peer`'s TCP socket go (empty: read nothing now).
    pub fn rx_spare(&mut self, peer: PeerId) -> &mut [u8] {
        match self.peer_mut(peer) {
            Some(p) => p.rx_spare(),
            None => &mut [],
        }
    }

    /// `n` bytes were read into [`rx_spare`](Self::rx_spare).
    pub fn handle_tcp_data(&mut self, _now: Now, peer: PeerId, n: usize) {
        if let Some(p) = self.peer_mut(peer) {
            p.rx_commit(n);
        }
    }

    /// Copies bytes read from `peer` into the session; returns how many it took (it takes no
    /// more than it can buffer: feed the rest after draining deliveries).
    pub fn handle_tcp(&mut self, now: Now, peer: PeerId, bytes: &[u8]) -> usize {
        let spare = self.rx_spare(peer);
        let n = spare.len().min(bytes.len());
        spare[..n].copy_from_slice(&bytes[..n]);
        self.handle_tcp_data(now, peer, n);
        n
    }

    /// The peer closed its TCP connection (`None`) or the socket failed.
    pub fn handle_closed(&mut self, now: Now, peer: PeerId, error: Option<&std::io::Error>) {
        let Some(p) = self.peer(peer) else {
            return;
        };
        let who = p.label.clone();
        let greeting = p.phase != Phase::Connected;
        let (text, failure) = match error {
            None => (
                format!("{who} closed the connection"),
                Failure::ClosedEarly("closed the connection".into()),
            ),
            Some(e) => (
                format!("connection to {who} failed: {e}"),
                Failure::ClosedEarly(e.to_string()),
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
        self.drop_peer(now, peer, text, Some(failure));
    }

    /// Sending to `peer` failed.
    pub fn handle_send_failed(&mut self, now: Now, peer: PeerId, error: &std::io::Error) {
        let Some(p) = self.peer(peer) else {
            return;
        };
        let text = format!("sending to {} failed: {error}", p.label);
        self.drop_peer(now, peer, text, Some(Failure::Other(error.to_string())));
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
    pub fn handle_udp_out(&mut self, _now: Now, peer: PeerId, ok: bool) {
        if let Some(p) = self.peer_mut(peer) {
            p.udp_ready = ok;
        }
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

    /// `count` datagrams were received into [`udp_inbox`](Self::udp_inbox).
    pub fn handle_datagrams(&mut self, _now: Now, peer: PeerId, count: usize) {
        if let Some(inbox) = self.peer_mut(peer).and_then(|p| p.udp_rx.as_mut()) {
            inbox.filled(count);
        }
    }

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

    /// The datagram from [`udp_front`](Self::udp_front) went out (or was lost).
    pub fn udp_sent(&mut self, peer: PeerId) {
        if let Some(p) = self.peer_mut(peer) {
            p.udp_tx.pop_front();
        }
    }

    /// The earliest time [`handle_timeout`](Self::handle_timeout) has work to do.
    pub fn poll_timeout(&self) -> Option<Instant> {
        let mut d: Option<Instant> = None;
        let mut at = |t: Instant| d = Some(d.map_or(t, |x| x.min(t)));
        for p in self.peers.iter().flatten() {
            if let Some(t) = p.deadline {
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
        for slot in 0..self.peers.len() {
            let Some(p) = self.peers[slot].as_ref() else {
                continue;
            };
            if !p.deadline.is_some_and(|d| now.mono >= d) {
                continue;
            }
            let (id, who, phase) = (p.id, p.label.clone(), p.phase);
            let is_client = matches!(self.kind, Kind::Client(_));
            let (text, failure) = match phase {
                Phase::Connecting => (
                    format!("TCP connection to {who} timed out"),
                    Failure::ConnectTimeout,
                ),
                _ if is_client => (
                    format!(
                        "{who} accepted the connection but sent no VRPN greeting within {:?}: \
                         is a VRPN server (and not another program) listening there? (will keep \
                         retrying every {:?})",
                        self.limits.handshake_timeout, self.limits.retry_interval
                    ),
                    Failure::Silent,
                ),
                _ => (
                    format!(
                        "dropped {who}: no VRPN greeting within {:?} \
                         (Limits::handshake_timeout)",
                        self.limits.handshake_timeout
                    ),
                    Failure::Silent,
                ),
            };
            self.drop_peer(now, id, text, Some(failure));
        }
        let limits = self.limits;
        let idle = self.peers.iter().flatten().next().is_none();
        match &mut self.kind {
            Kind::Client(c) if idle => {
                let explain = c.no_answer_due(now.mono, &limits).then(|| {
                    let listen = c.listen.map_or_else(|| "?".to_string(), |l| l.to_string());
                    format!(
                        "no answer from the VRPN server at {host}:{port} after {wait:?}: \
                         either no server runs there, or it cannot connect back to this \
                         machine at {listen} (a firewall or NAT). If the server runs, use \
                         DEVICE@tcp://{host}:{port} to connect over TCP only",
                        host = c.host,
                        port = c.server.port(),
                        wait = limits.no_answer_warning
                    )
                });
                let due = now.mono >= c.next_attempt;
                if let Some(text) = explain {
                    self.notice(Severity::Warning, text);
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
        let limits = self.limits;
        let Kind::Client(c) = &mut self.kind else {
            return;
        };
        if c.failed(now.mono, Failure::Other(error.to_string()), &limits) {
            let text = format!("cannot send a connection request to {to}: {error}");
            self.notice(Severity::Warning, text);
        }
    }

    /// Starts a new loop pass at `now`: every peer gets its full message budget again, and a
    /// replay's clock advances (C++ model: each pass plays what became due since the last).
    pub fn begin_pass(&mut self, now: Now) {
        for p in self.peers.iter_mut().flatten() {
            p.budget = 0;
        }
        if let Kind::File(r) = &mut self.kind {
            r.tick(now.mono);
        }
    }

    // ------------------------------------------------------------------ names

    /// Registers a sender (`true`) or type name for this side and describes it to every
    /// connected peer when it is new.
    pub fn register(&mut self, now: Now, is_sender: bool, name: &[u8]) -> Result<i32, NameLimit> {
        let (id, new) = self.names.table(is_sender).register(name)?;
        if new {
            self.describe_to_all(now, is_sender, id);
        }
        Ok(id)
    }

    /// The name of a local sender (`true`) or type id, as bytes.
    pub fn name_of(&self, is_sender: bool, id: i32) -> Option<&[u8]> {
        if is_sender {
            self.names.senders.name(id)
        } else {
            self.names.types.name(id)
        }
    }

    /// The local id of a name, if known.
    pub fn id_of(&self, is_sender: bool, name: &[u8]) -> Option<i32> {
        if is_sender {
            self.names.senders.get(name)
        } else {
            self.names.types.get(name)
        }
    }

    /// Sends one description to every connected peer (and the outgoing log).
    pub(crate) fn describe_to_all(&mut self, now: Now, is_sender: bool, id: i32) {
        let names = &self.names;
        let name = if is_sender {
            names.senders.name(id)
        } else {
            names.types.name(id)
        };
        let Some(name) = name else {
            return;
        };
        let mut buf = [0u8; 128];
        let n = system::encode_description(&mut buf, name);
        let t = if is_sender {
            system::SENDER_DESCRIPTION
        } else {
            system::TYPE_DESCRIPTION
        };
        let replay = self.is_replay();
        for p in self.peers.iter_mut().flatten() {
            if !(replay && p.id.slot == 0) {
                let _ = p.pack(now.wall, id, t, &buf[..n], class::RELIABLE);
            }
        }
        self.log_outgoing(t, id, now.wall, &buf[..n]);
    }

    fn is_replay_peer(&self, p: &Endpoint) -> bool {
        matches!(self.kind, Kind::File(_)) && p.id.slot == 0
    }

    /// Describes names that peers taught us to every connected peer (the C++ echo).
    pub(crate) fn describe_new_names(&mut self, now: Now) {
        let list = std::mem::take(&mut self.to_describe);
        for &(is_sender, id) in &list {
            self.describe_to_all(now, is_sender, id);
        }
        self.to_describe = list;
        self.to_describe.clear();
    }

    // ------------------------------------------------------------------ sending

    /// Queues a message to every connected peer. Returns true when a peer's reliable backlog
    /// overflowed: the caller then calls [`drop_backlogged`](Self::drop_backlogged) with the
    /// time (the only path here that needs it). A peer that falls behind sheds unreliable
    /// messages first, with a notice.
    pub fn pack(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> bool {
        self.log_outgoing(type_id, sender, time, payload);
        let mut shedding = None;
        let replay = self.is_replay();
        for p in self.peers.iter_mut().flatten() {
            if replay && p.id.slot == 0 {
                continue;
            }
            match p.pack(time, sender, type_id, payload, class_of_service) {
                Err(_) => {
                    if self.backlogged.is_none() {
                        self.backlogged = Some(p.id);
                    }
                }
                // Say so once per peer, when it first sheds unreliable traffic.
                Ok(Channel::Discarded) if p.unreliable_dropped == 1 => {
                    shedding = Some((p.label.clone(), p.tx.pending_len()));
                }
                Ok(_) => {}
            }
        }
        if let Some((who, pending)) = shedding {
            self.notice(
                Severity::Warning,
                format!(
                    "{who} is falling behind ({pending} bytes of output pending): dropping \
                     its unreliable messages while the backlog exceeds half of \
                     Limits::max_pending_output"
                ),
            );
        }
        self.backlogged.is_some()
    }

    /// Drops the peer whose reliable backlog overflowed in [`pack`](Self::pack).
    pub fn drop_backlogged(&mut self, now: Now) {
        let Some(id) = self.backlogged.take() else {
            return;
        };
        let limit = self.limits.max_pending_output;
        let who = self.peer(id).map(|p| p.label.clone()).unwrap_or_default();
        self.drop_peer(
            now,
            id,
            format!("{who} is not reading: more than {limit} bytes of reliable output pending"),
            None,
        );
    }

    /// Reliable bytes queued for peers and not yet written.
    pub fn pending_output(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .map(|p| p.tx.pending_len())
            .sum()
    }

    // ------------------------------------------------------------------ drops

    /// Forgets a peer: releases the names it held, asks the shell to close its sockets, fires
    /// the dropped events if it had connected, and (client) schedules the next attempt.
    pub(crate) fn drop_peer(
        &mut self,
        now: Now,
        id: PeerId,
        reason: String,
        failure: Option<Failure>,
    ) {
        let Some(mut p) = self
            .peers
            .get_mut(id.slot)
            .and_then(|s| s.take_if(|p| p.id == id))
        else {
            return;
        };
        let was_connected = p.phase == Phase::Connected;
        p.senders
            .held
            .drain(|local| self.names.senders.release(local));
        p.types.held.drain(|local| self.names.types.release(local));
        self.io.push_back(IoRequest::Close { peer: id });
        let limits = self.limits;
        let is_client = matches!(self.kind, Kind::Client(_));
        let mut explain = true;
        if let Kind::Client(c) = &mut self.kind {
            c.seq = (p.seq_tcp, p.seq_udp);
            if was_connected {
                c.dropped(now.mono, p.connected_at.unwrap_or(now.mono), &limits);
            } else {
                let failure = failure.unwrap_or(Failure::Other(reason.clone()));
                explain = c.failed(now.mono, failure, &limits);
            }
        }
        drop(p);
        if is_client && was_connected {
            self.log_outgoing(system::DISCONNECT, 0, now.wall, &[]);
        }
        let severity = if is_client {
            Severity::Warning
        } else {
            Severity::Info
        };
        if explain {
            let text = if is_client && was_connected {
                format!("{reason}; reconnecting")
            } else {
                reason
            };
            self.notice(severity, text);
        }
        if was_connected {
            self.connected -= 1;
            self.queue
                .push_back(Delivery::Event(ConnectionEvent::DroppedConnection));
            if self.connected == 0 {
                self.queue
                    .push_back(Delivery::Event(ConnectionEvent::DroppedLastConnection));
            }
        }
        self.note_state();
    }

    // ------------------------------------------------------------------ logging

    pub(crate) fn log_outgoing(
        &mut self,
        type_id: i32,
        sender: i32,
        time: TimeVal,
        payload: &[u8],
    ) {
        if let Some(w) = self.logs.outgoing.as_mut() {
            if let Err(e) = w.log_message(type_id, sender, time, payload) {
                self.log_error(e.to_string());
            }
        }
    }

    pub(crate) fn log_error(&mut self, e: String) {
        if !self.logs.failed {
            self.logs.failed = true;
            self.notice(Severity::Error, format!("logging failed: {e}"));
        }
    }

    /// Starts logging what this side receives: into `sink` for a client (one file across
    /// reconnects), or through `per_peer` for a server (one file per accepted client).
    pub fn set_incoming_log(&mut self, sink: Option<LogSink>, per_peer: Option<PeerLogFactory>) {
        self.logs.incoming = sink;
        self.logs.per_peer = per_peer;
    }

    /// Starts logging everything this side packs.
    pub fn set_outgoing_log(&mut self, sink: LogSink) {
        self.logs.outgoing = Some(sink);
    }

    /// Writes a bounded amount of buffered log data (called every pass; never stalls long).
    pub fn flush_logs_some(&mut self, max_bytes: usize) {
        let mut err = None;
        for w in self.log_sinks() {
            if w.pending() > 0 {
                if let Err(e) = w.flush_some(max_bytes) {
                    err = Some(e.to_string());
                }
            }
        }
        if let Some(e) = err {
            self.log_error(e);
        }
    }

    fn log_sinks(&mut self) -> impl Iterator<Item = &mut LogSink> {
        self.logs
            .incoming
            .iter_mut()
            .chain(self.logs.outgoing.iter_mut())
            .chain(
                self.peers
                    .iter_mut()
                    .flatten()
                    .filter_map(|p| p.log_in.as_mut()),
            )
    }

    /// Writes every buffered log byte.
    pub fn flush_logs_all(&mut self) -> Result<(), String> {
        for w in self.log_sinks() {
            w.flush_all().map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// Ends logging: a DISCONNECT entry closes the outgoing log (as C++ at shutdown).
    pub fn close_logs(&mut self, now: Now) -> Result<(), String> {
        let client = matches!(self.kind, Kind::Client(_));
        if self.logs.outgoing.is_some() && !client || self.connected > 0 {
            self.log_outgoing(system::DISCONNECT, 0, now.wall, &[]);
        }
        let r = self.flush_logs_all();
        self.logs.outgoing = None;
        self.logs.incoming = None;
        self.logs.per_peer = None;
        for p in self.peers.iter_mut().flatten() {
            p.log_in = None;
        }
        r
    }

    // ------------------------------------------------------------------ queries

    /// Number of peers that completed the handshake.
    pub fn connected_peers(&self) -> usize {
        self.connected
    }

    /// Address and VRPN version of each connected peer.
    pub fn peer_descriptions(&self) -> Vec<(String, Option<String>)> {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.phase == Phase::Connected && !self.is_replay_peer(p))
            .map(|p| (p.label.clone(), p.peer_version.clone()))
            .collect()
    }

    /// The sender names connected peers offer: those in their own tables, not the echoes of
    /// names this side described to them, nor `VRPN Control` (sender 0 of every connection).
    pub fn peer_sender_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for p in self.peers.iter().flatten() {
            for local in p.senders.locals() {
                if local == 0 || !p.offered.contains(local) {
                    continue;
                }
                if let Some(n) = self.names.senders.name(local) {
                    let n = String::from_utf8_lossy(n);
                    if !out.iter().any(|o| *o == n) {
                        out.push(n.into_owned());
                    }
                }
            }
        }
        out
    }

    /// True when every connected peer has described its whole sender table (so
    /// [`peer_sender_names`](Self::peer_sender_names) is complete).
    pub fn peer_senders_complete(&self) -> bool {
        self.peers
            .iter()
            .flatten()
            .all(|p| p.phase != Phase::Connected || p.senders_complete)
            && self.connected > 0
    }

    /// The replay, for control calls.
    pub fn replay_mut(&mut self) -> Option<&mut Replay> {
        match &mut self.kind {
            Kind::File(r) => Some(r),
            _ => None,
        }
    }

    /// Whether deliveries are waiting (after input that closed a peer, say).
    pub fn has_deliveries(&self) -> bool {
        !self.queue.is_empty() || !self.to_describe.is_empty()
    }

    /// Whether this is a client (whose state changes are worth reporting).
    pub fn is_client(&self) -> bool {
        matches!(self.kind, Kind::Client(_))
    }

    /// The payload of the last [`Delivery::Message`].
    pub fn payload(&self, len: usize) -> &[u8] {
        &self.scratch[..len]
    }

    /// Takes the scratch buffer (to dispatch from it without borrowing the session); give it
    /// back with [`restore_scratch`](Self::restore_scratch). Allocation-free.
    pub fn take_scratch(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.scratch)
    }

    /// Returns the buffer [`take_scratch`](Self::take_scratch) lent.
    pub fn restore_scratch(&mut self, buf: Vec<u8>) {
        self.scratch = buf;
    }
}
