//! Base-class messages every device registers: the text message, ping and pong.
//!
//! The text payload is always 1032 bytes: u32 severity, u32 level, then a 1024-byte buffer
//! holding a NUL-terminated string. C++ leaves the bytes after the NUL uninitialised; we zero
//! them.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};

/// Text message, either direction, always 1032 bytes ([`TextMessage`]).
pub const TEXT_MESSAGE: &str = "vrpn_Base text_message";
/// Ping, client->server, empty payload.
pub const PING_MESSAGE: &str = "vrpn_Base ping_message";
/// Pong, server->client, empty payload.
pub const PONG_MESSAGE: &str = "vrpn_Base pong_message";

/// The base-class type names in C++ registration order (registered after the device's own).
pub const TYPE_NAMES: &[&str] = &[TEXT_MESSAGE, PING_MESSAGE, PONG_MESSAGE];

/// Severity of an ordinary message (`vrpn_TEXT_NORMAL`).
pub const NORMAL: u32 = 0;
/// Severity of a warning (`vrpn_TEXT_WARNING`).
pub const WARNING: u32 = 1;
/// Severity of an error (`vrpn_TEXT_ERROR`).
pub const ERROR: u32 = 2;

/// Size of the text buffer, NUL included.
pub const TEXT_CAPACITY: usize = 1024;
/// Longest text that can be sent (one byte goes to the NUL).
pub const MAX_TEXT_LEN: usize = TEXT_CAPACITY - 1;

/// Lower-case name of a severity (`"normal"`, `"warning"`, `"error"`), `None` for others.
pub fn severity_name(severity: u32) -> Option<&'static str> {
    match severity {
        NORMAL => Some("normal"),
        WARNING => Some("warning"),
        ERROR => Some("error"),
        _ => None,
    }
}

/// Length of every text payload C++ sends: two u32 and the 1024-byte text buffer.
pub const TEXT_PAYLOAD_LEN: usize = 8 + TEXT_CAPACITY;

/// Severity of a text message, as a type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum TextSeverity {
    /// `vrpn_TEXT_NORMAL` (0).
    Normal,
    /// `vrpn_TEXT_WARNING` (1).
    Warning,
    /// `vrpn_TEXT_ERROR` (2).
    Error,
    /// Any other value a peer sent.
    Other(u32),
}

impl TextSeverity {
    /// The wire value.
    pub fn code(self) -> u32 {
        match self {
            TextSeverity::Normal => NORMAL,
            TextSeverity::Warning => WARNING,
            TextSeverity::Error => ERROR,
            TextSeverity::Other(c) => c,
        }
    }

    /// From the wire value.
    pub fn from_code(c: u32) -> TextSeverity {
        match c {
            NORMAL => TextSeverity::Normal,
            WARNING => TextSeverity::Warning,
            ERROR => TextSeverity::Error,
            c => TextSeverity::Other(c),
        }
    }

    /// The heading C++ prints for it.
    pub fn heading(self) -> &'static str {
        match self {
            TextSeverity::Normal => "VRPN Message",
            TextSeverity::Warning => "VRPN Warning",
            TextSeverity::Error => "VRPN Error",
            TextSeverity::Other(_) => "VRPN UNKNOWN SEVERITY",
        }
    }
}

/// A decoded `vrpn_Base text_message`, borrowing its text from the payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextMessage<'a> {
    /// [`NORMAL`], [`WARNING`] or [`ERROR`] (other values pass through).
    pub severity: u32,
    /// Free-form sub-level (the ping logic puts elapsed seconds here).
    pub level: u32,
    /// The text without its NUL; bytes, since C++ does not promise any encoding.
    pub text: &'a [u8],
}

impl<'a> TextMessage<'a> {
    /// Payload length on the wire: always 1032.
    pub const LEN: usize = 8 + TEXT_CAPACITY;

    /// Builds a message, refusing what C++ refuses to send: text of more than
    /// [`MAX_TEXT_LEN`] bytes. A NUL inside the text is refused too (it would cut it short).
    pub fn new(severity: u32, level: u32, text: &'a [u8]) -> Result<TextMessage<'a>> {
        if text.len() > MAX_TEXT_LEN {
            return Err(WireError::BadValue("text message longer than 1023 bytes"));
        }
        if text.contains(&0) {
            return Err(WireError::BadValue("text message with an embedded NUL"));
        }
        Ok(TextMessage {
            severity,
            level,
            text,
        })
    }

    /// The text as UTF-8, if it is.
    pub fn as_str(&self) -> Option<&'a str> {
        std::str::from_utf8(self.text).ok()
    }

    /// Decodes a text payload. Like the C++ receiver, the length field is not checked beyond
    /// holding the two words and the string: any payload of at least 9 bytes whose first
    /// 1024 text bytes hold a NUL is accepted; no NUL there is [`WireError::MissingNul`].
    pub fn decode(buf: &'a [u8]) -> Result<TextMessage<'a>> {
        need(buf, 9)?;
        let area = &buf[8..buf.len().min(Self::LEN)];
        let n = area
            .iter()
            .position(|&b| b == 0)
            .ok_or(WireError::MissingNul)?;
        Ok(TextMessage {
            severity: BigEndian::read_u32(&buf[0..4]),
            level: BigEndian::read_u32(&buf[4..8]),
            text: &area[..n],
        })
    }

    /// Writes the full 1032-byte payload, zero-filled after the text, into `out` (at least
    /// [`TextMessage::LEN`] bytes). Text beyond [`MAX_TEXT_LEN`] bytes is cut (use
    /// [`TextMessage::new`] to refuse it instead).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let out = &mut out[..Self::LEN];
        let n = self.text.len().min(MAX_TEXT_LEN);
        BigEndian::write_u32(&mut out[0..4], self.severity);
        BigEndian::write_u32(&mut out[4..8], self.level);
        out[8..8 + n].copy_from_slice(&self.text[..n]);
        out[8 + n..].fill(0);
        Self::LEN
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::hex;
    use super::*;

    #[test]
    fn round_trips_and_zero_fills() {
        let m = TextMessage::new(WARNING, 3, b"hello").unwrap();
        let mut buf = [0xAAu8; 1100];
        assert_eq!(m.encode(&mut buf), 1032);
        assert_eq!(&buf[..13], b"\0\0\0\x01\0\0\0\x03hello");
        assert!(buf[13..1032].iter().all(|&b| b == 0));
        assert_eq!(buf[1032], 0xAA);
        assert_eq!(TextMessage::decode(&buf[..1032]).unwrap(), m);

        let long = [b'x'; MAX_TEXT_LEN];
        let m = TextMessage::new(ERROR, 0, &long).unwrap();
        m.encode(&mut buf);
        assert_eq!(TextMessage::decode(&buf[..1032]).unwrap().text.len(), 1023);
        assert!(TextMessage::new(ERROR, 0, &[b'x'; 1024]).is_err());
        assert!(TextMessage::new(ERROR, 0, b"a\0b").is_err());
    }

    #[test]
    fn decode_rules() {
        // Short payloads are fine as long as the NUL is there.
        let m = TextMessage::decode(b"\0\0\0\0\0\0\0\x07hi\0").unwrap();
        assert_eq!((m.severity, m.level, m.text), (NORMAL, 7, &b"hi"[..]));
        assert_eq!(
            TextMessage::decode(b"\0\0\0\0\0\0\0\0\0").unwrap().text,
            b""
        );
        assert!(TextMessage::decode(b"\0\0\0\0\0\0\0\0").is_err());
        assert_eq!(
            TextMessage::decode(b"\0\0\0\0\0\0\0\0abc"),
            Err(WireError::MissingNul)
        );
        // The NUL must sit within the first 1024 text bytes.
        let mut buf = vec![b'y'; 1040];
        buf[1035] = 0;
        assert_eq!(TextMessage::decode(&buf), Err(WireError::MissingNul));
        buf[1031] = 0;
        assert_eq!(TextMessage::decode(&buf).unwrap().text.len(), 1023);
    }

    #[test]
    fn golden_joystick_error() {
        // text_and_ping: a joystick driver's error text; the tail after the NUL is stack garbage.
        let mut p = hex(
            "00000002000000004572726f722072656164696e672066726f6d206a6f79737469636b00\
             00000000d0c3f717fe7f00000600000001000000693f026b00000000",
        );
        p.resize(1032, 0x5a);
        let m = TextMessage::decode(&p).unwrap();
        assert_eq!(m.severity, ERROR);
        assert_eq!(severity_name(m.severity), Some("error"));
        assert_eq!(m.level, 0);
        assert_eq!(m.as_str(), Some("Error reading from joystick"));
        let mut out = [0u8; 1032];
        m.encode(&mut out);
        assert_eq!(&out[..36], &p[..36]);
    }
}
