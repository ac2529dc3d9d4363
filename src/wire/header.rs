//! The 24-byte message header.
//!
//! ```text
//! length | tv_sec | tv_usec | sender | type | seqno | payload | pad to 8
//! ```
//! `length` is 24 + the unpadded payload length; the sixth word is a per-channel sequence
//! number that receivers ignore.

use byteorder::{BigEndian, ByteOrder};

use super::{need, Result, WireError, ALIGN, MAX_TCP_PADDED_PAYLOAD};
use crate::time::TimeVal;

/// Size of the header on the wire.
pub const HEADER_LEN: usize = 24;

/// Where the sequence number sits in an encoded header: the only header field that differs
/// between the copies of one message sent to several peers.
pub const SEQ_OFFSET: usize = 20;

/// Rounds a length up to the 8-byte wire alignment.
#[inline]
pub const fn padded_len(n: usize) -> usize {
    (n + ALIGN - 1) & !(ALIGN - 1)
}

/// One decoded message header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Payload length in bytes (the wire field minus 24).
    pub payload_len: usize,
    /// Sender's timestamp.
    pub time: TimeVal,
    /// Sender id in the sending side's id space (or a parameter for system messages).
    pub sender: i32,
    /// Type id in the sending side's id space; negative for system messages.
    pub type_id: i32,
    /// Sequence number; informational only.
    pub seq: u32,
}

impl Header {
    /// Bytes this message occupies on the wire, header and padding included.
    #[inline]
    pub fn wire_size(&self) -> usize {
        HEADER_LEN + padded_len(self.payload_len)
    }

    /// Decodes a header and checks its length field against the C++ limits.
    pub fn decode(buf: &[u8]) -> Result<Header> {
        need(buf, HEADER_LEN)?;
        let len = BigEndian::read_u32(&buf[0..4]);
        if (len as usize) < HEADER_LEN {
            return Err(WireError::LengthTooShort(len));
        }
        let payload_len = len as usize - HEADER_LEN;
        if padded_len(payload_len) > MAX_TCP_PADDED_PAYLOAD {
            return Err(WireError::LengthTooLong(len));
        }
        Ok(Header {
            payload_len,
            time: TimeVal::from_header_words(
                BigEndian::read_u32(&buf[4..8]),
                BigEndian::read_u32(&buf[8..12]),
            ),
            sender: BigEndian::read_i32(&buf[12..16]),
            type_id: BigEndian::read_i32(&buf[16..20]),
            seq: BigEndian::read_u32(&buf[20..24]),
        })
    }

    /// Writes the 24 header bytes. `buf` must hold at least [`HEADER_LEN`] bytes.
    pub fn encode(&self, buf: &mut [u8]) {
        let (sec, usec) = self.time.to_wire();
        BigEndian::write_u32(&mut buf[0..4], (HEADER_LEN + self.payload_len) as u32);
        BigEndian::write_u32(&mut buf[4..8], sec);
        BigEndian::write_u32(&mut buf[8..12], usec);
        BigEndian::write_i32(&mut buf[12..16], self.sender);
        BigEndian::write_i32(&mut buf[16..20], self.type_id);
        BigEndian::write_u32(&mut buf[20..24], self.seq);
    }
}

/// Overwrites the sequence number of an encoded message (`msg` holds at least its header).
#[inline]
pub fn patch_seq(msg: &mut [u8], seq: u32) {
    BigEndian::write_u32(&mut msg[SEQ_OFFSET..SEQ_OFFSET + 4], seq);
}

/// Writes a whole message (header, payload, zeroed padding) at the start of `out`.
///
/// Returns the bytes written, or `None` when `out` is too small.
pub fn encode_message(out: &mut [u8], header: &Header, payload: &[u8]) -> Option<usize> {
    debug_assert_eq!(header.payload_len, payload.len());
    let total = header.wire_size();
    if out.len() < total {
        return None;
    }
    header.encode(&mut out[..HEADER_LEN]);
    out[HEADER_LEN..HEADER_LEN + payload.len()].copy_from_slice(payload);
    out[HEADER_LEN + payload.len()..total].fill(0);
    Some(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_pads() {
        let h = Header {
            payload_len: 13,
            time: TimeVal::new(1_795_309_382, 663_181),
            sender: 1,
            type_id: -1,
            seq: 2,
        };
        let mut buf = [0xAAu8; 64];
        let n = encode_message(&mut buf, &h, b"\0\0\0\x09Tracker0\0").unwrap();
        assert_eq!(n, 40);
        assert_eq!(&buf[0..4], &[0, 0, 0, 37]);
        assert_eq!(&buf[37..40], &[0, 0, 0]);
        assert_eq!(Header::decode(&buf).unwrap(), h);
        patch_seq(&mut buf, 0x0102_0304);
        assert_eq!(
            Header::decode(&buf).unwrap(),
            Header {
                seq: 0x0102_0304,
                ..h
            }
        );
        assert_eq!(&buf[24..37], b"\0\0\0\x09Tracker0\0");
    }

    #[test]
    fn rejects_bad_lengths() {
        let mut buf = [0u8; 24];
        buf[3] = 23;
        assert_eq!(Header::decode(&buf), Err(WireError::LengthTooShort(23)));
        BigEndian::write_u32(&mut buf[0..4], 70_000);
        assert_eq!(Header::decode(&buf), Err(WireError::LengthTooLong(70_000)));
        assert!(matches!(
            Header::decode(&buf[..10]),
            Err(WireError::Truncated { .. })
        ));
    }
}
