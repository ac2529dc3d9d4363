//! The pure VRPN 07.x codec: byte slices in, typed values out, and back. No I/O, no allocation.
//!
//! Message framing, the cookie and the system messages are here; device payloads are in
//! [`payload`]. Every decoder checks lengths before reading, so no decoder panics on any input;
//! the fuzz targets hold it to that. All multi-byte fields are big-endian, and every message is
//! a 24-byte header (length, seconds, microseconds, sender, type, sequence) followed by its
//! payload padded to a multiple of 8 bytes.

pub mod cookie;
pub mod framing;
pub mod header;
pub mod lob;
pub mod payload;
pub mod system;

pub use cookie::{Cookie, CookieError, COOKIE_LEN};
pub use framing::{DatagramMessages, StreamDecoder};
pub use header::{padded_len, Header, HEADER_LEN};

/// Alignment of header and payload on the wire (`vrpn_ALIGN`).
pub const ALIGN: usize = 8;
/// Largest message a C++ peer can send on TCP, header and padding included.
pub const MAX_TCP_MESSAGE: usize = 64_000;
/// Largest payload a VRPN peer can receive over TCP (its 64000-byte buffer less the header).
pub const MAX_PAYLOAD: usize = MAX_TCP_MESSAGE - HEADER_LEN;
/// Largest padded payload a C++ receiver accepts on TCP (`d_tcpAlignedInbuf`).
pub const MAX_TCP_PADDED_PAYLOAD: usize = 64_008;
/// Largest UDP datagram a C++ peer sends (Ethernet MTU less IP and UDP headers).
pub const MAX_UDP_DATAGRAM: usize = 1472;
/// Largest UDP datagram a C++ peer receives in full.
pub const MAX_UDP_INBOUND: usize = 1480;
/// Longest sender or type name that survives a C++ peer (`vrpn_CNAME_LENGTH` less overhead).
pub const MAX_NAME_LEN: usize = 95;
/// Most sender ids and type ids per side (`vrpn_CONNECTION_MAX_SENDERS` / `_TYPES`).
pub const MAX_IDS: usize = 2000;
/// Default UDP and TCP port of a VRPN server.
pub const DEFAULT_PORT: u16 = 3883;

/// Class of service bits (`vrpn_CONNECTION_*`). Only RELIABLE decides the channel.
pub mod class {
    /// Must arrive, in order: sent over TCP.
    pub const RELIABLE: u32 = 1;
    /// Hint only.
    pub const FIXED_LATENCY: u32 = 2;
    /// Prefer fast, may drop: sent over UDP once the peer announced a UDP port.
    pub const LOW_LATENCY: u32 = 4;
    /// Hint only.
    pub const FIXED_THROUGHPUT: u32 = 8;
    /// Hint only.
    pub const HIGH_THROUGHPUT: u32 = 16;
}

/// Why bytes could not be decoded. Small and `Copy`: carried in events and error messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WireError {
    /// Fewer bytes than the structure needs.
    Truncated {
        /// Bytes the structure needs.
        needed: usize,
        /// Bytes that were there.
        available: usize,
    },
    /// The header's length field is below the 24-byte header size.
    LengthTooShort(u32),
    /// The header's length field exceeds what a C++ peer may send.
    LengthTooLong(u32),
    /// A string field lacks its NUL terminator.
    MissingNul,
    /// A name longer than a C++ peer accepts.
    NameTooLong(usize),
    /// A field holds a value outside its range.
    BadValue(&'static str),
}

impl std::fmt::Display for WireError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WireError::Truncated { needed, available } => {
                write!(f, "truncated: needed {needed} bytes, had {available}")
            }
            WireError::LengthTooShort(l) => {
                write!(f, "message length field {l} is shorter than the 24-byte header")
            }
            WireError::LengthTooLong(l) => write!(
                f,
                "message length field {l} exceeds the VRPN limit of {MAX_TCP_PADDED_PAYLOAD} payload bytes"
            ),
            WireError::MissingNul => write!(f, "string without NUL terminator"),
            WireError::NameTooLong(n) => {
                write!(f, "name of {n} bytes exceeds the {MAX_NAME_LEN}-byte limit")
            }
            WireError::BadValue(what) => write!(f, "bad value in {what}"),
        }
    }
}

impl std::error::Error for WireError {}

/// Shorthand for codec results.
pub type Result<T> = std::result::Result<T, WireError>;

/// Checks that `buf` holds at least `needed` bytes.
#[inline]
pub(crate) fn need(buf: &[u8], needed: usize) -> Result<()> {
    if buf.len() < needed {
        Err(WireError::Truncated {
            needed,
            available: buf.len(),
        })
    } else {
        Ok(())
    }
}

/// Reads a NUL-terminated string starting at the beginning of `buf`, returning it without the NUL.
pub(crate) fn c_str(buf: &[u8]) -> Result<&[u8]> {
    match buf.iter().position(|&b| b == 0) {
        Some(n) => Ok(&buf[..n]),
        None => Err(WireError::MissingNul),
    }
}
