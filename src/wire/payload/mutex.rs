//! Mutex messages (`vrpn_Mutex`, `vrpn_PeerMutex`). A mutex is not a `vrpn_BaseClass`: it
//! registers no text, ping or pong types.
//!
//! Server and remote ([`vrpn_Mutex_Server`, `vrpn_Mutex_Remote`]): a remote first asks for an
//! index ([`IndexRequest`]: its IPv4 address and process id); the server answers every
//! remote on the connection with [`Initialize`] (the request echoed, then the index), and a
//! remote takes the answer whose address and process id are its own. Requests, grants and
//! denials then carry that index ([`Index`]); release and release notification are empty.
//!
//! Peers (`vrpn_PeerMutex`) use the request, release, grant and deny names with a
//! [`PeerId`] payload instead: the requester's IPv4 address and port.

/// Ask for an index, remote->server, 8 bytes ([`IndexRequest`]).
pub const REQUEST_INDEX: &str = "vrpn_Mutex Request Index";
/// Ask for the mutex: remote->server with an [`Index`], peer->peer with a [`PeerId`].
pub const REQUEST_MUTEX: &str = "vrpn_Mutex Request Mutex";
/// Give the mutex back: remote->server empty, peer->peer with a [`PeerId`].
pub const RELEASE: &str = "vrpn_Mutex Release";
/// The mutex is free again, server->remotes, empty.
pub const RELEASE_NOTIFICATION: &str = "vrpn_Mutex Release_Notification";
/// The mutex went to the index (server) or the peer (peers) named.
pub const GRANT_REQUEST: &str = "vrpn_Mutex Grant_Request";
/// The request of the index or peer named was refused.
pub const DENY_REQUEST: &str = "vrpn_Mutex Deny_Request";
/// The index of a remote, server->remotes, 12 bytes ([`Initialize`]).
pub const INITIALIZE: &str = "vrpn_Mutex Initialize";

/// The mutex type names in C++ registration order (server and remote; a peer registers
/// request, release, grant and deny only).
pub const TYPE_NAMES: &[&str] = &[
    REQUEST_INDEX,
    REQUEST_MUTEX,
    RELEASE,
    RELEASE_NOTIFICATION,
    GRANT_REQUEST,
    DENY_REQUEST,
    INITIALIZE,
];

fixed_payload! {
    /// `vrpn_Mutex Request Index`: who asks, so that it recognises the answer. At least
    /// 8 bytes (the server echoes whatever it got).
    pub struct IndexRequest: at_least {
        /// IPv4 address of the remote's host, as a host-order number on the wire
        /// (big-endian).
        pub ip: u32,
        /// Process id.
        pub pid: i32,
    }
}

fixed_payload! {
    /// `vrpn_Mutex Initialize` as a C++ server sends it to a C++ remote: the 8-byte index
    /// request echoed, then the index. The C++ remote ignores any other length, and so
    /// does this decoder.
    pub struct Initialize: exact {
        /// The requester's address, echoed.
        pub ip: u32,
        /// The requester's process id, echoed.
        pub pid: i32,
        /// The index the server assigned.
        pub index: i32,
    }
}

fixed_payload! {
    /// A remote's index: `Request Mutex` (remote->server), `Grant_Request` and
    /// `Deny_Request` (server->remotes). At least 4 bytes.
    pub struct Index: at_least {
        /// The remote's index (-1 before it has one).
        pub index: i32,
    }
}

fixed_payload! {
    /// A peer: `Request Mutex`, `Release`, `Grant_Request` and `Deny_Request` between
    /// `vrpn_PeerMutex`es. At least 8 bytes.
    pub struct PeerId: at_least {
        /// The peer's IPv4 address as a host-order number.
        pub ip: u32,
        /// The port of the peer's server connection.
        pub port: u32,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn layouts() {
        let b = round_trip!(
            IndexRequest,
            IndexRequest {
                ip: 0x7f000001,
                pid: 4242
            }
        );
        assert_eq!(b, hex("7f000001 00001092"));
        let b = round_trip!(
            Initialize,
            Initialize {
                ip: 0x7f000001,
                pid: 4242,
                index: 3
            }
        );
        assert_eq!(b, hex("7f000001 00001092 00000003"));
        // The remote ignores initialize messages of any other length.
        assert!(Initialize::decode(&hex("7f000001 00001092 00000003 00")).is_err());
        let b = round_trip!(Index, Index { index: -1 });
        assert_eq!(b, hex("ffffffff"));
        let b = round_trip!(
            PeerId,
            PeerId {
                ip: 0xc0a80102,
                port: 4500
            }
        );
        assert_eq!(b, hex("c0a80102 00001194"));
    }
}
