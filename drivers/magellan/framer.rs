//! Finding Magellan records in the byte stream, one byte at a time.
//!
//! A record starts with a known letter, has the length that letter gives, carries only
//! nibble characters, and ends with CR. A byte that breaks these rules ends the record being
//! collected (which is dropped), and is itself looked at as a possible record start, so
//! garbage costs at most the record it hits and never a later one. The record's time is the
//! arrival of its letter.

use super::record::{is_nibble_char, record_len, CR, MAX_RECORD};
use crate::time::Now;

/// Why bytes were dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Problem {
    /// A byte that starts no record where a record should start.
    NotRecordStart(u8),
    /// A byte that is not a data character inside a record.
    BadCharacter(u8),
    /// The last byte of a record was not CR.
    NoCarriageReturn(u8),
}

/// One complete record.
#[derive(Clone, Copy, Debug)]
pub struct Record {
    bytes: [u8; MAX_RECORD],
    len: usize,
    /// When the poll woke for its first byte.
    pub first_byte: Now,
}

impl Record {
    /// The record, letter and CR included.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    /// Its letter.
    pub fn letter(&self) -> u8 {
        self.bytes[0]
    }
}

impl PartialEq for Record {
    fn eq(&self, other: &Record) -> bool {
        self.bytes() == other.bytes() && self.first_byte == other.first_byte
    }
}

impl Eq for Record {}

/// Bytes dropped before a record, and the first reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// How many.
    pub bytes: u64,
    /// Why the first of them was dropped.
    pub first: Problem,
}

/// A record and what was dropped since the previous one.
#[derive(Clone, Copy, Debug)]
pub struct Framed {
    /// The record.
    pub record: Record,
    /// Garbage dropped between the previous record and this one.
    pub skipped: Option<Skipped>,
}

/// The framing state.
#[derive(Debug)]
pub struct Framer {
    buf: [u8; MAX_RECORD],
    len: usize,
    want: usize,
    first_byte: Option<Now>,
    skipped: Option<Skipped>,
    total_skipped: u64,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// Waiting for a record start.
    pub fn new() -> Framer {
        Framer {
            buf: [0; MAX_RECORD],
            len: 0,
            want: 0,
            first_byte: None,
            skipped: None,
            total_skipped: 0,
        }
    }

    /// Forgets any partial record and pending garbage count (after a flush or reopen).
    pub fn clear(&mut self) {
        self.len = 0;
        self.want = 0;
        self.first_byte = None;
        self.skipped = None;
    }

    /// Bytes dropped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if self.want == 0 {
            self.start(b, arrived);
            return None;
        }
        if self.len + 1 == self.want {
            if b != CR {
                self.drop_partial(Problem::NoCarriageReturn(b));
                self.start(b, arrived);
                return None;
            }
            self.buf[self.len] = b;
            let record = Record {
                bytes: self.buf,
                len: self.want,
                first_byte: self.first_byte.unwrap_or(arrived),
            };
            self.len = 0;
            self.want = 0;
            self.first_byte = None;
            return Some(Framed {
                record,
                skipped: self.skipped.take(),
            });
        }
        if !is_nibble_char(b) {
            self.drop_partial(Problem::BadCharacter(b));
            self.start(b, arrived);
            return None;
        }
        self.buf[self.len] = b;
        self.len += 1;
        None
    }

    fn start(&mut self, b: u8, arrived: Now) {
        match record_len(b) {
            Some(n) => {
                self.buf[0] = b;
                self.len = 1;
                self.want = n;
                self.first_byte = Some(arrived);
            }
            None => self.skip(1, Problem::NotRecordStart(b)),
        }
    }

    fn drop_partial(&mut self, why: Problem) {
        let n = self.len as u64;
        self.len = 0;
        self.want = 0;
        self.first_byte = None;
        self.skip(n, why);
    }

    fn skip(&mut self, n: u64, why: Problem) {
        self.total_skipped += n;
        match &mut self.skipped {
            Some(s) => s.bytes += n,
            None => {
                self.skipped = Some(Skipped {
                    bytes: n,
                    first: why,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::super::record::{encode_axes, encode_keys};
    use super::*;
    use crate::time::TimeVal;

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(1000, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn frame_all(f: &mut Framer, bytes: &[u8], t: Now) -> Vec<Framed> {
        bytes.iter().filter_map(|&b| f.push(b, t)).collect()
    }

    #[test]
    fn records_in_pieces_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new();
        let d = encode_axes(&[1, 2, 3, 4, 5, 6]);
        assert!(frame_all(&mut f, &d[..10], at(1, base)).is_empty());
        let got = frame_all(&mut f, &d[10..], at(7, base));
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].record.bytes(), &d[..]);
        assert_eq!(got[0].record.first_byte, at(1, base));
        assert!(got[0].skipped.is_none());
        let got = frame_all(&mut f, b"z\rb\rnH\r", at(9, base));
        let letters: Vec<u8> = got.iter().map(|g| g.record.letter()).collect();
        assert_eq!(letters, b"zbn");
    }

    #[test]
    fn garbage_costs_only_the_record_it_hits() {
        let base = Instant::now();
        let mut f = Framer::new();
        let k = encode_keys(0x155);
        let d = encode_axes(&[-7000, 0, 9, 100, -100, 7000]);
        let mut stream = Vec::new();
        stream.extend_from_slice(b"\x00xy");
        // A key record cut short by an axis record: the key record is lost, the axis kept.
        stream.extend_from_slice(&k[..3]);
        stream.extend_from_slice(&d);
        // An axis record with a bad character, then a key record.
        let mut bad = d;
        bad[9] = b'1';
        stream.extend_from_slice(&bad);
        stream.extend_from_slice(&k);
        // No CR where it belongs, then a good key record right after.
        stream.extend_from_slice(&k[..4]);
        stream.push(b'A');
        stream.extend_from_slice(&k);
        let got = frame_all(&mut f, &stream, at(0, base));
        let recs: Vec<&[u8]> = got.iter().map(|g| g.record.bytes()).collect();
        assert_eq!(recs, vec![&d[..], &k[..], &k[..]]);
        assert_eq!(
            got[0].skipped,
            Some(Skipped {
                bytes: 6,
                first: Problem::NotRecordStart(0)
            })
        );
        // The bad axis record's 9 bytes, the '1', and the following data characters up to
        // the key record's letter.
        let s1 = got[1].skipped.unwrap();
        assert_eq!(s1.first, Problem::BadCharacter(b'1'));
        assert_eq!(s1.bytes, 26);
        let s2 = got[2].skipped.unwrap();
        assert_eq!(s2.first, Problem::NoCarriageReturn(b'A'));
        assert_eq!(s2.bytes, 5);
        assert_eq!(f.total_skipped(), 6 + 26 + 5);
    }
}
