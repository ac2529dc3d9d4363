//! Text messages (`vrpn_Base text_message`): severity, level and a string of at most 1023 bytes.

use byteorder::{BigEndian, ByteOrder};

/// Length C++ always sends: two u32 and a 1024-byte text buffer.
pub const TEXT_PAYLOAD_LEN: usize = 1032;
/// Longest text, NUL excluded (`vrpn_MAX_TEXT_LEN` − 1).
pub const MAX_TEXT: usize = 1023;

/// Severity of a text message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
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
            TextSeverity::Normal => 0,
            TextSeverity::Warning => 1,
            TextSeverity::Error => 2,
            TextSeverity::Other(c) => c,
        }
    }

    /// From the wire value.
    pub fn from_code(c: u32) -> TextSeverity {
        match c {
            0 => TextSeverity::Normal,
            1 => TextSeverity::Warning,
            2 => TextSeverity::Error,
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

/// Encodes a text payload zero-filled to 1032 bytes. Returns `None` for text too long.
pub fn encode_text(
    out: &mut [u8; TEXT_PAYLOAD_LEN],
    severity: TextSeverity,
    level: u32,
    text: &str,
) -> Option<()> {
    if text.len() > MAX_TEXT {
        return None;
    }
    out.fill(0);
    BigEndian::write_u32(&mut out[0..4], severity.code());
    BigEndian::write_u32(&mut out[4..8], level);
    out[8..8 + text.len()].copy_from_slice(text.as_bytes());
    Some(())
}

/// Decodes a text payload: any length ≥ 9 with a NUL in the first 1024 text bytes.
pub fn decode_text(payload: &[u8]) -> Option<(TextSeverity, u32, &str)> {
    if payload.len() < 9 {
        return None;
    }
    let severity = TextSeverity::from_code(BigEndian::read_u32(&payload[0..4]));
    let level = BigEndian::read_u32(&payload[4..8]);
    let body = &payload[8..payload.len().min(8 + 1024)];
    let end = body.iter().position(|&b| b == 0)?;
    let text = std::str::from_utf8(&body[..end]).ok()?;
    Some((severity, level, text))
}
