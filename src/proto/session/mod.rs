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
mod input;
mod logs;
mod output;
mod receive;
mod remote_logs;
mod send;

pub use remote_logs::RemoteLogRequest;
pub(crate) use remote_logs::RequestedLogs;

use std::collections::VecDeque;
use std::net::{Ipv4Addr, SocketAddrV4};
use std::time::Instant;

use super::buffers::PayloadBuf;
use super::client::ClientSchedule;
use super::endpoint::{Endpoint, LogSink, Phase};
use super::names::Names;
use super::server::RequestPolicy;
use super::{
    ConnectionState, Delivery, DropReason, IoRequest, Limits, Notice, NoticeKind, PeerId, Severity,
};
use crate::log::replay::Replay;
use crate::log::LogError;
use crate::time::Now;
use crate::wire::{self};

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
pub type PeerLogFactory = Box<dyn FnMut(u32) -> Result<LogSink, LogError>>;

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
    /// Some log was ever opened (lets a pass without logs skip the flush walk).
    pub(crate) any: bool,
    /// Server: where logs that peers ask for are written (`None`: such requests are refused).
    pub(crate) remote_folder: Option<crate::log::folder::LogFolder>,
}

/// The local ids of the clock-synchronisation names, registered when the first peer connects
/// (after the handshake's descriptions, so the handshake stays byte-for-byte C++'s).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ClockIds {
    pub(crate) sender: i32,
    pub(crate) query: i32,
    pub(crate) reply: i32,
}

impl ClockIds {
    #[inline]
    pub(crate) fn is_clock_type(&self, t: i32) -> bool {
        t == self.query || t == self.reply
    }
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
    pub(crate) scratch: PayloadBuf,
    /// A message being packed, encoded once for all peers (empty for the in-process
    /// connection, which has none).
    pub(crate) encoded: Vec<u8>,
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
    /// Input arrived (or a peer's budget was renewed) since a poll last found nothing to
    /// deliver: lets [`poll_delivery`](Session::poll_delivery) answer "nothing" without a walk.
    pub(crate) input_pending: bool,
    /// Why the peer whose message is being handled must be dropped (and the words for it):
    /// set by the (rare) refusals of message handling, taken at once by the receive walk.
    pub(crate) refusal: Option<(DropReason, String)>,
    /// [`poll_timeout`](Session::poll_timeout)'s answer while nothing that sets a deadline has
    /// changed (`None`: work it out again). Every pass asks; few passes change it.
    pub(crate) timeout_cache: std::cell::Cell<Option<Option<Instant>>>,
    /// Clock-synchronisation names, once registered.
    pub(crate) clock_ids: Option<ClockIds>,
    /// A peer described the clock-synchronisation names (register ours before its queries).
    pub(crate) clock_names_seen: bool,
    /// Client: the logs to ask the server for at the next connect.
    pub(crate) remote_log_request: Option<RemoteLogRequest>,
    /// Replay: a jump is under way; the user messages it passes over are not delivered.
    pub(crate) replay_skipping: bool,
    /// The peer whose message [`poll_delivery`](Self::poll_delivery) returned last (`None`
    /// for a delivery of another kind or from the queue): where a reply goes.
    pub(crate) delivering_from: Option<PeerId>,
}

impl Session {
    fn with_kind(kind: Kind, limits: Limits) -> Session {
        let state = match kind {
            Kind::Server(_) => ConnectionState::Listening,
            Kind::Client(_) => ConnectionState::Connecting,
            Kind::Loopback | Kind::File(_) => ConnectionState::Connected,
        };
        let encoded = match kind {
            Kind::Loopback => Vec::new(),
            _ => vec![0; wire::header::HEADER_LEN + wire::MAX_TCP_PADDED_PAYLOAD],
        };
        Session {
            kind,
            names: Names::new(),
            peers: Vec::new(),
            generation: 0,
            limits,
            queue: VecDeque::with_capacity(64),
            io: VecDeque::with_capacity(16),
            scratch: PayloadBuf::new(wire::MAX_TCP_PADDED_PAYLOAD),
            encoded,
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
            input_pending: true,
            refusal: None,
            timeout_cache: std::cell::Cell::new(None),
            clock_ids: None,
            clock_names_seen: false,
            remote_log_request: None,
            replay_skipping: false,
            delivering_from: None,
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

    /// Something that sets a deadline changed: [`poll_timeout`](Self::poll_timeout) works it
    /// out again.
    #[inline]
    pub(crate) fn timeouts_changed(&self) {
        self.timeout_cache.set(None);
    }

    pub(super) fn alloc_peer(&mut self, tcp_only: bool, addr: SocketAddrV4) -> PeerId {
        self.timeouts_changed();
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
            // A client's one peer is its server, named as the user named it: on the default
            // path its TCP connection comes from the server's call-back port, which would
            // only confuse a reader.
            ep.label = c.server_text();
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

    /// The replay's pseudo-peer (slot 0 of a replay session) is not a peer to send to or list.
    pub(super) fn is_replay_peer(&self, p: &Endpoint) -> bool {
        matches!(self.kind, Kind::File(_)) && p.id.slot == 0
    }

    pub(super) fn is_replay(&self) -> bool {
        matches!(self.kind, Kind::File(_))
    }

    /// Peers with a TCP connection (greeting or connected): what the connection limit counts.
    pub(super) fn live_peers(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.phase != Phase::Connecting)
            .count()
    }

    /// Call-backs in progress.
    pub(super) fn pending_callbacks(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.callback && p.phase == Phase::Connecting)
            .count()
    }

    // ------------------------------------------------------------------ notices and state

    pub(crate) fn notice(&mut self, severity: Severity, kind: NoticeKind, text: String) {
        self.queue
            .push_back(Delivery::Notice(Notice::new(severity, kind, text)));
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
    /// names this side described to them, nor the protocol's own senders (`VRPN Control`,
    /// sender 0 of every connection, and the clock synchronisation's): exactly the names
    /// [`Delivery::PeerSender`] reported.
    pub fn peer_sender_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for p in self.peers.iter().flatten() {
            for local in p.senders.locals() {
                if !p.offered.contains(local) {
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

    /// The peer the message being delivered came from (see [`pack_to`](Self::pack_to)).
    pub fn delivering_from(&self) -> Option<PeerId> {
        self.delivering_from
    }

    /// The limits this session was made with.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Whether a peer used up its message budget in this pass, so that input may be left
    /// for the next one (it is due at once).
    pub fn input_left_over(&self) -> bool {
        let budget = self.limits.max_messages_per_peer_per_loop;
        self.peers.iter().flatten().any(|p| p.budget >= budget)
    }

    /// Replay: while set, the user messages that come due are consumed without being
    /// delivered (a jump); it ends by itself where nothing more is due.
    pub fn set_replay_skipping(&mut self, skip: bool) {
        self.replay_skipping = skip && self.is_replay();
    }

    /// Whether deliveries are waiting (after input that closed a peer, say).
    pub fn has_deliveries(&self) -> bool {
        !self.queue.is_empty() || !self.to_describe.is_empty()
    }

    /// Whether I/O requests wait for [`poll_io`](Self::poll_io).
    #[inline]
    pub fn has_io(&self) -> bool {
        !self.io.is_empty()
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
    pub fn take_scratch(&mut self) -> PayloadBuf {
        std::mem::take(&mut self.scratch)
    }

    /// Returns the buffer [`take_scratch`](Self::take_scratch) lent.
    pub fn restore_scratch(&mut self, buf: PayloadBuf) {
        self.scratch = buf;
    }
}
