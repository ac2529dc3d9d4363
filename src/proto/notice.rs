//! What a connection tells the application about itself: a [`Notice`] with a typed
//! [`NoticeKind`] (what a program matches on) and a text (what a person reads).

use std::fmt;
use std::net::SocketAddrV4;

/// How serious a [`Notice`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// For the curious (a peer with another minor version, a peer that left).
    Info,
    /// Something a user may need to act on (no answer from a server, a dropped peer).
    Warning,
    /// Something failed.
    Error,
}

/// Sender names or type names (the two name tables of a connection).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NameKind {
    /// Sender (device) names.
    Sender,
    /// Message type names.
    Type,
}

impl NameKind {
    /// `Sender` for `true`.
    pub(crate) fn of(is_sender: bool) -> NameKind {
        if is_sender {
            NameKind::Sender
        } else {
            NameKind::Type
        }
    }
}

impl fmt::Display for NameKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NameKind::Sender => "sender",
            NameKind::Type => "type",
        })
    }
}

/// Why a peer was dropped, or (for a client) why an attempt to reach the server failed.
///
/// New variants may be added: match with a `_` arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum DropReason {
    /// The peer closed its connection.
    Closed,
    /// The peer accepted the connection and closed it before the VRPN greeting (often not a
    /// VRPN server at all).
    ClosedBeforeGreeting,
    /// Reading from the peer's socket failed.
    ReadFailed(std::io::ErrorKind),
    /// Writing to the peer's socket failed.
    SendFailed(std::io::ErrorKind),
    /// Nothing listens on the server's TCP port (connection refused).
    Refused,
    /// The server's UDP port answered "port unreachable" to a connection request.
    Unreachable,
    /// A TCP connect (a client's, or a server's call-back) did not complete in time.
    ConnectTimeout,
    /// A TCP connect failed for another reason.
    ConnectFailed(std::io::ErrorKind),
    /// A client could not send its connection request.
    RequestFailed(std::io::ErrorKind),
    /// The peer connected but sent no VRPN greeting within `Limits::handshake_timeout`.
    NoGreeting,
    /// The peer's greeting was not a VRPN cookie, or of an incompatible major version.
    BadGreeting,
    /// A message that cannot be framed (bad length field, truncated header).
    Malformed,
    /// A message larger than `Limits::max_message_payload`.
    Oversized {
        /// The message's payload length.
        len: usize,
        /// The limit.
        limit: usize,
    },
    /// A name description that is not valid (an id outside VRPN's range, a bad payload, a
    /// name the table cannot hold).
    BadDescription,
    /// More names described than `Limits::max_names_per_peer`.
    TooManyNames {
        /// Which table.
        kind: NameKind,
        /// The limit.
        limit: usize,
    },
    /// More reliable output waiting for the peer than `Limits::max_pending_output`: it is
    /// not reading.
    NotReading {
        /// The limit in bytes.
        limit: usize,
    },
    /// Server: a peer that had not greeted yet gave way to a new client (every slot taken).
    MadeRoom,
    /// Server: the peer asked to be logged under names this server cannot honour (closing
    /// the connection is how a VRPN client learns that remote logging failed).
    RemoteLogRefused,
}

/// What a [`Notice`] is about: the typed part a program can match on.
///
/// New variants may be added: match with a `_` arm.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum NoticeKind {
    /// A peer was dropped (a client's server lost: the client reconnects), or a client's
    /// attempt to reach its server failed (the client keeps trying).
    PeerDropped {
        /// The peer, as `host:port` (a client names its server as the user did).
        peer: String,
        /// Why.
        reason: DropReason,
    },
    /// Client: nothing answered the connection requests for `Limits::no_answer_warning`.
    NoAnswer {
        /// The server as the user named it (`host:port`).
        server: String,
    },
    /// Client: the server is connected and offers no device of this name.
    NoSuchDevice {
        /// The device name asked for.
        device: String,
        /// The devices the server offers.
        offered: Vec<String>,
    },
    /// Server: a client was refused because `Limits::max_connections` are connected.
    ConnectionLimit {
        /// The refused client.
        from: SocketAddrV4,
    },
    /// Server: a connection request datagram that does not parse (reported once; later
    /// ones are counted in [`RequestsIgnored`](Self::RequestsIgnored)).
    BadConnectionRequest {
        /// Where it came from.
        from: SocketAddrV4,
    },
    /// Server: connection requests ignored lately (rate limit, duplicates, bad ones), at
    /// most one summary every few seconds.
    RequestsIgnored,
    /// A peer falls behind: unreliable messages to it are dropped while its backlog lasts.
    FallingBehind {
        /// The peer.
        peer: String,
    },
    /// Datagrams from a stranger's address arrived on a peer's UDP channel and were ignored.
    ForeignDatagrams {
        /// The peer whose channel it was.
        peer: String,
        /// Where the first one came from.
        from: SocketAddrV4,
    },
    /// A datagram from the peer that does not frame was discarded (the peer stays).
    MalformedDatagram {
        /// The peer.
        peer: String,
    },
    /// A peer's name found no room in the full name table; its messages are ignored.
    NameTableFull {
        /// Which table.
        kind: NameKind,
    },
    /// A peer asked this side to write log files; refused.
    RemoteLogRefused {
        /// The peer.
        peer: String,
    },
    /// Server: a peer asked to be logged, and its logs were opened in the operator's folder.
    RemoteLogOpened {
        /// The peer.
        peer: String,
    },
    /// A peer speaks another minor version of VRPN (normally no problem).
    MinorVersion {
        /// The peer.
        peer: String,
    },
    /// Writing a log (or opening a client's incoming log on a server) failed.
    LogFailed,
    /// Server: what a client's forwarding request (the Forwarder brain) did: a port opened,
    /// a message type forwarded, or why not.
    Forwarding,
    /// A replayed log stopped at damaged data (every whole message before it was played).
    ReplayDamaged,
}

/// A diagnostic from a connection: what happened ([`kind`](Self::kind), for programs) and
/// the same in words a user can act on ([`text`](Self::text); `Display` prints it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Notice {
    /// How serious it is.
    pub severity: Severity,
    /// What it is about.
    pub kind: NoticeKind,
    /// What happened and what to do.
    pub text: String,
}

impl Notice {
    /// A notice of `kind` with its text.
    pub fn new(severity: Severity, kind: NoticeKind, text: impl Into<String>) -> Notice {
        Notice {
            severity,
            kind,
            text: text.into(),
        }
    }

    /// The drop reason, when this notice reports a dropped peer or a failed attempt.
    pub fn drop_reason(&self) -> Option<DropReason> {
        match &self.kind {
            NoticeKind::PeerDropped { reason, .. } => Some(*reason),
            _ => None,
        }
    }
}

impl fmt::Display for Notice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}
