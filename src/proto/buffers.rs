//! The byte buffers of one peer: TCP output, UDP output, UDP input. Sized when the peer needs
//! them and reused after that, so steady-state traffic allocates nothing; a peer that never
//! completes its handshake costs a few hundred bytes, not the 300 KB a connected one holds.

use std::net::{Ipv4Addr, SocketAddrV4};

use crate::wire::header::{encode_message, patch_seq, Header, HEADER_LEN};
use crate::wire::{MAX_UDP_DATAGRAM, MAX_UDP_INBOUND};

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
        self.make_room(bytes.len())?;
        self.buf.extend_from_slice(bytes);
        Ok(())
    }

    /// Appends header, payload and zero padding (copied straight in: no zero-fill first).
    pub(crate) fn push_message(&mut self, h: &Header, payload: &[u8]) -> Result<(), Backlogged> {
        let size = h.wire_size();
        self.make_room(size)?;
        let mut header = [0u8; HEADER_LEN];
        h.encode(&mut header);
        self.buf.extend_from_slice(&header);
        self.buf.extend_from_slice(payload);
        const ZEROS: [u8; 8] = [0; 8];
        self.buf
            .extend_from_slice(&ZEROS[..size - HEADER_LEN - payload.len()]);
        Ok(())
    }

    /// Appends a message encoded once for every peer (see `Session::pack`), with this peer's
    /// sequence number written over the encoded one.
    #[inline]
    pub(crate) fn push_encoded(&mut self, msg: &[u8], seq: u32) -> Result<(), Backlogged> {
        self.make_room(msg.len())?;
        let at = self.buf.len();
        self.buf.extend_from_slice(msg);
        patch_seq(&mut self.buf[at..], seq);
        Ok(())
    }

    /// Checks the limit for `n` more bytes and moves unsent bytes to the front when that
    /// avoids growing the buffer.
    fn make_room(&mut self, n: usize) -> Result<(), Backlogged> {
        let pending = self.pending_len();
        if pending + n > self.limit {
            return Err(Backlogged { pending });
        }
        if self.sent > 0 && self.buf.len() + n > self.buf.capacity() {
            self.buf.copy_within(self.sent.., 0);
            self.buf.truncate(pending);
            self.sent = 0;
        }
        Ok(())
    }
}

/// Datagrams waiting to go out on UDP: the one being filled plus a ring of full ones. When the
/// ring is full the oldest datagram is dropped: unreliable traffic is what gives way first.
/// The ring is allocated when the peer's UDP channel opens ([`DatagramQueue::allocate`]), so
/// the first datagram allocates nothing; peers on the TCP-only path never need it.
#[derive(Debug, Default)]
pub(crate) struct DatagramQueue {
    slots: Vec<u8>,
    lens: Vec<usize>,
    head: usize,
    count: usize,
    /// Datagrams dropped because the peer's UDP path could not keep up.
    pub(crate) dropped: u64,
}

pub(crate) const DATAGRAM_SLOTS: usize = 64;

impl DatagramQueue {
    fn tail_slot(&self) -> usize {
        (self.head + self.count - 1) % DATAGRAM_SLOTS
    }

    /// Appends a message, starting a new datagram when the current one is full.
    pub(crate) fn push_message(&mut self, h: &Header, payload: &[u8]) -> bool {
        let size = h.wire_size();
        let Some(out) = self.reserve(size) else {
            return false;
        };
        encode_message(out, h, payload);
        true
    }

    /// Appends a message encoded once for every peer (see `Session::pack`), with this peer's
    /// sequence number written over the encoded one.
    #[inline]
    pub(crate) fn push_encoded(&mut self, msg: &[u8], seq: u32) -> bool {
        let Some(out) = self.reserve(msg.len()) else {
            return false;
        };
        out.copy_from_slice(msg);
        patch_seq(out, seq);
        true
    }

    /// Room for `size` more bytes at the end of the open datagram, or of a new one (dropping
    /// the oldest when the ring is full); `None` for a message no datagram can hold.
    #[inline]
    fn reserve(&mut self, size: usize) -> Option<&mut [u8]> {
        if size > MAX_UDP_DATAGRAM {
            return None;
        }
        self.allocate();
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
        self.lens[t] += size;
        Some(&mut self.slots[start..start + size])
    }

    /// Allocates the ring, once. Called when the peer's UDP channel opens: unreliable
    /// messages may keep to TCP for a while after that (`Limits::udp_after_descriptions`), and
    /// the first datagram must not allocate in what is by then the steady state.
    pub(crate) fn allocate(&mut self) {
        if self.slots.is_empty() {
            self.slots = vec![0; DATAGRAM_SLOTS * MAX_UDP_DATAGRAM];
            self.lens = vec![0; DATAGRAM_SLOTS];
        }
    }

    /// No datagram waits.
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The oldest datagram waiting, if any.
    pub(crate) fn front(&self) -> Option<&[u8]> {
        (self.count > 0).then(|| {
            let s = self.head * MAX_UDP_DATAGRAM;
            &self.slots[s..s + self.lens[self.head]]
        })
    }

    /// The datagrams waiting, oldest first.
    pub(crate) fn iter(&self) -> impl Iterator<Item = &[u8]> + '_ {
        (0..self.count).map(move |k| {
            let slot = (self.head + k) % DATAGRAM_SLOTS;
            let s = slot * MAX_UDP_DATAGRAM;
            &self.slots[s..s + self.lens[slot]]
        })
    }

    /// Number of datagrams waiting.
    pub(crate) fn len(&self) -> usize {
        self.count
    }

    /// Takes out the `n` oldest datagrams (sent or lost).
    pub(crate) fn pop_many(&mut self, n: usize) {
        let n = n.min(self.count);
        self.head = (self.head + n) % DATAGRAM_SLOTS;
        self.count -= n;
        self.rewind_if_empty();
    }

    pub(crate) fn pop_front(&mut self) {
        if self.count > 0 {
            self.head = (self.head + 1) % DATAGRAM_SLOTS;
            self.count -= 1;
            self.rewind_if_empty();
        }
    }

    /// An empty ring starts again at slot 0. A peer that keeps up sends everything every pass,
    /// so its next datagram is written over the bytes it just sent, still in cache: walking the
    /// ring's 94 KB per peer instead made every message to each of 255 peers a cache miss.
    #[inline]
    fn rewind_if_empty(&mut self) {
        if self.count == 0 {
            self.head = 0;
        }
    }

    pub(crate) fn clear(&mut self) {
        self.count = 0;
        self.head = 0;
    }
}

/// Bytes of one inbox slot: a C++ receiver's 1480-byte limit plus alignment room.
pub const INBOX_SLOT: usize = MAX_UDP_INBOUND + 8;
/// Datagrams taken per receive call. Two, so that a batch of one proves the queue empty.
pub const INBOX_SLOTS: usize = 2;

/// Received datagrams (up to [`INBOX_SLOTS`] per system call) with their sources, walked
/// message by message. The shell receives straight into it.
#[derive(Debug)]
pub struct DatagramInbox {
    /// `INBOX_SLOTS` slots of `INBOX_SLOT` bytes.
    pub buf: Vec<u8>,
    /// Length of each received datagram.
    pub lens: [usize; INBOX_SLOTS],
    /// Source of each received datagram.
    pub from: [SocketAddrV4; INBOX_SLOTS],
    /// Datagrams held.
    count: usize,
    /// Datagram being walked.
    cur: usize,
    /// Position inside it.
    pos: usize,
}

impl Default for DatagramInbox {
    fn default() -> Self {
        DatagramInbox {
            buf: vec![0; INBOX_SLOT * INBOX_SLOTS],
            lens: [0; INBOX_SLOTS],
            from: [SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0); INBOX_SLOTS],
            count: 0,
            cur: 0,
            pos: 0,
        }
    }
}

impl DatagramInbox {
    /// Everything received has been walked.
    pub(crate) fn is_drained(&self) -> bool {
        self.cur >= self.count
    }

    /// Starts walking `count` freshly received datagrams.
    pub(crate) fn filled(&mut self, count: usize) {
        self.count = count.min(INBOX_SLOTS);
        self.cur = 0;
        self.pos = 0;
    }

    /// Source of the datagram being walked.
    pub(crate) fn current_source(&self) -> SocketAddrV4 {
        self.from[self.cur.min(INBOX_SLOTS - 1)]
    }

    /// The unwalked rest of the current datagram.
    pub(crate) fn current(&self) -> &[u8] {
        if self.is_drained() {
            return &[];
        }
        let start = self.cur * INBOX_SLOT;
        let len = self.lens[self.cur].min(INBOX_SLOT);
        &self.buf[start + self.pos.min(len)..start + len]
    }

    /// Moves past `n` bytes of the current datagram, to the next datagram at its end.
    pub(crate) fn advance(&mut self, n: usize) {
        self.pos += n;
        if self.cur < self.count && self.pos >= self.lens[self.cur] {
            self.cur += 1;
            self.pos = 0;
        }
    }

    /// Skips the rest of the current datagram (malformed, empty, or from a stranger).
    pub(crate) fn skip_datagram(&mut self) {
        if self.cur < self.count {
            self.cur += 1;
            self.pos = 0;
        }
    }
}

/// Alignment of [`PayloadBuf`]: a cache line.
const PAYLOAD_ALIGN: usize = 64;

/// The buffer a message's payload is copied into before handlers read it, starting on a
/// cache-line boundary.
///
/// Where a plain `Vec` starts is up to the allocator. Measured: one that began 48 bytes before
/// a page boundary made every 64-byte pose payload copy a store split across two pages, and
/// those copies took longer than all the rest of a report's receive path (the UDP throughput
/// figure fell by 5 %). Aligning it takes the luck out.
pub struct PayloadBuf {
    bytes: Vec<u8>,
    start: usize,
}

impl PayloadBuf {
    /// A zeroed buffer of `len` usable bytes.
    pub fn new(len: usize) -> PayloadBuf {
        let mut bytes = vec![0; len + PAYLOAD_ALIGN];
        // `align_offset` may in principle decline (usize::MAX); the buffer then works unaligned.
        let start = match bytes.as_ptr().align_offset(PAYLOAD_ALIGN) {
            n if n < PAYLOAD_ALIGN => n,
            _ => 0,
        };
        // Exactly `len` usable bytes (shortening a Vec keeps its allocation in place).
        bytes.truncate(start + len);
        PayloadBuf { bytes, start }
    }
}

impl Default for PayloadBuf {
    /// An empty buffer (what is left behind while the real one is lent out).
    fn default() -> PayloadBuf {
        PayloadBuf {
            bytes: Vec::new(),
            start: 0,
        }
    }
}

impl std::ops::Deref for PayloadBuf {
    type Target = [u8];
    #[inline]
    fn deref(&self) -> &[u8] {
        &self.bytes[self.start..]
    }
}

impl std::ops::DerefMut for PayloadBuf {
    #[inline]
    fn deref_mut(&mut self) -> &mut [u8] {
        &mut self.bytes[self.start..]
    }
}

impl std::fmt::Debug for PayloadBuf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PayloadBuf({} bytes)", self.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;

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
        let mut q = DatagramQueue::default();
        for _ in 0..16 {
            assert!(q.push_message(&header(64), &[0; 64]));
        }
        // 16 × 88 bytes = 1408 fit in one 1472-byte datagram.
        assert_eq!(q.front().unwrap().len(), 1408);
        q.push_message(&header(64), &[0; 64]);
        assert_eq!(q.len(), 2);
        for _ in 0..(DATAGRAM_SLOTS * 16) {
            q.push_message(&header(64), &[0; 64]);
        }
        assert_eq!(q.len(), DATAGRAM_SLOTS);
        assert!(q.dropped > 0);
    }

    #[test]
    fn datagram_queue_keeps_order_and_reuses_slot_zero_once_empty() {
        let mut q = DatagramQueue::default();
        // Fill three datagrams (16 messages each), marking each message by its number.
        for k in 0..48u8 {
            assert!(q.push_message(&header(64), &[k; 64]));
        }
        assert_eq!(q.len(), 3);
        q.pop_front();
        let firsts: Vec<u8> = q.iter().map(|d| d[24]).collect();
        assert_eq!(firsts, [16, 32], "oldest first after a partial send");
        assert_ne!(q.head, 0);
        q.pop_many(2);
        assert!(q.is_empty());
        assert_eq!(q.head, 0, "an empty ring starts again at slot 0");
        assert!(q.push_message(&header(64), &[99; 64]));
        assert_eq!(q.front().unwrap()[24], 99);
        assert_eq!(q.front().unwrap().len(), 88);
        // Over-long pops of an empty queue keep it sane.
        q.pop_many(5);
        q.pop_front();
        assert!(q.is_empty() && q.head == 0 && q.front().is_none());
    }

    #[test]
    fn inbox_walks_datagrams_and_skips() {
        let mut inbox = DatagramInbox::default();
        inbox.buf[..3].copy_from_slice(b"abc");
        inbox.buf[INBOX_SLOT..INBOX_SLOT + 2].copy_from_slice(b"de");
        inbox.lens = [3, 2];
        inbox.filled(2);
        assert_eq!(inbox.current(), b"abc");
        inbox.advance(1);
        assert_eq!(inbox.current(), b"bc");
        inbox.skip_datagram();
        assert_eq!(inbox.current(), b"de");
        inbox.advance(2);
        assert!(inbox.is_drained());
    }

    #[test]
    fn payload_buffer_starts_on_a_cache_line_and_lends_its_whole_length() {
        for len in [1, 88, 65_536] {
            let mut b = PayloadBuf::new(len);
            assert_eq!(b.len(), len);
            assert_eq!(b.as_ptr() as usize % PAYLOAD_ALIGN, 0);
            b[len - 1] = 7;
            let lent = std::mem::take(&mut b);
            assert_eq!(b.len(), 0);
            assert_eq!(lent[len - 1], 7);
        }
    }
}
