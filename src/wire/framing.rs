//! Splitting byte streams and datagrams into messages.
//!
//! [`StreamDecoder`] reassembles a TCP stream in a fixed buffer sized once: reads land in
//! [`StreamDecoder::spare`], whole messages come out of [`StreamDecoder::next_message`] as
//! borrowed slices. [`DatagramMessages`] walks one UDP datagram. Neither allocates after
//! construction.

use super::header::{Header, HEADER_LEN};
use super::{Result, WireError, MAX_TCP_PADDED_PAYLOAD};

/// Buffer size that holds the largest legal message plus room for a large read.
pub const DEFAULT_STREAM_BUFFER: usize = 128 * 1024;

/// Reassembles messages from a TCP byte stream.
#[derive(Debug)]
pub struct StreamDecoder {
    buf: Vec<u8>,
    start: usize,
    end: usize,
}

impl Default for StreamDecoder {
    fn default() -> Self {
        Self::with_capacity(DEFAULT_STREAM_BUFFER)
    }
}

impl StreamDecoder {
    /// A decoder with a buffer of `capacity` bytes (at least one maximal message).
    pub fn with_capacity(capacity: usize) -> StreamDecoder {
        let capacity = capacity.max(HEADER_LEN + MAX_TCP_PADDED_PAYLOAD);
        StreamDecoder {
            buf: vec![0; capacity],
            start: 0,
            end: 0,
        }
    }

    /// Forgets buffered bytes (on reconnect).
    pub fn clear(&mut self) {
        self.start = 0;
        self.end = 0;
    }

    /// Bytes received but not yet consumed.
    pub fn buffered(&self) -> usize {
        self.end - self.start
    }

    /// Free space to read into; moves unconsumed bytes to the front first when that helps.
    pub fn spare(&mut self) -> &mut [u8] {
        if self.start > 0 && (self.start == self.end || self.end == self.buf.len()) {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        &mut self.buf[self.end..]
    }

    /// Marks `n` bytes of [`StreamDecoder::spare`] as filled.
    pub fn commit(&mut self, n: usize) {
        self.end = (self.end + n).min(self.buf.len());
    }

    /// Copies as much of `bytes` as fits; returns how many were taken. For feeding from memory.
    pub fn feed(&mut self, bytes: &[u8]) -> usize {
        let spare = self.spare();
        let n = spare.len().min(bytes.len());
        spare[..n].copy_from_slice(&bytes[..n]);
        self.commit(n);
        n
    }

    /// Takes exactly `n` bytes if that many are buffered (the cookie, for instance).
    pub fn take_exact(&mut self, n: usize) -> Option<&[u8]> {
        if self.buffered() < n {
            return None;
        }
        let s = self.start;
        self.start += n;
        Some(&self.buf[s..s + n])
    }

    /// The next whole message: its header and unpadded payload.
    ///
    /// `None` means more bytes are needed. An error means the stream cannot be framed any more
    /// (bad length field) and the connection must be dropped.
    #[inline]
    pub fn next_message(&mut self) -> Option<Result<(Header, &[u8])>> {
        let avail = &self.buf[self.start..self.end];
        if avail.len() < HEADER_LEN {
            return None;
        }
        let header = match Header::decode(avail) {
            Ok(h) => h,
            Err(e) => return Some(Err(e)),
        };
        let size = header.wire_size();
        if avail.len() < size {
            return None;
        }
        let s = self.start + HEADER_LEN;
        self.start += size;
        Some(Ok((header, &self.buf[s..s + header.payload_len])))
    }
}

/// Iterates over the messages of one UDP datagram.
///
/// Yields an error (and then stops) when the datagram ends inside a header or a payload.
pub struct DatagramMessages<'a> {
    rest: &'a [u8],
    failed: bool,
}

impl<'a> DatagramMessages<'a> {
    /// Starts walking `datagram`.
    pub fn new(datagram: &'a [u8]) -> Self {
        DatagramMessages {
            rest: datagram,
            failed: false,
        }
    }
}

impl<'a> Iterator for DatagramMessages<'a> {
    type Item = Result<(Header, &'a [u8])>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.rest.is_empty() || self.failed {
            return None;
        }
        let header = match Header::decode(self.rest) {
            Ok(h) => h,
            Err(e) => {
                self.failed = true;
                return Some(Err(e));
            }
        };
        let end = HEADER_LEN + header.payload_len;
        if self.rest.len() < end {
            self.failed = true;
            return Some(Err(WireError::Truncated {
                needed: end,
                available: self.rest.len(),
            }));
        }
        let payload = &self.rest[HEADER_LEN..end];
        // The last message of a datagram carries its padding too; tolerate its absence.
        self.rest = &self.rest[header.wire_size().min(self.rest.len())..];
        Some(Ok((header, payload)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use crate::wire::header::encode_message;

    fn msg(type_id: i32, payload: &[u8]) -> Vec<u8> {
        let h = Header {
            payload_len: payload.len(),
            time: TimeVal::new(1, 2),
            sender: 0,
            type_id,
            seq: 0,
        };
        let mut out = vec![0u8; h.wire_size()];
        encode_message(&mut out, &h, payload).unwrap();
        out
    }

    #[test]
    fn reassembles_split_reads_byte_by_byte() {
        let mut stream = msg(3, b"hello");
        stream.extend(msg(4, b""));
        stream.extend(msg(5, &[7u8; 100]));
        let mut d = StreamDecoder::default();
        let mut seen = Vec::new();
        for b in &stream {
            d.feed(std::slice::from_ref(b));
            while let Some(m) = d.next_message() {
                let (h, p) = m.unwrap();
                seen.push((h.type_id, p.len()));
            }
        }
        assert_eq!(seen, vec![(3, 5), (4, 0), (5, 100)]);
        assert_eq!(d.buffered(), 0);
    }

    #[test]
    fn datagram_truncation_is_an_error() {
        let mut dg = msg(3, b"abc");
        dg.extend(msg(4, b"0123456789"));
        let all: Vec<_> = DatagramMessages::new(&dg).collect();
        assert_eq!(all.len(), 2);
        assert!(all.iter().all(|m| m.is_ok()));
        let cut = &dg[..dg.len() - 10];
        let res: Vec<_> = DatagramMessages::new(cut).collect();
        assert!(res[0].is_ok() && res[1].is_err());
    }
}
