//! Shared object messages (`vrpn_Shared_int32`, `vrpn_Shared_float64`, `vrpn_Shared_String`).
//! A shared object is not a `vrpn_BaseClass`: no text, ping or pong.
//!
//! Each object registers two senders, `vrpn Shared server <type> <name>` and
//! `vrpn Shared peer <type> <name>` (type `int32`, `float64` or `String`; C++ cuts type and
//! name to 100 bytes each): the server side sends from the first and listens to the second,
//! the remote side the other way round. The update carries the value and the time of the
//! change in its payload (clock synchronisation rewrites header times, and the time is the
//! object's version). The three serializer messages are empty.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result};
use crate::time::TimeVal;

/// A new value, either direction ([`IntUpdate`], [`FloatUpdate`], [`StringUpdate`]).
pub const UPDATE: &str = "vrpn_Shared update";
/// "Let me serialize", empty.
pub const REQUEST_SERIALIZER: &str = "vrpn_Shared request_serializer";
/// "You may", empty.
pub const GRANT_SERIALIZER: &str = "vrpn_Shared grant_serializer";
/// "I do now", empty.
pub const ASSUME_SERIALIZER: &str = "vrpn_Shared assume_serializer";

/// The shared object type names in C++ registration order (after the two senders).
pub const TYPE_NAMES: &[&str] = &[
    UPDATE,
    REQUEST_SERIALIZER,
    GRANT_SERIALIZER,
    ASSUME_SERIALIZER,
];

/// Type word of `vrpn_Shared_int32` in its sender names.
pub const INT32: &str = "int32";
/// Type word of `vrpn_Shared_float64`.
pub const FLOAT64: &str = "float64";
/// Type word of `vrpn_Shared_String`.
pub const STRING: &str = "String";

/// Longest string value a C++ peer sends or receives: its 1024-byte buffers less the time.
pub const MAX_STRING_LEN: usize = 1024 - 8;

/// The sender name of the server side of the object `name` of type `type_word`.
pub fn server_sender(type_word: &str, name: &str) -> String {
    format!("vrpn Shared server {} {}", cut(type_word), cut(name))
}

/// The sender name of the remote side.
pub fn peer_sender(type_word: &str, name: &str) -> String {
    format!("vrpn Shared peer {} {}", cut(type_word), cut(name))
}

/// C++ formats each part with `%.100s`: at most 100 bytes (cut on a character boundary here).
fn cut(s: &str) -> &str {
    let mut n = s.len().min(100);
    while !s.is_char_boundary(n) {
        n -= 1;
    }
    &s[..n]
}

fn read_time(buf: &[u8]) -> TimeVal {
    TimeVal {
        sec: i64::from(BigEndian::read_i32(&buf[0..4])),
        usec: i64::from(BigEndian::read_i32(&buf[4..8])),
    }
}

fn write_time(t: TimeVal, out: &mut [u8]) {
    BigEndian::write_i32(&mut out[0..4], t.sec as i32);
    BigEndian::write_i32(&mut out[4..8], t.usec as i32);
}

/// `vrpn_Shared update` of an int32: i32 value, then the time of the change (i32 seconds,
/// i32 microseconds). 12 bytes; C++ checks no length (at least 12 here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IntUpdate {
    /// The value.
    pub value: i32,
    /// When it was set (the object's version).
    pub when: TimeVal,
}

impl IntUpdate {
    /// Payload length.
    pub const LEN: usize = 12;

    /// Decodes an update (at least 12 bytes).
    pub fn decode(buf: &[u8]) -> Result<IntUpdate> {
        need(buf, Self::LEN)?;
        Ok(IntUpdate {
            value: BigEndian::read_i32(&buf[0..4]),
            when: read_time(&buf[4..12]),
        })
    }

    /// Writes the 12 bytes; returns 12.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_i32(&mut out[0..4], self.value);
        write_time(self.when, &mut out[4..12]);
        Self::LEN
    }
}

/// `vrpn_Shared update` of a float64: f64 value, then the time (i32 seconds, i32
/// microseconds). 16 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloatUpdate {
    /// The value.
    pub value: f64,
    /// When it was set.
    pub when: TimeVal,
}

impl FloatUpdate {
    /// Payload length.
    pub const LEN: usize = 16;

    /// Decodes an update (at least 16 bytes).
    pub fn decode(buf: &[u8]) -> Result<FloatUpdate> {
        need(buf, Self::LEN)?;
        Ok(FloatUpdate {
            value: BigEndian::read_f64(&buf[0..8]),
            when: read_time(&buf[8..16]),
        })
    }

    /// Writes the 16 bytes; returns 16.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_f64(&mut out[0..8], self.value);
        write_time(self.when, &mut out[8..16]);
        Self::LEN
    }
}

/// `vrpn_Shared update` of a String: the time first (so that it is aligned), then the
/// string's bytes with no NUL; the string is the rest of the payload.
///
/// A C++ receiver on a 64-bit host subtracts `sizeof(timeval)` (16, not the 8 on the wire)
/// from the payload length, so it keeps all but the last 8 bytes of a string of 8 bytes or
/// more; this decoder keeps all of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StringUpdate<'a> {
    /// The value's bytes.
    pub value: &'a [u8],
    /// When it was set.
    pub when: TimeVal,
}

impl<'a> StringUpdate<'a> {
    /// Decodes an update (at least 8 bytes). A NUL inside ends the string, as it would in C.
    pub fn decode(buf: &'a [u8]) -> Result<StringUpdate<'a>> {
        need(buf, 8)?;
        let rest = &buf[8..];
        let n = rest.iter().position(|&b| b == 0).unwrap_or(rest.len());
        Ok(StringUpdate {
            value: &rest[..n],
            when: read_time(&buf[0..8]),
        })
    }

    /// Payload length: 8 + the string.
    pub fn encoded_len(&self) -> usize {
        8 + self.value.len()
    }

    /// Writes the payload at the start of `out` (at least [`Self::encoded_len`] bytes).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        write_time(self.when, &mut out[0..8]);
        out[8..8 + self.value.len()].copy_from_slice(self.value);
        self.encoded_len()
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::hex;
    use super::*;

    #[test]
    fn layouts() {
        let t = TimeVal {
            sec: 0x5f000000,
            usec: 250_000,
        };
        let mut buf = [0u8; 32];
        let n = IntUpdate { value: -3, when: t }.encode(&mut buf);
        assert_eq!(&buf[..n], &hex("fffffffd 5f000000 0003d090")[..]);
        assert_eq!(
            IntUpdate::decode(&buf[..n]).unwrap(),
            IntUpdate { value: -3, when: t }
        );
        assert!(IntUpdate::decode(&buf[..11]).is_err());
        let n = FloatUpdate {
            value: 0.5,
            when: t,
        }
        .encode(&mut buf);
        assert_eq!(&buf[..n], &hex("3fe0000000000000 5f000000 0003d090")[..]);
        assert_eq!(FloatUpdate::decode(&buf[..n]).unwrap().value, 0.5);
        assert!(FloatUpdate::decode(&buf[..15]).is_err());
        let s = StringUpdate {
            value: b"hello",
            when: t,
        };
        let n = s.encode(&mut buf);
        assert_eq!(n, 13);
        assert_eq!(&buf[..n], &hex("5f000000 0003d090 68656c6c6f")[..]);
        assert_eq!(StringUpdate::decode(&buf[..n]).unwrap(), s);
        assert_eq!(StringUpdate::decode(&buf[..8]).unwrap().value, b"");
        assert!(StringUpdate::decode(&buf[..7]).is_err());
    }

    #[test]
    fn sender_names() {
        assert_eq!(server_sender(INT32, "a"), "vrpn Shared server int32 a");
        assert_eq!(peer_sender(STRING, "x y"), "vrpn Shared peer String x y");
        let long = "n".repeat(150);
        assert_eq!(server_sender(FLOAT64, &long).len(), 27 + 100);
    }
}
