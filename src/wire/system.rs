//! System messages: negative type ids.

use byteorder::{BigEndian, ByteOrder};

use super::{c_str, need, Result, WireError, MAX_NAME_LEN};

/// Type id of a sender description; the header's sender field carries the described id.
pub const SENDER_DESCRIPTION: i32 = -1;
/// Type id of a type description; the header's sender field carries the described id.
pub const TYPE_DESCRIPTION: i32 = -2;
/// Type id of a UDP description; the header's sender field carries the UDP port.
pub const UDP_DESCRIPTION: i32 = -3;
/// Type id of a log description; the header's sender field carries the log mode.
pub const LOG_DESCRIPTION: i32 = -4;
/// Type id of the disconnect marker (written into logs, never sent by C++).
pub const DISCONNECT: i32 = -5;
/// System types at or below this make a C++ peer drop the connection.
pub const LOWEST_SYSTEM_TYPE: i32 = -1999;

/// Length of a description payload for `name`: u32 length, the name, its NUL.
#[inline]
pub fn description_len(name: impl AsRef<[u8]>) -> usize {
    4 + name.as_ref().len() + 1
}

/// Writes a sender or type description payload. `out` must hold [`description_len`] bytes.
pub fn encode_description(out: &mut [u8], name: impl AsRef<[u8]>) -> usize {
    let name = name.as_ref();
    let n = name.len();
    BigEndian::write_u32(&mut out[0..4], (n + 1) as u32);
    out[4..4 + n].copy_from_slice(name);
    out[4 + n] = 0;
    4 + n + 1
}

/// Reads the name in a sender or type description payload, as the bytes the peer sent.
///
/// Like C++, the name ends at its NUL and a payload longer than 100 bytes
/// (`vrpn_CNAME_LENGTH`) is refused. Any other byte is allowed: names are ASCII in practice,
/// but a peer (or a C++ server echoing what some client described) may send any byte.
pub fn decode_description_bytes(payload: &[u8]) -> Result<&[u8]> {
    need(payload, 5)?;
    if payload.len() > MAX_NAME_LEN + 5 {
        return Err(WireError::NameTooLong(payload.len() - 5));
    }
    let declared = BigEndian::read_u32(&payload[0..4]) as usize;
    if declared == 0 || declared > payload.len() - 4 + 1 {
        return Err(WireError::BadValue("description length"));
    }
    c_str(&payload[4..])
}

/// [`decode_description_bytes`] for a name that must be UTF-8 (log tools showing names).
pub fn decode_description(payload: &[u8]) -> Result<&str> {
    let name = decode_description_bytes(payload)?;
    std::str::from_utf8(name).map_err(|_| WireError::BadValue("name encoding"))
}

/// Writes a UDP description payload (the address text plus NUL). Returns the length.
pub fn encode_udp_description(out: &mut [u8], ip: &str) -> usize {
    out[..ip.len()].copy_from_slice(ip.as_bytes());
    out[ip.len()] = 0;
    ip.len() + 1
}

/// Reads the host text of a UDP description payload.
pub fn decode_udp_description(payload: &[u8]) -> Result<&str> {
    let host = c_str(payload)?;
    std::str::from_utf8(host).map_err(|_| WireError::BadValue("UDP description host"))
}

/// A decoded log description.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogDescription<'a> {
    /// File name for the incoming log, empty for none.
    pub incoming: &'a str,
    /// File name for the outgoing log, empty for none.
    pub outgoing: &'a str,
}

/// Length of a log description payload.
pub fn log_description_len(incoming: &str, outgoing: &str) -> usize {
    8 + incoming.len() + 1 + outgoing.len() + 1
}

/// Writes a log description payload.
pub fn encode_log_description(out: &mut [u8], incoming: &str, outgoing: &str) -> usize {
    let (a, b) = (incoming.len(), outgoing.len());
    BigEndian::write_i32(&mut out[0..4], a as i32);
    BigEndian::write_i32(&mut out[4..8], b as i32);
    out[8..8 + a].copy_from_slice(incoming.as_bytes());
    out[8 + a] = 0;
    out[9 + a..9 + a + b].copy_from_slice(outgoing.as_bytes());
    out[9 + a + b] = 0;
    10 + a + b
}

/// Reads a log description payload.
pub fn decode_log_description(payload: &[u8]) -> Result<LogDescription<'_>> {
    need(payload, 10)?;
    let a = BigEndian::read_i32(&payload[0..4]);
    let b = BigEndian::read_i32(&payload[4..8]);
    if a < 0 || b < 0 {
        return Err(WireError::BadValue("log description lengths"));
    }
    let (a, b) = (a as usize, b as usize);
    need(payload, 10 + a + b)?;
    Ok(LogDescription {
        incoming: utf8_field(&payload[8..8 + a])?,
        outgoing: utf8_field(&payload[9 + a..9 + a + b])?,
    })
}

fn utf8_field(s: &[u8]) -> Result<&str> {
    std::str::from_utf8(s).map_err(|_| WireError::BadValue("log description name"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn description_matches_cpp_bytes() {
        let mut buf = [0u8; 32];
        let n = encode_description(&mut buf, "Tracker0");
        assert_eq!(&buf[..n], b"\0\0\0\x09Tracker0\0");
        assert_eq!(decode_description(&buf[..n]).unwrap(), "Tracker0");
    }

    #[test]
    fn description_limits() {
        let long = "x".repeat(96);
        let mut buf = vec![0u8; 200];
        let n = encode_description(&mut buf, &long);
        assert!(matches!(
            decode_description(&buf[..n]),
            Err(WireError::NameTooLong(_))
        ));
        let ok = "y".repeat(95);
        let n = encode_description(&mut buf, &ok);
        assert_eq!(decode_description(&buf[..n]).unwrap(), ok);
        assert!(decode_description(b"\0\0\0\x05abcd").is_err());
    }

    #[test]
    fn log_description_round_trip() {
        let mut buf = [0u8; 64];
        let n = encode_log_description(&mut buf, "in.vrpn", "");
        assert_eq!(n, 10 + 7);
        let d = decode_log_description(&buf[..n]).unwrap();
        assert_eq!(d.incoming, "in.vrpn");
        assert_eq!(d.outgoing, "");
    }
}
