//! Text messages (`vrpn_Base text_message`) as devices send and receive them: a severity, a
//! level and a string of at most 1023 bytes, always sent as a zero-filled 1032-byte payload.
//!
//! The codec is [`crate::wire::payload::text`]; these are the string-level conveniences the
//! devices use.

use crate::wire::payload::text::TextMessage;
pub use crate::wire::payload::text::{TextSeverity, MAX_TEXT_LEN as MAX_TEXT, TEXT_PAYLOAD_LEN};

/// Encodes a text payload zero-filled to 1032 bytes. Returns `None` for text too long (over
/// 1023 bytes) or holding a NUL.
pub fn encode_text(
    out: &mut [u8; TEXT_PAYLOAD_LEN],
    severity: TextSeverity,
    level: u32,
    text: &str,
) -> Option<()> {
    let m = TextMessage::new(severity.code(), level, text.as_bytes()).ok()?;
    m.encode(out);
    Some(())
}

/// Decodes a text payload (any length ≥ 9 with a NUL in the first 1024 text bytes) whose text
/// is UTF-8.
pub fn decode_text(payload: &[u8]) -> Option<(TextSeverity, u32, &str)> {
    let m = TextMessage::decode(payload).ok()?;
    Some((TextSeverity::from_code(m.severity), m.level, m.as_str()?))
}
