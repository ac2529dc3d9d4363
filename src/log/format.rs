//! The log entry codec: a 24-byte header of six big-endian words, then the
//! payload, unpadded.
//!
//! ```text
//! type i32 | sender i32 | tv_sec u32 | tv_usec u32 | payload length u32 | zero i32 | payload
//! ```
//! Everything here is pure: byte slices in, borrowed views out. Decoders check lengths before
//! reading and never panic.

use byteorder::{BigEndian, ByteOrder};

use crate::time::TimeVal;
use crate::wire::system::{self, LogDescription};
use crate::wire::{WireError, COOKIE_LEN, MAX_TCP_PADDED_PAYLOAD};

/// Size of an entry header in a log file.
pub const ENTRY_HEADER_LEN: usize = 24;

/// Largest payload length accepted in a log entry, on read and on write.
///
/// C++ cannot send or receive a message with a larger payload over TCP (and UDP is smaller), so a
/// larger length field can only come from a damaged file.
pub const MAX_ENTRY_PAYLOAD: usize = MAX_TCP_PADDED_PAYLOAD;

/// Bytes an entry with a `payload_len`-byte payload occupies in a file.
#[inline]
pub const fn entry_len(payload_len: usize) -> usize {
    ENTRY_HEADER_LEN + payload_len
}

/// The six header words of one log entry, as stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EntryHeader {
    /// Message type id; negative for system messages.
    pub type_id: i32,
    /// Sender id, or for system messages their parameter (described id, UDP port, log mode, 0).
    pub sender: i32,
    /// Timestamp seconds (low 32 bits of `time_t`).
    pub sec: u32,
    /// Timestamp microseconds.
    pub usec: u32,
    /// Payload length in bytes, unpadded.
    pub payload_len: u32,
    /// The sixth word: written as 0 by C++, ignored on read.
    pub zero_word: i32,
}

impl EntryHeader {
    /// A header for a message with the given ids, time and payload length; the sixth word is 0.
    pub fn new(type_id: i32, sender: i32, time: TimeVal, payload_len: usize) -> EntryHeader {
        let (sec, usec) = time.to_wire();
        EntryHeader {
            type_id,
            sender,
            sec,
            usec,
            payload_len: payload_len as u32,
            zero_word: 0,
        }
    }

    /// Decodes the six words at the start of `buf` and checks the payload length against
    /// [`MAX_ENTRY_PAYLOAD`]. Does not look at the payload.
    pub fn decode(buf: &[u8]) -> Result<EntryHeader, EntryProblem> {
        if buf.len() < ENTRY_HEADER_LEN {
            return Err(EntryProblem::TruncatedHeader {
                available: buf.len(),
            });
        }
        let len = BigEndian::read_i32(&buf[16..20]);
        if len < 0 {
            return Err(EntryProblem::NegativeLength(len));
        }
        if len as usize > MAX_ENTRY_PAYLOAD {
            return Err(EntryProblem::LengthTooLong(len as u32));
        }
        Ok(EntryHeader {
            type_id: BigEndian::read_i32(&buf[0..4]),
            sender: BigEndian::read_i32(&buf[4..8]),
            sec: BigEndian::read_u32(&buf[8..12]),
            usec: BigEndian::read_u32(&buf[12..16]),
            payload_len: len as u32,
            zero_word: BigEndian::read_i32(&buf[20..24]),
        })
    }

    /// Writes the six words into `buf[..24]`, the sixth as stored in `zero_word`.
    ///
    /// Returns `None` (writing nothing) when `buf` is shorter than [`ENTRY_HEADER_LEN`].
    pub fn encode(&self, buf: &mut [u8]) -> Option<()> {
        let buf = buf.get_mut(..ENTRY_HEADER_LEN)?;
        BigEndian::write_i32(&mut buf[0..4], self.type_id);
        BigEndian::write_i32(&mut buf[4..8], self.sender);
        BigEndian::write_u32(&mut buf[8..12], self.sec);
        BigEndian::write_u32(&mut buf[12..16], self.usec);
        BigEndian::write_u32(&mut buf[16..20], self.payload_len);
        BigEndian::write_i32(&mut buf[20..24], self.zero_word);
        Some(())
    }

    /// The timestamp, seconds read as unsigned (as a 64-bit C++ reader does).
    pub fn time(&self) -> TimeVal {
        TimeVal::from_header_words(self.sec, self.usec)
    }
}

/// One entry of a log, borrowing its payload from the file's bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogEntry<'a> {
    /// Byte offset of the entry's header from the start of the file (the cookie included).
    pub offset: usize,
    /// The stored header words.
    pub header: EntryHeader,
    /// The payload, exactly `header.payload_len` bytes.
    pub payload: &'a [u8],
}

impl<'a> LogEntry<'a> {
    /// Type id (negative for system messages).
    #[inline]
    pub fn type_id(&self) -> i32 {
        self.header.type_id
    }

    /// Sender id (or the system message's parameter).
    #[inline]
    pub fn sender(&self) -> i32 {
        self.header.sender
    }

    /// The message's timestamp.
    #[inline]
    pub fn time(&self) -> TimeVal {
        self.header.time()
    }

    /// True for system messages (negative type id).
    #[inline]
    pub fn is_system(&self) -> bool {
        self.header.type_id < 0
    }

    /// Bytes the entry occupies in the file.
    #[inline]
    pub fn len_in_file(&self) -> usize {
        entry_len(self.payload.len())
    }

    /// Offset just past the entry: where the next one starts.
    #[inline]
    pub fn end_offset(&self) -> usize {
        self.offset + self.len_in_file()
    }

    /// Decodes a system entry's payload; `None` for user messages (type ≥ 0).
    pub fn system(&self) -> Option<Result<SystemEntry<'a>, WireError>> {
        if self.is_system() {
            Some(SystemEntry::decode(
                self.header.type_id,
                self.header.sender,
                self.payload,
            ))
        } else {
            None
        }
    }
}

/// A decoded system entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SystemEntry<'a> {
    /// Type −1: the log's sender `id` is called `name`.
    SenderDescription {
        /// The id being described.
        id: i32,
        /// Its name.
        name: &'a str,
    },
    /// Type −2: the log's type `id` is called `name`.
    TypeDescription {
        /// The id being described.
        id: i32,
        /// Its name.
        name: &'a str,
    },
    /// Type −3: the peer's UDP address.
    UdpDescription {
        /// UDP port (the header's sender field).
        port: i32,
        /// Host text.
        host: &'a str,
    },
    /// Type −4: a remote-logging request; `mode` is the header's sender field.
    LogDescription {
        /// Requested log mode bits.
        mode: i32,
        /// The requested file names.
        names: LogDescription<'a>,
    },
    /// Type −5: the connection dropped; name tables are cleared.
    Disconnect,
    /// Any other negative type id (unknown to VRPN 07).
    Unknown(i32),
}

impl<'a> SystemEntry<'a> {
    /// Decodes the payload of a system entry of type `type_id` whose header sender field is
    /// `sender`.
    pub fn decode(
        type_id: i32,
        sender: i32,
        payload: &'a [u8],
    ) -> Result<SystemEntry<'a>, WireError> {
        Ok(match type_id {
            system::SENDER_DESCRIPTION => SystemEntry::SenderDescription {
                id: sender,
                name: system::decode_description(payload)?,
            },
            system::TYPE_DESCRIPTION => SystemEntry::TypeDescription {
                id: sender,
                name: system::decode_description(payload)?,
            },
            system::UDP_DESCRIPTION => SystemEntry::UdpDescription {
                port: sender,
                host: system::decode_udp_description(payload)?,
            },
            system::LOG_DESCRIPTION => SystemEntry::LogDescription {
                mode: sender,
                names: system::decode_log_description(payload)?,
            },
            system::DISCONNECT => SystemEntry::Disconnect,
            other => SystemEntry::Unknown(other),
        })
    }
}

/// What is wrong with the bytes where an entry should be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntryProblem {
    /// The file ends inside an entry header.
    TruncatedHeader {
        /// Header bytes present (1..=23).
        available: usize,
    },
    /// The file ends inside an entry's payload.
    TruncatedPayload {
        /// Payload length the header declares.
        payload_len: u32,
        /// Payload bytes present.
        available: usize,
    },
    /// The payload length field is negative.
    NegativeLength(i32),
    /// The payload length field exceeds [`MAX_ENTRY_PAYLOAD`].
    LengthTooLong(u32),
}

impl std::fmt::Display for EntryProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EntryProblem::TruncatedHeader { available } => write!(
                f,
                "file ends inside an entry header ({available} of {ENTRY_HEADER_LEN} bytes)"
            ),
            EntryProblem::TruncatedPayload {
                payload_len,
                available,
            } => write!(
                f,
                "file ends inside an entry payload ({available} of {payload_len} bytes)"
            ),
            EntryProblem::NegativeLength(l) => {
                write!(f, "corrupt entry: negative payload length {l}")
            }
            EntryProblem::LengthTooLong(l) => write!(
                f,
                "corrupt entry: payload length {l} exceeds the limit of {MAX_ENTRY_PAYLOAD} bytes"
            ),
        }
    }
}

impl std::error::Error for EntryProblem {}

/// An [`EntryProblem`] and the file offset of the entry it concerns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EntryFault {
    /// File offset of the damaged entry's first byte.
    pub offset: usize,
    /// What is wrong there.
    pub problem: EntryProblem,
}

impl std::fmt::Display for EntryFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "byte offset {}: {}", self.offset, self.problem)
    }
}

impl std::error::Error for EntryFault {}

/// Decodes the entry at the start of `buf`, whose first byte lies at file offset `offset`.
pub fn decode_entry(buf: &[u8], offset: usize) -> Result<LogEntry<'_>, EntryProblem> {
    let header = EntryHeader::decode(buf)?;
    let len = header.payload_len as usize;
    let rest = &buf[ENTRY_HEADER_LEN..];
    match rest.get(..len) {
        Some(payload) => Ok(LogEntry {
            offset,
            header,
            payload,
        }),
        None => Err(EntryProblem::TruncatedPayload {
            payload_len: header.payload_len,
            available: rest.len(),
        }),
    }
}

/// Writes one entry (header with a zero sixth word, then the payload) at the start of `out`.
///
/// Returns the bytes written, [`entry_len`]`(payload.len())`, or `None` (writing nothing) when
/// `out` is too small or the payload exceeds [`MAX_ENTRY_PAYLOAD`].
pub fn encode_entry(
    out: &mut [u8],
    type_id: i32,
    sender: i32,
    time: TimeVal,
    payload: &[u8],
) -> Option<usize> {
    encode_entry_with_header(
        out,
        &EntryHeader::new(type_id, sender, time, payload.len()),
        payload,
    )
}

/// Writes an entry with an explicit header (e.g. one read from another log, zero word
/// included). `header.payload_len` must equal `payload.len()`; otherwise, or when `out` is too
/// small or the payload too long, writes nothing and returns `None`.
pub fn encode_entry_with_header(
    out: &mut [u8],
    header: &EntryHeader,
    payload: &[u8],
) -> Option<usize> {
    if payload.len() > MAX_ENTRY_PAYLOAD || header.payload_len as usize != payload.len() {
        return None;
    }
    let total = entry_len(payload.len());
    let out = out.get_mut(..total)?;
    header.encode(out)?;
    out[ENTRY_HEADER_LEN..].copy_from_slice(payload);
    Some(total)
}

/// Walks the entries of a log body: the bytes after the cookie.
///
/// Yields each whole entry; on damage yields one [`EntryFault`] and then ends. A body that ends
/// exactly on an entry boundary ends without error.
#[derive(Clone, Debug)]
pub struct EntryWalker<'a> {
    body: &'a [u8],
    pos: usize,
    base: usize,
    done: bool,
}

impl<'a> EntryWalker<'a> {
    /// Walks `body`, whose first byte lies at file offset `base` (normally [`COOKIE_LEN`]).
    pub fn new(body: &'a [u8], base: usize) -> EntryWalker<'a> {
        EntryWalker {
            body,
            pos: 0,
            base,
            done: false,
        }
    }

    /// Walks the entries of a whole file image, skipping its first [`COOKIE_LEN`] bytes without
    /// judging them (an image shorter than the cookie holds no entries).
    pub fn after_cookie(file: &'a [u8]) -> EntryWalker<'a> {
        EntryWalker::new(file.get(COOKIE_LEN..).unwrap_or(&[]), COOKIE_LEN)
    }

    /// File offset of the next entry to decode.
    pub fn offset(&self) -> usize {
        self.base + self.pos
    }
}

impl<'a> Iterator for EntryWalker<'a> {
    type Item = Result<LogEntry<'a>, EntryFault>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let rest = &self.body[self.pos..];
        if rest.is_empty() {
            self.done = true;
            return None;
        }
        let offset = self.offset();
        match decode_entry(rest, offset) {
            Ok(entry) => {
                self.pos += entry.len_in_file();
                Some(Ok(entry))
            }
            Err(problem) => {
                self.done = true;
                Some(Err(EntryFault { offset, problem }))
            }
        }
    }
}

impl std::iter::FusedIterator for EntryWalker<'_> {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encodes_the_manual_example() {
        // The first entry of a C++ server log: a sender description of "Tracker0".
        let mut out = [0xAAu8; 64];
        let payload = b"\0\0\0\x09Tracker0\0";
        let n = encode_entry(
            &mut out,
            -1,
            1,
            TimeVal::new(1_795_308_845, 802_009),
            payload,
        )
        .unwrap();
        assert_eq!(n, 37);
        let expected: [u8; 24] = [
            0xff, 0xff, 0xff, 0xff, 0, 0, 0, 1, 0x6b, 0x02, 0x3d, 0x2d, 0x00, 0x0c, 0x3c, 0xd9, 0,
            0, 0, 0x0d, 0, 0, 0, 0,
        ];
        assert_eq!(&out[..24], &expected);
        assert_eq!(&out[24..37], payload);
        assert_eq!(out[37], 0xAA, "no padding written");
        let e = decode_entry(&out[..37], 24).unwrap();
        assert_eq!(e.offset, 24);
        assert_eq!(e.end_offset(), 61);
        assert_eq!(e.payload, payload);
        assert_eq!(
            e.system().unwrap().unwrap(),
            SystemEntry::SenderDescription {
                id: 1,
                name: "Tracker0"
            }
        );
    }

    #[test]
    fn encode_refuses_small_buffers_and_long_payloads() {
        let mut out = [0u8; 30];
        assert_eq!(encode_entry(&mut out, 4, 1, TimeVal::ZERO, &[1; 7]), None);
        assert_eq!(out, [0u8; 30], "nothing written");
        assert_eq!(
            encode_entry(&mut out, 4, 1, TimeVal::ZERO, &[1; 6]),
            Some(30)
        );
        let big = vec![0u8; MAX_ENTRY_PAYLOAD + 1];
        let mut out = vec![0u8; big.len() + 24];
        assert_eq!(encode_entry(&mut out, 4, 1, TimeVal::ZERO, &big), None);
        let h = EntryHeader::new(4, 1, TimeVal::ZERO, 3);
        assert_eq!(encode_entry_with_header(&mut out, &h, &[0; 2]), None);
    }

    #[test]
    fn bad_lengths_are_reported() {
        let mut buf = [0u8; 40];
        encode_entry(&mut buf, 5, 0, TimeVal::ZERO, &[9; 16]).unwrap();
        BigEndian::write_i32(&mut buf[16..20], -3);
        assert_eq!(decode_entry(&buf, 0), Err(EntryProblem::NegativeLength(-3)));
        BigEndian::write_u32(&mut buf[16..20], 70_000);
        assert_eq!(
            decode_entry(&buf, 0),
            Err(EntryProblem::LengthTooLong(70_000))
        );
        BigEndian::write_u32(&mut buf[16..20], 17);
        assert_eq!(
            decode_entry(&buf, 0),
            Err(EntryProblem::TruncatedPayload {
                payload_len: 17,
                available: 16
            })
        );
        assert_eq!(
            decode_entry(&buf[..5], 0),
            Err(EntryProblem::TruncatedHeader { available: 5 })
        );
    }

    #[test]
    fn walker_stops_at_damage() {
        let mut file = vec![0u8; 24];
        let mut entry = [0u8; 40];
        for i in 0..3 {
            let n =
                encode_entry(&mut entry, i, 0, TimeVal::new(1, i as i64), &[i as u8; 3]).unwrap();
            file.extend_from_slice(&entry[..n]);
        }
        let all: Vec<_> = EntryWalker::after_cookie(&file).collect();
        assert_eq!(all.len(), 3);
        assert!(all.iter().all(|r| r.is_ok()));
        let cut = &file[..file.len() - 1];
        let mut w = EntryWalker::after_cookie(cut);
        assert!(w.next().unwrap().is_ok());
        assert!(w.next().unwrap().is_ok());
        assert_eq!(
            w.next().unwrap(),
            Err(EntryFault {
                offset: 24 + 2 * 27,
                problem: EntryProblem::TruncatedPayload {
                    payload_len: 3,
                    available: 2
                }
            })
        );
        assert_eq!(w.next(), None);
        assert_eq!(EntryWalker::after_cookie(&file[..10]).count(), 0);
    }

    #[test]
    fn never_panics_on_garbage() {
        let mut seed = 0x1234_5678u32;
        for len in 0..300 {
            let buf: Vec<u8> = (0..len)
                .map(|_| {
                    seed ^= seed << 13;
                    seed ^= seed >> 17;
                    seed ^= seed << 5;
                    (seed >> 24) as u8
                })
                .collect();
            for e in EntryWalker::after_cookie(&buf).flatten() {
                let _ = e.system();
            }
        }
    }
}
