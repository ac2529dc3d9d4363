//! One peer of a connection, without sockets: handshake phase, id translation tables, and the
//! output buffers that packed messages wait in until the I/O layer writes them.
//!
//! The I/O layer (`net`) fills [`Endpoint::rx`] and [`Endpoint::udp_rx`] with what it read and
//! drains [`Endpoint::tx`] and [`Endpoint::udp_tx`]; everything else here is plain state.

use crate::time::TimeVal;
use crate::wire::framing::StreamDecoder;
use crate::wire::header::{encode_message, Header, HEADER_LEN};
use crate::wire::{class, padded_len, MAX_IDS, MAX_UDP_DATAGRAM, MAX_UDP_INBOUND};

/// Where an endpoint is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    /// TCP connect in progress (server call-back, or TCP-only client).
    TcpConnecting,
    /// Our cookie is sent or queued; waiting for the peer's 24 bytes.
    AwaitingCookie,
    /// Cookies exchanged: messages flow.
    Connected,
}

/// Bytes waiting to go out on TCP. Grows only under backlog, up to `limit`.
#[derive(Debug)]
pub(crate) struct TxBuffer {
    buf: Vec<u8>,
    sent: usize,
    pub(crate) limit: usize,
}

/// The reliable backlog passed its limit: the peer is not reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Backlogged {
    pub(crate) pending: usize,
}

impl TxBuffer {
    pub(crate) fn new(initial: usize, limit: usize) -> TxBuffer {
        TxBuffer {
            buf: Vec::with_capacity(initial),
            sent: 0,
            limit,
        }
    }

    pub(crate) fn pending(&self) -> &[u8] {
        &self.buf[self.sent..]
    }

    pub(crate) fn pending_len(&self) -> usize {
        self.buf.len() - self.sent
    }

    pub(crate) fn consume(&mut self, n: usize) {
        self.sent += n;
        if self.sent >= self.buf.len() {
            self.buf.clear();
            self.sent = 0;
        }
    }

    pub(crate) fn push_raw(&mut self, bytes: &[u8]) -> Result<(), Backlogged> {
        let at = self.reserve(bytes.len())?;
        self.buf[at..at + bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    pub(crate) fn push_message(&mut self, h: &Header, payload: &[u8]) -> Result<(), Backlogged> {
        let size = h.wire_size();
        let at = self.reserve(size)?;
        encode_message(&mut self.buf[at..at + size], h, payload);
        Ok(())
    }

    /// Makes room for `n` more bytes at the end and returns where they start.
    fn reserve(&mut self, n: usize) -> Result<usize, Backlogged> {
        let pending = self.pending_len();
        if pending + n > self.limit {
            return Err(Backlogged { pending });
        }
        if self.sent > 0 && self.buf.len() + n > self.buf.capacity() {
            self.buf.copy_within(self.sent.., 0);
            self.buf.truncate(pending);
            self.sent = 0;
        }
        let at = self.buf.len();
        self.buf.resize(at + n, 0);
        Ok(at)
    }
}

/// Datagrams waiting to go out on UDP: the one being filled plus a ring of full ones. When the
/// ring is full the oldest datagram is dropped: unreliable traffic is what gives way first.
#[derive(Debug)]
pub(crate) struct DatagramQueue {
    slots: Vec<u8>,
    lens: Vec<usize>,
    head: usize,
    count: usize,
    /// Datagrams dropped because the peer's UDP path could not keep up.
    pub(crate) dropped: u64,
}

const DATAGRAM_SLOTS: usize = 64;

impl DatagramQueue {
    pub(crate) fn new() -> DatagramQueue {
        DatagramQueue {
            slots: vec![0; DATAGRAM_SLOTS * MAX_UDP_DATAGRAM],
            lens: vec![0; DATAGRAM_SLOTS],
            head: 0,
            count: 0,
            dropped: 0,
        }
    }

    fn tail_slot(&self) -> usize {
        (self.head + self.count - 1) % DATAGRAM_SLOTS
    }

    /// Appends a message, starting a new datagram when the current one is full.
    pub(crate) fn push_message(&mut self, h: &Header, payload: &[u8]) -> bool {
        let size = h.wire_size();
        if size > MAX_UDP_DATAGRAM {
            return false;
        }
        // The last slot is "open" while it has room; otherwise open a new one.
        let need_new = self.count == 0 || self.lens[self.tail_slot()] + size > MAX_UDP_DATAGRAM;
        if need_new {
            if self.count == DATAGRAM_SLOTS {
                self.head = (self.head + 1) % DATAGRAM_SLOTS;
                self.count -= 1;
                self.dropped += 1;
            }
            self.count += 1;
            let t = self.tail_slot();
            self.lens[t] = 0;
        }
        let t = self.tail_slot();
        let start = t * MAX_UDP_DATAGRAM + self.lens[t];
        encode_message(&mut self.slots[start..start + size], h, payload);
        self.lens[t] += size;
        true
    }

    /// The oldest datagram waiting, if any.
    pub(crate) fn front(&self) -> Option<&[u8]> {
        (self.count > 0).then(|| {
            let s = self.head * MAX_UDP_DATAGRAM;
            &self.slots[s..s + self.lens[self.head]]
        })
    }

    pub(crate) fn pop_front(&mut self) {
        if self.count > 0 {
            self.head = (self.head + 1) % DATAGRAM_SLOTS;
            self.count -= 1;
        }
    }

    pub(crate) fn clear(&mut self) {
        self.count = 0;
        self.head = 0;
    }
}

/// Bytes of one inbox slot: a C++ receiver's 1480-byte limit plus alignment room.
pub(crate) const INBOX_SLOT: usize = MAX_UDP_INBOUND + 8;
/// Datagrams taken per receive call. Two, so that a batch of one proves the queue empty.
pub(crate) const INBOX_SLOTS: usize = 2;

/// Received datagrams (up to [`INBOX_SLOTS`] per system call), walked message by message.
#[derive(Debug)]
pub(crate) struct DatagramInbox {
    pub(crate) buf: Vec<u8>,
    pub(crate) lens: [usize; INBOX_SLOTS],
    /// Datagrams held.
    pub(crate) count: usize,
    /// Datagram being walked.
    cur: usize,
    /// Position inside it.
    pos: usize,
}

impl DatagramInbox {
    fn new() -> DatagramInbox {
        DatagramInbox {
            buf: vec![0; INBOX_SLOT * INBOX_SLOTS],
            lens: [0; INBOX_SLOTS],
            count: 0,
            cur: 0,
            pos: 0,
        }
    }

    /// Everything received has been walked.
    pub(crate) fn is_drained(&self) -> bool {
        self.cur >= self.count
    }

    /// Starts walking `count` freshly received datagrams.
    pub(crate) fn filled(&mut self, count: usize) {
        self.count = count;
        self.cur = 0;
        self.pos = 0;
    }

    /// The unwalked rest of the current datagram.
    pub(crate) fn current(&self) -> &[u8] {
        if self.is_drained() {
            return &[];
        }
        let start = self.cur * INBOX_SLOT;
        &self.buf[start + self.pos..start + self.lens[self.cur]]
    }

    /// Moves past `n` bytes of the current datagram, to the next datagram at its end.
    pub(crate) fn advance(&mut self, n: usize) {
        self.pos += n;
        if self.cur < self.count && self.pos >= self.lens[self.cur] {
            self.cur += 1;
            self.pos = 0;
        }
    }

    /// Skips the rest of the current datagram (malformed or empty).
    pub(crate) fn skip_datagram(&mut self) {
        let rest = self.current().len();
        self.advance(rest.max(1));
    }
}

/// Which channel a packed message went to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Channel {
    Tcp,
    Udp,
    Discarded,
}

/// The sans-IO part of one peer.
#[derive(Debug)]
pub(crate) struct Endpoint {
    pub(crate) phase: Phase,
    /// No UDP channel in either direction (TCP-only path).
    pub(crate) tcp_only: bool,
    pub(crate) rx: StreamDecoder,
    pub(crate) udp_rx: DatagramInbox,
    pub(crate) tx: TxBuffer,
    pub(crate) udp_tx: DatagramQueue,
    /// The peer announced a UDP port and our outbound socket is connected to it.
    pub(crate) udp_ready: bool,
    /// Remote sender id → local sender id (−1 when not described).
    pub(crate) remote_senders: Vec<i32>,
    /// Remote type id → local type id (−1 when not described).
    pub(crate) remote_types: Vec<i32>,
    pub(crate) seq_tcp: u32,
    pub(crate) seq_udp: u32,
    /// Human-readable peer address for messages.
    pub(crate) peer: String,
    /// Version text of the peer's cookie once read.
    pub(crate) peer_version: Option<String>,
    /// The peer broke the protocol; the I/O layer drops it.
    pub(crate) protocol_error: bool,
    /// Largest payload accepted from this peer (`Limits::max_message_payload`).
    pub(crate) max_payload: usize,
    /// Sender names, and separately type names, this peer may describe
    /// (`Limits::max_names_per_peer`).
    pub(crate) max_names: usize,
    /// Sender names this peer described (each new name-to-id binding counts once).
    pub(crate) senders_described: usize,
    /// Type names this peer described.
    pub(crate) types_described: usize,
    /// Unreliable messages not queued on TCP because the peer's reliable backlog was already
    /// past half its limit: unreliable traffic gives way before reliable traffic does.
    pub(crate) unreliable_dropped: u64,
}

impl Endpoint {
    pub(crate) fn new(tcp_only: bool, peer: String, tx_limit: usize) -> Endpoint {
        Endpoint {
            phase: Phase::TcpConnecting,
            tcp_only,
            rx: StreamDecoder::default(),
            udp_rx: DatagramInbox::new(),
            tx: TxBuffer::new(64 * 1024, tx_limit),
            udp_tx: DatagramQueue::new(),
            udp_ready: false,
            remote_senders: Vec::new(),
            remote_types: Vec::new(),
            seq_tcp: 0,
            seq_udp: 0,
            peer,
            peer_version: None,
            protocol_error: false,
            max_payload: crate::wire::MAX_TCP_PADDED_PAYLOAD,
            max_names: MAX_IDS,
            senders_described: 0,
            types_described: 0,
            unreliable_dropped: 0,
        }
    }

    /// Counts one new name this peer described; false once it passes `max_names`.
    pub(crate) fn note_description(&mut self, is_sender: bool) -> bool {
        let n = if is_sender {
            &mut self.senders_described
        } else {
            &mut self.types_described
        };
        *n += 1;
        *n <= self.max_names
    }

    pub(crate) fn clear_remote_names(&mut self) {
        self.remote_senders.clear();
        self.remote_types.clear();
    }

    /// Records what a remote id means locally. Ids outside 0..2000 are refused, as C++ does.
    pub(crate) fn map_remote(table: &mut Vec<i32>, remote: i32, local: i32) -> bool {
        if remote < 0 || remote as usize >= MAX_IDS {
            return false;
        }
        let r = remote as usize;
        if table.len() <= r {
            table.resize(r + 1, -1);
        }
        table[r] = local;
        true
    }

    /// Local id for a remote id, or −1.
    #[inline]
    pub(crate) fn lookup(table: &[i32], remote: i32) -> i32 {
        usize::try_from(remote)
            .ok()
            .and_then(|r| table.get(r).copied())
            .unwrap_or(-1)
    }

    /// Queues a message with the channel its class of service asks for (WIRE.md §6).
    /// Messages packed before the handshake completes are discarded, as in C++.
    pub(crate) fn pack(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> Result<Channel, super::Backlogged> {
        if self.phase != Phase::Connected {
            return Ok(Channel::Discarded);
        }
        self.pack_always(time, sender, type_id, payload, class_of_service)
    }

    /// Queues a message whatever the phase (descriptions during the handshake).
    pub(crate) fn pack_always(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> Result<Channel, super::Backlogged> {
        let use_udp = class_of_service & class::RELIABLE == 0
            && self.udp_ready
            && HEADER_LEN + padded_len(payload.len()) <= MAX_UDP_DATAGRAM;
        let mut h = Header {
            payload_len: payload.len(),
            time,
            sender,
            type_id,
            seq: 0,
        };
        if !use_udp
            && class_of_service & class::RELIABLE == 0
            && self.tx.pending_len() > self.tx.limit / 2
        {
            // The peer is falling behind on TCP: shed unreliable traffic first, so the
            // reliable backlog limit is reached only by reliable messages.
            self.unreliable_dropped += 1;
            return Ok(Channel::Discarded);
        }
        if use_udp {
            h.seq = self.seq_udp;
            self.seq_udp = self.seq_udp.wrapping_add(1);
            self.udp_tx.push_message(&h, payload);
            Ok(Channel::Udp)
        } else {
            h.seq = self.seq_tcp;
            self.seq_tcp = self.seq_tcp.wrapping_add(1);
            self.tx.push_message(&h, payload)?;
            Ok(Channel::Tcp)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(len: usize) -> Header {
        Header {
            payload_len: len,
            time: TimeVal::ZERO,
            sender: 0,
            type_id: 5,
            seq: 0,
        }
    }

    #[test]
    fn tx_buffer_enforces_limit_and_compacts() {
        let mut tx = TxBuffer::new(128, 200);
        tx.push_message(&header(64), &[1; 64]).unwrap();
        assert_eq!(tx.pending_len(), 88);
        tx.push_message(&header(64), &[2; 64]).unwrap();
        assert!(tx.push_message(&header(64), &[3; 64]).is_err());
        tx.consume(88);
        tx.push_message(&header(64), &[3; 64]).unwrap();
        assert_eq!(tx.pending_len(), 176);
        assert_eq!(tx.pending()[24], 2);
    }

    #[test]
    fn datagram_queue_packs_and_drops_oldest() {
        let mut q = DatagramQueue::new();
        for _ in 0..16 {
            assert!(q.push_message(&header(64), &[0; 64]));
        }
        // 16 × 88 bytes = 1408 fit in one 1472-byte datagram.
        assert_eq!(q.front().unwrap().len(), 1408);
        q.push_message(&header(64), &[0; 64]);
        assert_eq!(q.count, 2);
        for _ in 0..(DATAGRAM_SLOTS * 16) {
            q.push_message(&header(64), &[0; 64]);
        }
        assert_eq!(q.count, DATAGRAM_SLOTS);
        assert!(q.dropped > 0);
    }

    #[test]
    fn unconnected_endpoint_discards_and_routes_by_class() {
        let mut ep = Endpoint::new(false, "peer".into(), 1 << 20);
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
        let mut ep = Endpoint::new(true, "peer".into(), 1000);
        ep.phase = Phase::Connected;
        // Fill past half the limit with reliable messages.
        for _ in 0..6 {
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::RELIABLE)
                .unwrap();
        }
        assert_eq!(
            ep.pack(TimeVal::ZERO, 1, 4, &[0; 64], class::LOW_LATENCY),
            Ok(Channel::Discarded)
        );
        assert_eq!(ep.unreliable_dropped, 1);
        // Reliable still queues until the hard limit.
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

    #[test]
    fn description_count_is_limited() {
        let mut ep = Endpoint::new(true, "peer".into(), 1000);
        ep.max_names = 2;
        assert!(ep.note_description(true));
        assert!(ep.note_description(true));
        assert!(ep.note_description(false));
        assert!(!ep.note_description(true));
    }
}
