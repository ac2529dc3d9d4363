//! The VRPN protocol without sockets and without a clock.
//!
//! A [`Session`] is everything one connection decides: the cookie exchange
//! and version check, descriptions and id translation, the UDP channel negotiation, the
//! sending policy (channel choice, shedding, backlog limits), fairness between peers, drops,
//! the client's connect-and-retry schedule, the server's connection-request policy, log hooks
//! and log replay. It is fed bytes and the time ([`Now`](crate::time::Now)) by its caller and
//! hands back bytes to write, [`IoRequest`]s for the shell to carry out (connect, bind, close),
//! [`Delivery`]s for the dispatcher, and the next deadline — the shape of quinn-proto's
//! `handle_*` / `poll_transmit` / `poll_timeout` / `poll`.
//!
//! Nothing in this module reads a clock, touches a socket or calls user code, which is what
//! lets `tests/pair.rs` run a client and a server through every time-out on virtual time.

pub mod buffers;
pub mod client;
pub mod clock;
pub mod endpoint;
pub mod names;
pub mod notice;
pub mod ping;
pub mod server;
pub mod session;

use std::net::SocketAddrV4;
use std::time::Duration;

use crate::time::TimeVal;
use crate::wire;

pub use notice::{DropReason, NameKind, Notice, NoticeKind, Severity};
pub use session::{RemoteLogRequest, Session};

/// What a connection is doing now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConnectionState {
    /// Client: trying to reach the server for the first time.
    Connecting,
    /// Client: connected to the server. Server: at least one peer connected. Loopback and
    /// replay: always.
    Connected,
    /// Client: was connected, lost the server (the change to this state is the drop), and
    /// keeps trying.
    Reconnecting,
    /// Server: listening, no peer connected.
    Listening,
}

/// Local connection events (sent as messages of the four `VRPN_Connection_*` types).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConnectionEvent {
    /// The first peer completed its handshake.
    GotFirstConnection,
    /// A peer completed its handshake.
    GotConnection,
    /// A connected peer was lost.
    DroppedConnection,
    /// The last connected peer was lost.
    DroppedLastConnection,
}

impl ConnectionEvent {
    /// The local type id of the event's message (the four types every connection registers
    /// first).
    pub fn type_id(self) -> i32 {
        match self {
            ConnectionEvent::GotFirstConnection => 0,
            ConnectionEvent::GotConnection => 1,
            ConnectionEvent::DroppedConnection => 2,
            ConnectionEvent::DroppedLastConnection => 3,
        }
    }
}

/// Limits and timings of a connection. The defaults suit a lab network.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Reliable output that may wait for one peer before the peer is dropped as not reading.
    pub max_pending_output: usize,
    /// Peers a server serves at once (C++: 255). Call-backs still in progress do not count.
    pub max_connections: usize,
    /// Client: time between connection attempts (C++ 07.38 uses 2 s; the paper says 1 s).
    pub retry_interval: Duration,
    /// Client: when to explain that the server does not answer.
    pub no_answer_warning: Duration,
    /// Time allowed for a TCP connect (server call-back or TCP-only client).
    pub connect_timeout: Duration,
    /// Messages taken from one peer in one `mainloop()` pass: every message counts (device
    /// reports, descriptions, clock queries, messages nobody handles), and the rest waits for
    /// the next pass, so no peer can keep a pass (and a server's devices) waiting.
    pub max_messages_per_peer_per_loop: usize,
    /// Time one `mainloop()` pass may spend delivering messages to callbacks before it
    /// returns; what remains is delivered by the next call. Callbacks slower than the data
    /// arrives thus still let `mainloop()` return (after about this time plus two callbacks).
    pub max_pass_time: Duration,
    /// Largest message payload accepted from a peer; a peer that sends a larger one is dropped
    /// with a notice. Default: the C++ receive limit (64008 padded bytes).
    pub max_message_payload: usize,
    /// Sender names, and separately type names, one peer may describe (C++: 2000 each); a peer
    /// describing more is dropped with a notice. What counts is a name new to this side or an
    /// id bound again to another name; a known name described again for an unbound id (as
    /// every session of a log does after a DISCONNECT entry) does not. However many names peers describe, they can
    /// never take the ids this side needs: names learned from peers are freed when the last
    /// peer that described them leaves, and when the table has no room left for a peer's new
    /// name, that name is ignored (its messages are not delivered), not fatal.
    pub max_names_per_peer: usize,
    /// Time a peer has from its TCP connection to the end of the cookie exchange. A peer
    /// that connects and never greets is dropped when it runs out.
    pub handshake_timeout: Duration,
    /// Server: connection requests (UDP) accepted per second, over all sources; the rest are
    /// ignored and counted in a notice at most every few seconds.
    pub max_requests_per_second: u32,
    /// Server: call-back connects in progress at once (default: as many as clients, so that
    /// every client of a burst is called back at once). When a new request finds them all
    /// still connecting, the oldest is given up if it has been connecting for longer than
    /// [`server::CALLBACK_PATIENCE`] (its host may be dropping SYNs); otherwise the request is
    /// ignored and its client asks again.
    pub max_pending_callbacks: usize,
    /// Server: call back the address a connection request names instead of the address it
    /// came from. C++ does this; it lets anyone aim the server's connects at a third host, so
    /// it is off by default. Turn it on only for multi-homed set-ups where a client must be
    /// reached on another interface than the one it asked from (the named address must then be
    /// numeric: the server never resolves host names in its loop).
    pub callback_to_named_address: bool,
    /// Clock synchronisation with each peer (`None`: off). On by default: between two peers
    /// of this crate it makes remote timestamps comparable to the local clock; a C++ peer
    /// never answers, so nothing changes there (it gets one small query a minute).
    pub clock_sync: Option<clock::ClockSyncConfig>,
    /// After a peer's UDP channel opens, and after new names are described to it, its
    /// unreliable messages keep to TCP for this long. A C++ 07.x peer reads its UDP socket
    /// before its TCP stream in each pass and drops, without a word, a message whose type
    /// it has not been told yet, so a report sent by UDP right behind the descriptions sent
    /// by TCP can overtake them and be lost (a C++ client missed the answer to the ping it
    /// sent on connecting). A peer that answers a clock query sent during the hold (a peer of
    /// this crate, with `clock_sync` on) has shown it read the descriptions, and the hold ends
    /// at once. Zero sends by UDP at once.
    pub udp_after_descriptions: Duration,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_pending_output: 4 * 1024 * 1024,
            max_connections: 255,
            retry_interval: Duration::from_secs(1),
            no_answer_warning: Duration::from_secs(3),
            connect_timeout: Duration::from_secs(5),
            max_messages_per_peer_per_loop: 1024,
            max_pass_time: Duration::from_millis(5),
            max_message_payload: wire::MAX_TCP_PADDED_PAYLOAD,
            max_names_per_peer: wire::MAX_IDS,
            handshake_timeout: Duration::from_secs(5),
            max_requests_per_second: 100,
            max_pending_callbacks: 255,
            callback_to_named_address: false,
            clock_sync: Some(clock::ClockSyncConfig::default()),
            udp_after_descriptions: Duration::from_millis(250),
        }
    }
}

/// A peer of a session: its slot and a generation, so a stale id never reaches a new peer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PeerId {
    /// Index in the session's peer table (the shell keeps its sockets at the same index).
    pub slot: usize,
    generation: u32,
}

/// Something the shell must do for the session; its outcome is reported back through the
/// named `Session::handle_*` call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IoRequest {
    /// Open a non-blocking TCP connection to `addr` for `peer` (a server's call-back, or a
    /// TCP-only client's attempt). Report `handle_connected` or `handle_connect_failed`.
    Connect {
        /// The peer the socket belongs to.
        peer: PeerId,
        /// Where to connect.
        addr: SocketAddrV4,
    },
    /// Bind a UDP socket for `peer`'s inbound datagrams. Report `handle_udp_bound`.
    BindUdp {
        /// The peer.
        peer: PeerId,
    },
    /// Open the outbound UDP socket of `peer`, connected to `addr`. Report
    /// `handle_udp_out` with the outcome.
    OpenUdpOut {
        /// The peer.
        peer: PeerId,
        /// The peer's announced UDP address.
        addr: SocketAddrV4,
    },
    /// The peer's datagrams come from `source`: the shell may connect `peer`'s inbound UDP
    /// socket to it, so that the kernel drops anyone else's datagrams and no longer reports
    /// each datagram's source (what the session checks otherwise). Asked once per peer, for
    /// the first datagram that passed the source check. Nothing to report back.
    PinUdpSource {
        /// The peer.
        peer: PeerId,
        /// Where its datagrams come from.
        source: SocketAddrV4,
    },
    /// Close every socket of `peer` (the session has forgotten it).
    Close {
        /// The peer.
        peer: PeerId,
    },
    /// Client: send a connection request to the server from a fresh UDP socket; the text is
    /// [`Session::request_text`].
    SendRequest {
        /// The server's address.
        to: SocketAddrV4,
    },
}

/// What the session hands to the dispatcher, in order.
#[derive(Debug)]
pub enum Delivery {
    /// A user message; its payload is the session's scratch buffer (`Session::payload`).
    Message {
        /// The sender's timestamp in local time when clock sync with the peer is in effect,
        /// else as the sender stamped it.
        time: TimeVal,
        /// The timestamp as the sender stamped it.
        sender_time: TimeVal,
        /// Local sender id (−1 when the peer never described it).
        sender: i32,
        /// Local type id.
        type_id: i32,
        /// Payload length.
        len: usize,
    },
    /// A local connection event.
    Event(ConnectionEvent),
    /// A diagnostic.
    Notice(Notice),
    /// A sender name the peer offers, described for the first time (local id).
    PeerSender(i32),
    /// The connection's state changed.
    State(ConnectionState),
    /// A peer finished describing its own senders (it started describing types), so the list
    /// of senders it offers is complete.
    PeerSendersComplete,
}
