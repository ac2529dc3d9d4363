//! `vrpn_Auxiliary_Logger`: a client asks a server to start or stop logging a connection.
//!
//! The request, the response and the status request share one layout: four big-endian `i32`
//! lengths (local incoming, local outgoing, remote incoming, remote outgoing), then the four
//! names, back to back, **without** NUL terminators. An empty name (length 0) means "no such
//! log". The payload length must be exactly 16 plus the four lengths (the C++ handler refuses
//! anything else). A status request carries four empty names (16 zero bytes).
//!
//! "Local" logs are written by the logging server's own connection to the logged server;
//! "remote" ones are requested from the logged server when that connection is made.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};

/// Client to server: start (non-empty names) or stop (all empty) logging.
pub const REQUEST: &str = "vrpn_Auxiliary_Logger Logging_request";
/// Server to client: the logs now open (all empty: none, or the request failed).
pub const RESPONSE: &str = "vrpn_Auxiliary_Logger Logging_response";
/// Client to server: "which logs are open?" (answered with a response).
pub const STATUS_REQUEST: &str = "vrpn_Auxiliary_Logger Logging_status_request";

/// The types in C++ registration order (before the three base types).
pub const TYPE_NAMES: &[&str] = &[REQUEST, RESPONSE, STATUS_REQUEST];

/// Bytes of the four length words.
pub const LENGTHS_LEN: usize = 16;

/// The four log file names of a request or response, borrowed from a payload or a caller.
/// Names are bytes on the wire; an empty one means "no log".
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LogNames<'a> {
    /// What the logging connection receives, written on the logging server's machine.
    pub local_in: &'a [u8],
    /// What the logging connection sends, written on the logging server's machine.
    pub local_out: &'a [u8],
    /// What the logged server receives from the logging connection, written by that server.
    pub remote_in: &'a [u8],
    /// What the logged server sends to the logging connection, written by that server.
    pub remote_out: &'a [u8],
}

impl<'a> LogNames<'a> {
    /// Four names from text.
    pub fn new(
        local_in: &'a str,
        local_out: &'a str,
        remote_in: &'a str,
        remote_out: &'a str,
    ) -> LogNames<'a> {
        LogNames {
            local_in: local_in.as_bytes(),
            local_out: local_out.as_bytes(),
            remote_in: remote_in.as_bytes(),
            remote_out: remote_out.as_bytes(),
        }
    }

    /// The names in wire order.
    pub fn fields(&self) -> [&'a [u8]; 4] {
        [
            self.local_in,
            self.local_out,
            self.remote_in,
            self.remote_out,
        ]
    }

    /// True when every name is empty (a stop request, or a response saying nothing is logged).
    pub fn is_empty(&self) -> bool {
        self.fields().iter().all(|f| f.is_empty())
    }

    /// Payload length of these names.
    pub fn encoded_len(&self) -> usize {
        LENGTHS_LEN + self.fields().iter().map(|f| f.len()).sum::<usize>()
    }

    /// Writes the payload at the start of `out` (at least [`encoded_len`](Self::encoded_len)
    /// bytes); returns its length.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let fields = self.fields();
        for (i, f) in fields.iter().enumerate() {
            BigEndian::write_i32(&mut out[i * 4..i * 4 + 4], f.len() as i32);
        }
        let mut at = LENGTHS_LEN;
        for f in fields {
            out[at..at + f.len()].copy_from_slice(f);
            at += f.len();
        }
        at
    }

    /// Reads a payload: the four lengths, then exactly that many name bytes (a longer or
    /// shorter payload, or a negative length, is an error, as in C++).
    pub fn decode(payload: &'a [u8]) -> Result<LogNames<'a>> {
        need(payload, LENGTHS_LEN)?;
        let mut lens = [0usize; 4];
        let mut total = LENGTHS_LEN;
        for (i, len) in lens.iter_mut().enumerate() {
            let l = BigEndian::read_i32(&payload[i * 4..i * 4 + 4]);
            if l < 0 {
                return Err(WireError::BadValue("auxiliary logger name length"));
            }
            *len = l as usize;
            total = total.saturating_add(*len);
        }
        if payload.len() != total {
            return Err(WireError::BadValue("auxiliary logger payload length"));
        }
        let mut at = LENGTHS_LEN;
        let mut take = |len: usize| {
            let f = &payload[at..at + len];
            at += len;
            f
        };
        Ok(LogNames {
            local_in: take(lens[0]),
            local_out: take(lens[1]),
            remote_in: take(lens[2]),
            remote_out: take(lens[3]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_layout_matches_cpp() {
        // What C++ `send_logging_request("", "", "", "out.vrpn")` packs.
        let names = LogNames::new("", "", "", "out.vrpn");
        let mut buf = [0u8; 64];
        let n = names.encode(&mut buf);
        assert_eq!(n, 24);
        assert_eq!(
            &buf[..n],
            b"\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x08out.vrpn".as_slice()
        );
        assert_eq!(LogNames::decode(&buf[..n]).unwrap(), names);
    }

    #[test]
    fn four_names_in_order() {
        let names = LogNames::new("a", "bb", "ccc", "dddd");
        let mut buf = [0u8; 64];
        let n = names.encode(&mut buf);
        assert_eq!(
            &buf[..n],
            b"\0\0\0\x01\0\0\0\x02\0\0\0\x03\0\0\0\x04abbcccdddd".as_slice()
        );
        let back = LogNames::decode(&buf[..n]).unwrap();
        assert_eq!(back.remote_in, b"ccc");
        assert_eq!(back.encoded_len(), n);
    }

    #[test]
    fn status_request_is_sixteen_zero_bytes() {
        let mut buf = [0xffu8; 32];
        let n = LogNames::default().encode(&mut buf);
        assert_eq!(&buf[..n], &[0u8; 16]);
        assert!(LogNames::decode(&buf[..n]).unwrap().is_empty());
    }

    #[test]
    fn wrong_lengths_are_refused() {
        let mut buf = [0u8; 64];
        let n = LogNames::new("in", "", "", "").encode(&mut buf);
        for cut in 0..n {
            assert!(LogNames::decode(&buf[..cut]).is_err(), "cut {cut}");
        }
        // A trailing byte: C++ checks the total exactly.
        assert!(LogNames::decode(&buf[..n + 1]).is_err());
        // Negative and huge lengths never panic.
        BigEndian::write_i32(&mut buf[0..4], -1);
        assert!(LogNames::decode(&buf[..n]).is_err());
        BigEndian::write_i32(&mut buf[0..4], i32::MAX);
        BigEndian::write_i32(&mut buf[4..8], i32::MAX);
        assert!(LogNames::decode(&buf[..n]).is_err());
    }
}
