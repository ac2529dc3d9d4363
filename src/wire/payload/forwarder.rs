//! `vrpn_Forwarder_Brain`: a client tells a server to open another port and to forward the
//! messages of a device to whoever connects there.
//!
//! Both messages come from the sender `vrpn_Forwarder_Brain`:
//!
//! * start forwarding: one big-endian `i32`, the port to open (4 bytes);
//! * forward: `i32` port, `i32` length of the sender name, `i32` length of the type name,
//!   then the two names back to back, without NUL terminators.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};

/// The sender both messages come from.
pub const SENDER: &str = "vrpn_Forwarder_Brain";
/// Client to server: open this port.
pub const START_FORWARDING: &str = "vrpn_Forwarder_Brain start_forwarding";
/// Client to server: forward this type from this sender on that port.
pub const FORWARD: &str = "vrpn_Forwarder_Brain forward";

/// The types in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[START_FORWARDING, FORWARD];

/// Length of a start-forwarding payload.
pub const START_LEN: usize = 4;

/// Writes a start-forwarding payload; returns its length.
pub fn encode_start(out: &mut [u8], port: i32) -> usize {
    BigEndian::write_i32(&mut out[..4], port);
    START_LEN
}

/// Reads a start-forwarding payload (at least 4 bytes; C++ reads the first four).
pub fn decode_start(payload: &[u8]) -> Result<i32> {
    need(payload, START_LEN)?;
    Ok(BigEndian::read_i32(&payload[..4]))
}

/// A request to forward one message type of one sender over a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Forward<'a> {
    /// The port opened by a start-forwarding request.
    pub port: i32,
    /// The sender (device) whose messages are forwarded.
    pub sender: &'a [u8],
    /// The message type forwarded.
    pub type_name: &'a [u8],
}

impl<'a> Forward<'a> {
    /// Payload length.
    pub fn encoded_len(&self) -> usize {
        12 + self.sender.len() + self.type_name.len()
    }

    /// Writes the payload at the start of `out` (at least [`encoded_len`](Self::encoded_len)
    /// bytes); returns its length.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let (s, t) = (self.sender.len(), self.type_name.len());
        BigEndian::write_i32(&mut out[0..4], self.port);
        BigEndian::write_i32(&mut out[4..8], s as i32);
        BigEndian::write_i32(&mut out[8..12], t as i32);
        out[12..12 + s].copy_from_slice(self.sender);
        out[12 + s..12 + s + t].copy_from_slice(self.type_name);
        12 + s + t
    }

    /// Reads a payload; the names must fit in it (C++ does not check; a longer payload's
    /// tail is ignored, as there).
    pub fn decode(payload: &'a [u8]) -> Result<Forward<'a>> {
        need(payload, 12)?;
        let port = BigEndian::read_i32(&payload[0..4]);
        let s = BigEndian::read_i32(&payload[4..8]);
        let t = BigEndian::read_i32(&payload[8..12]);
        let (Ok(s), Ok(t)) = (usize::try_from(s), usize::try_from(t)) else {
            return Err(WireError::BadValue("forward request name length"));
        };
        need(payload, 12usize.saturating_add(s).saturating_add(t))?;
        Ok(Forward {
            port,
            sender: &payload[12..12 + s],
            type_name: &payload[12 + s..12 + s + t],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_is_the_port_big_endian() {
        let mut buf = [0u8; 4];
        assert_eq!(encode_start(&mut buf, 4510), 4);
        assert_eq!(buf, [0, 0, 0x11, 0x9e]);
        assert_eq!(decode_start(&buf).unwrap(), 4510);
        assert!(decode_start(&buf[..3]).is_err());
    }

    #[test]
    fn forward_layout_matches_cpp() {
        // What C++ `forward_message_type(4510, "Tracker0", "vrpn_Tracker Pos_Quat")` packs.
        let f = Forward {
            port: 4510,
            sender: b"Tracker0",
            type_name: b"vrpn_Tracker Pos_Quat",
        };
        let mut buf = [0u8; 64];
        let n = f.encode(&mut buf);
        let mut want = vec![0, 0, 0x11, 0x9e, 0, 0, 0, 8, 0, 0, 0, 21];
        want.extend_from_slice(b"Tracker0vrpn_Tracker Pos_Quat");
        assert_eq!(&buf[..n], &want[..]);
        assert_eq!(Forward::decode(&buf[..n]).unwrap(), f);
        for cut in 0..n {
            assert!(Forward::decode(&buf[..cut]).is_err(), "cut {cut}");
        }
    }

    #[test]
    fn bad_lengths_never_panic() {
        let mut buf = [0u8; 16];
        BigEndian::write_i32(&mut buf[4..8], -5);
        assert!(Forward::decode(&buf).is_err());
        BigEndian::write_i32(&mut buf[4..8], i32::MAX);
        BigEndian::write_i32(&mut buf[8..12], i32::MAX);
        assert!(Forward::decode(&buf).is_err());
    }
}
