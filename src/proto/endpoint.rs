//! One peer of a session, without sockets: its phase, the bytes in and out, what its ids mean
//! here, and the deadline it must meet.

use std::net::SocketAddrV4;
use std::time::{Duration, Instant};

use super::buffers::{Backlogged, DatagramInbox, DatagramQueue, TxBuffer};
use super::names::IdSet;
use super::PeerId;
use crate::log::LogWriter;
use crate::time::TimeVal;
use crate::wire::framing::StreamDecoder;
use crate::wire::header::Header;
use crate::wire::{class, COOKIE_LEN, MAX_IDS, MAX_UDP_DATAGRAM};

/// A log file sink as the session sees it: bytes out, nothing else.
pub(crate) type LogSink = LogWriter<Box<dyn std::io::Write>>;

/// Where a peer is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    /// TCP connect in progress (server call-back, or TCP-only client).
    Connecting,
    /// Our cookie is queued; waiting for the peer's 24 bytes.
    AwaitingCookie,
    /// Cookies exchanged; our UDP socket is being bound before we describe ourselves.
    Describing,
    /// Handshake complete: messages flow.
    Connected,
}

/// Which channel a packed message went to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Channel {
    Tcp,
    Udp,
    Discarded,
}

/// Remote id → local id for one kind of name, with what the peer holds of our name table.
#[derive(Debug, Default)]
#[repr(C)] // `map`, read per message, first
pub(crate) struct RemoteNames {
    /// Remote id → local id (−1 when not described or not mapped).
    map: Vec<i32>,
    /// Learned local names this peer holds (released when it leaves).
    pub(crate) held: IdSet,
    /// Name-to-id bindings this peer described (limited per peer).
    pub(crate) described: usize,
}

impl RemoteNames {
    /// Local id for a remote id, or −1.
    #[inline]
    pub(crate) fn lookup(&self, remote: i32) -> i32 {
        usize::try_from(remote)
            .ok()
            .and_then(|r| self.map.get(r).copied())
            .unwrap_or(-1)
    }

    /// Records what a remote id means locally (−1: known to be unmappable here).
    pub(crate) fn bind(&mut self, remote: i32, local: i32) {
        let r = remote as usize;
        if self.map.len() <= r {
            self.map.resize(r + 1, -1);
        }
        self.map[r] = local;
    }

    /// Every local id some remote id maps to.
    pub(crate) fn locals(&self) -> impl Iterator<Item = i32> + '_ {
        self.map.iter().copied().filter(|&l| l >= 0)
    }

    /// Forgets the mapping (a DISCONNECT from the peer); held names stay held until the peer
    /// leaves, so the ids cannot change under a peer that re-describes them.
    pub(crate) fn clear(&mut self) {
        self.map.clear();
    }

    /// True for a remote id a C++ peer would accept.
    pub(crate) fn valid_id(remote: i32) -> bool {
        (0..MAX_IDS as i32).contains(&remote)
    }
}

/// The clock translation a peer's messages use for a while (see `Endpoint::clock_pass`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ClockPass {
    /// `None` while synchronisation is not in effect: times pass unchanged.
    pub(crate) translation: Option<super::clock::Translation>,
    /// Until when it may be used (a deadline of the session).
    pub(crate) until: std::time::Instant,
    /// The last timestamp translated and its local time: the reports of one frame (every
    /// sensor of a tracker, every channel of a device) carry the same time.
    pub(crate) last: Option<(TimeVal, TimeVal)>,
}

impl ClockPass {
    /// `remote` in local time.
    #[inline]
    pub(crate) fn translate(&mut self, remote: TimeVal) -> TimeVal {
        let Some(t) = &self.translation else {
            return remote;
        };
        match self.last {
            Some((r, local)) if r == remote => local,
            _ => {
                let local = t.remote_to_local(remote);
                self.last = Some((remote, local));
                local
            }
        }
    }
}

/// The sans-IO part of one peer.
///
/// Laid out by hand (`repr(C)`): the fields every received message touches come first, so that
/// a report costs a few cache lines of this struct rather than one line per field (the
/// compiler's order spread them over ten). The set-up and bookkeeping fields follow.
#[repr(C)]
pub(crate) struct Endpoint {
    pub(crate) phase: Phase,
    /// The peer announced a UDP port and our outbound socket is connected to it.
    pub(crate) udp_ready: bool,
    /// Unreliable messages keep to TCP until then: the peer may not have read the
    /// descriptions sent just before (`Limits::udp_after_descriptions`).
    pub(crate) udp_held_until: Option<Instant>,
    /// The id of a clock query sent to the peer since the hold was last set: it went by TCP,
    /// behind the descriptions, so the peer's reply shows it has read them and ends the hold
    /// early (a peer of this crate; C++ never answers, and keeps the timed hold).
    pub(crate) udp_hold_probe: Option<u32>,
    /// No UDP channel in either direction (TCP-only path).
    pub(crate) tcp_only: bool,
    /// The peer has described a type: its own sender table is complete (C++ describes every
    /// sender, then every type), so senders described after this are echoes of names other
    /// peers taught it, or later registrations.
    pub(crate) senders_complete: bool,
    /// A call-back connect started by a connection request (coalesced per address).
    pub(crate) callback: bool,
    pub(crate) seq_tcp: u32,
    pub(crate) seq_udp: u32,
    /// The peer's TCP address.
    pub(crate) addr: SocketAddrV4,
    /// Messages taken from this peer in the current pass (fairness).
    pub(crate) budget: usize,
    /// Clock synchronisation with this peer, once it is connected (and sync is on).
    pub(crate) clock: Option<Box<super::clock::ClockSync>>,
    /// The clock translation in use and the moment until which it holds, so that messages
    /// work out the estimate only a few times a second. Cleared when a reply changes the
    /// estimate.
    pub(crate) clock_pass: Option<ClockPass>,
    /// This peer's incoming log (`vrpn_server -li`: one file per client).
    pub(crate) log_in: Option<LogSink>,
    /// The logs the peer asked this server to write (remote logging; boxed: rare).
    pub(crate) requested_logs: Option<Box<super::session::RequestedLogs>>,
    /// Reassembles the TCP stream; made when the handshake completes.
    pub(crate) rx: Option<StreamDecoder>,
    /// Inbound datagrams; made when our UDP socket for this peer is bound.
    pub(crate) udp_rx: Option<DatagramInbox>,
    pub(crate) tx: TxBuffer,
    pub(crate) udp_tx: DatagramQueue,
    pub(crate) senders: RemoteNames,
    pub(crate) types: RemoteNames,
    pub(crate) id: PeerId,
    /// Our end of the TCP connection (the address we announce for UDP).
    pub(crate) local: Option<SocketAddrV4>,
    /// The peer's address as text, for messages.
    pub(crate) label: String,
    cookie: [u8; COOKIE_LEN],
    cookie_len: usize,
    /// Version text of the peer's cookie once read.
    pub(crate) peer_version: Option<String>,
    /// When the peer must have reached the next phase (connect, then handshake).
    pub(crate) deadline: Option<Instant>,
    /// When the peer completed its handshake.
    pub(crate) connected_at: Option<Instant>,
    /// Unreliable messages not queued because the reliable backlog was past half its limit.
    pub(crate) unreliable_dropped: u64,
    /// Local sender ids this peer offers (described in its own table).
    pub(crate) offered: IdSet,
    /// The shell was asked to pin the peer's UDP source (`IoRequest::PinUdpSource`).
    pub(crate) udp_source_pinned: bool,
    /// Datagrams dropped because they came from another address than the peer's.
    pub(crate) foreign_datagrams: u64,
}

impl Endpoint {
    /// Nothing received from this peer is left to walk: no stream bytes, no datagram.
    #[inline]
    pub(crate) fn input_drained(&self) -> bool {
        self.rx.as_ref().map_or(true, |r| r.buffered() == 0)
            && self.udp_rx.as_ref().map_or(true, |i| i.is_drained())
    }

    pub(crate) fn new(id: PeerId, tcp_only: bool, addr: SocketAddrV4, tx_limit: usize) -> Endpoint {
        Endpoint {
            id,
            phase: Phase::Connecting,
            tcp_only,
            addr,
            local: None,
            label: addr.to_string(),
            cookie: [0; COOKIE_LEN],
            cookie_len: 0,
            rx: None,
            udp_rx: None,
            tx: TxBuffer::new(1024, tx_limit),
            udp_tx: DatagramQueue::default(),
            udp_ready: false,
            udp_held_until: None,
            udp_hold_probe: None,
            senders: RemoteNames::default(),
            types: RemoteNames::default(),
            seq_tcp: 0,
            seq_udp: 0,
            peer_version: None,
            deadline: None,
            connected_at: None,
            budget: 0,
            unreliable_dropped: 0,
            senders_complete: false,
            offered: IdSet::default(),
            foreign_datagrams: 0,
            udp_source_pinned: false,
            log_in: None,
            requested_logs: None,
            callback: false,
            clock: None,
            clock_pass: None,
        }
    }

    /// Where the next TCP bytes should be read to: the rest of the cookie while greeting (so a
    /// read never takes more than the greeting), the stream decoder after.
    pub(crate) fn rx_spare(&mut self) -> &mut [u8] {
        match self.phase {
            Phase::Connecting => &mut [],
            Phase::AwaitingCookie => &mut self.cookie[self.cookie_len..],
            Phase::Describing | Phase::Connected => match self.rx.as_mut() {
                Some(rx) => rx.spare(),
                None => &mut [],
            },
        }
    }

    /// Marks `n` bytes of [`rx_spare`](Self::rx_spare) as filled.
    pub(crate) fn rx_commit(&mut self, n: usize) {
        match self.phase {
            Phase::AwaitingCookie => self.cookie_len = (self.cookie_len + n).min(COOKIE_LEN),
            Phase::Describing | Phase::Connected => {
                if let Some(rx) = self.rx.as_mut() {
                    rx.commit(n);
                }
            }
            Phase::Connecting => {}
        }
    }

    /// The peer's whole cookie, once it arrived.
    pub(crate) fn cookie(&self) -> Option<&[u8; COOKIE_LEN]> {
        (self.phase == Phase::AwaitingCookie && self.cookie_len == COOKIE_LEN)
            .then_some(&self.cookie)
    }

    /// The peer's cookie once all 24 bytes were read (whatever the phase since).
    pub(crate) fn greeting_bytes(&self) -> Option<[u8; COOKIE_LEN]> {
        (self.cookie_len == COOKIE_LEN).then_some(self.cookie)
    }

    /// Queues a message with the channel its class of service asks for. Messages packed
    /// before the handshake completes are discarded, as in C++.
    pub(crate) fn pack(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> Result<Channel, Backlogged> {
        if self.phase != Phase::Connected {
            return Ok(Channel::Discarded);
        }
        self.pack_always(time, sender, type_id, payload, class_of_service)
    }

    /// Queues a message whatever the phase (the handshake's own descriptions).
    pub(crate) fn pack_always(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> Result<Channel, Backlogged> {
        let mut h = Header {
            payload_len: payload.len(),
            time,
            sender,
            type_id,
            seq: 0,
        };
        match self.route(h.wire_size(), class_of_service) {
            Channel::Udp => {
                h.seq = self.next_seq_udp();
                self.udp_tx.push_message(&h, payload);
                Ok(Channel::Udp)
            }
            Channel::Tcp => {
                h.seq = self.next_seq_tcp();
                self.tx.push_message(&h, payload)?;
                Ok(Channel::Tcp)
            }
            Channel::Discarded => Ok(Channel::Discarded),
        }
    }

    /// Queues a whole encoded message (header, payload, padding: the same bytes for every
    /// peer, because the ids in it are this side's) as [`pack`](Self::pack) would, writing
    /// this peer's sequence number into its copy. One encoding then serves every peer.
    #[inline]
    pub(crate) fn pack_encoded(
        &mut self,
        msg: &[u8],
        class_of_service: u32,
    ) -> Result<Channel, Backlogged> {
        if self.phase != Phase::Connected {
            return Ok(Channel::Discarded);
        }
        match self.route(msg.len(), class_of_service) {
            Channel::Udp => {
                let seq = self.next_seq_udp();
                self.udp_tx.push_encoded(msg, seq);
                Ok(Channel::Udp)
            }
            Channel::Tcp => {
                let seq = self.next_seq_tcp();
                self.tx.push_encoded(msg, seq)?;
                Ok(Channel::Tcp)
            }
            Channel::Discarded => Ok(Channel::Discarded),
        }
    }

    /// The channel a message of `wire_size` bytes takes: UDP when it is unreliable, the UDP
    /// channel is open and it fits a datagram; otherwise TCP, unless it is unreliable and the
    /// peer is falling behind on TCP (then it is shed and counted).
    #[inline]
    fn route(&mut self, wire_size: usize, class_of_service: u32) -> Channel {
        let reliable = class_of_service & class::RELIABLE != 0;
        if reliable {
            return Channel::Tcp;
        }
        if self.udp_ready && self.udp_held_until.is_none() && wire_size <= MAX_UDP_DATAGRAM {
            return Channel::Udp;
        }
        if self.tx.pending_len() > self.tx.limit / 2 {
            // The peer is falling behind on TCP: shed unreliable traffic first, so the
            // reliable backlog limit is reached only by reliable messages.
            self.unreliable_dropped += 1;
            return Channel::Discarded;
        }
        Channel::Tcp
    }

    /// Keeps unreliable messages on TCP for `hold` from `now` (see `udp_held_until`).
    pub(crate) fn hold_udp(&mut self, now: Instant, hold: Duration) {
        if self.udp_ready && !hold.is_zero() {
            let until = now + hold;
            self.udp_held_until = Some(self.udp_held_until.map_or(until, |t| t.max(until)));
            // A query sent before these descriptions shows nothing about them.
            self.udp_hold_probe = None;
        }
    }

    /// A clock query `id` is being sent: while unreliable messages are held it goes by TCP
    /// behind the descriptions, and the first such one becomes the probe.
    pub(crate) fn note_clock_query(&mut self, id: u32) {
        if self.udp_held_until.is_some() && self.udp_hold_probe.is_none() {
            self.udp_hold_probe = Some(id);
        }
    }

    /// The peer answered clock query `id`: if that is the probe or a later query, it has read
    /// every description sent before the probe, and the hold ends. Returns whether it did.
    pub(crate) fn note_clock_reply(&mut self, id: u32) -> bool {
        let Some(probe) = self.udp_hold_probe else {
            return false;
        };
        // Query ids count up (wrapping) on a connection; an older id proves nothing.
        if id.wrapping_sub(probe) > u32::MAX / 2 {
            return false;
        }
        self.udp_held_until = None;
        self.udp_hold_probe = None;
        true
    }

    #[inline]
    fn next_seq_udp(&mut self) -> u32 {
        let s = self.seq_udp;
        self.seq_udp = s.wrapping_add(1);
        s
    }

    #[inline]
    fn next_seq_tcp(&mut self) -> u32 {
        let s = self.seq_tcp;
        self.seq_tcp = s.wrapping_add(1);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::Ipv4Addr;

    fn ep(tcp_only: bool, limit: usize) -> Endpoint {
        let id = PeerId {
            slot: 0,
            generation: 1,
        };
        Endpoint::new(
            id,
            tcp_only,
            SocketAddrV4::new(Ipv4Addr::LOCALHOST, 1),
            limit,
        )
    }

    #[test]
    fn unconnected_endpoint_discards_and_routes_by_class() {
        let mut ep = ep(false, 1 << 20);
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::LOW_LATENCY),
            Ok(Channel::Discarded)
        );
        ep.phase = Phase::Connected;
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::LOW_LATENCY),
            Ok(Channel::Tcp)
        );
        ep.udp_ready = true;
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::LOW_LATENCY),
            Ok(Channel::Udp)
        );
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::RELIABLE),
            Ok(Channel::Tcp)
        );
        assert_eq!((ep.seq_tcp, ep.seq_udp), (2, 1));
    }

    #[test]
    fn unreliable_gives_way_first_under_backlog() {
        let mut ep = ep(true, 1000);
        ep.phase = Phase::Connected;
        for _ in 0..6 {
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::RELIABLE)
                .unwrap();
        }
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::LOW_LATENCY),
            Ok(Channel::Discarded)
        );
        assert_eq!(ep.unreliable_dropped, 1);
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::RELIABLE),
            Ok(Channel::Tcp)
        );
        while ep
            .pack(TimeVal::ZERO, 1, 4, &[0; 64], class::RELIABLE)
            .is_ok()
        {}
        assert!(ep.tx.pending_len() <= 1000);
    }

    /// A message encoded once and copied (`pack_encoded`, the fan-out path) leaves exactly the
    /// bytes a per-peer encoding (`pack`) leaves, sequence numbers included, on both channels,
    /// and sheds and counts the same way.
    #[test]
    fn encoded_once_copies_are_the_bytes_of_a_per_peer_encoding() {
        use crate::wire::header::encode_message;
        let time = TimeVal::new(1_795_309_382, 663_181);
        let payloads: [&[u8]; 4] = [&[], &[7; 13], &[9; 64], &[3; 2000]];
        for tcp_only in [false, true] {
            let (mut a, mut b) = (ep(tcp_only, 1 << 20), ep(tcp_only, 1 << 20));
            for e in [&mut a, &mut b] {
                e.phase = Phase::Connected;
                e.udp_ready = !tcp_only;
                // Peers differ in how far their sequence numbers got.
                e.seq_tcp = 5;
                e.seq_udp = 0xFFFF_FFFE;
            }
            let mut encoded = vec![0xAA; 4096];
            for round in 0..3 {
                for (k, payload) in payloads.iter().enumerate() {
                    for cos in [class::RELIABLE, class::LOW_LATENCY] {
                        let (sender, type_id) = (k as i32, round - 1);
                        let per_peer = a.pack(time, sender, type_id, payload, cos);
                        let h = Header {
                            payload_len: payload.len(),
                            time,
                            sender,
                            type_id,
                            seq: 0,
                        };
                        let n = encode_message(&mut encoded, &h, payload).unwrap();
                        assert_eq!(b.pack_encoded(&encoded[..n], cos), per_peer);
                    }
                }
            }
            assert_eq!(a.tx.pending(), b.tx.pending());
            assert!(!a.tx.pending().is_empty());
            assert_eq!(a.udp_tx.len(), b.udp_tx.len());
            assert!(a.udp_tx.iter().eq(b.udp_tx.iter()));
            assert_eq!(a.udp_tx.is_empty(), tcp_only);
            assert_eq!((a.seq_tcp, a.seq_udp), (b.seq_tcp, b.seq_udp));
        }
        // Unconnected: discarded; falling behind on TCP: unreliable shed and counted.
        let mut c = ep(true, 1000);
        let msg = [0u8; 88];
        assert_eq!(
            c.pack_encoded(&msg, class::RELIABLE),
            Ok(Channel::Discarded)
        );
        c.phase = Phase::Connected;
        for _ in 0..6 {
            assert_eq!(c.pack_encoded(&msg, class::RELIABLE), Ok(Channel::Tcp));
        }
        assert_eq!(
            c.pack_encoded(&msg, class::LOW_LATENCY),
            Ok(Channel::Discarded)
        );
        assert_eq!(c.unreliable_dropped, 1);
        while c.pack_encoded(&msg, class::RELIABLE).is_ok() {}
        assert!(c.tx.pending_len() <= 1000);
    }

    #[test]
    fn greeting_reads_stop_at_the_cookie() {
        let mut ep = ep(true, 1000);
        ep.phase = Phase::AwaitingCookie;
        assert_eq!(ep.rx_spare().len(), COOKIE_LEN);
        ep.rx_commit(10);
        assert_eq!(ep.rx_spare().len(), COOKIE_LEN - 10);
        assert!(ep.cookie().is_none());
        ep.rx_commit(14);
        assert!(ep.cookie().is_some());
        assert!(ep.rx_spare().is_empty());
    }
}
