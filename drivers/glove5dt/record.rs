//! The glove's records: finding them byte by byte and decoding them.
//!
//! A record is nine or ten bytes: the header `0x80`, five finger values (thumb to little
//! finger, 0..255), pitch and roll (0..255), a byte C++ ignores, and on ten-byte gloves one
//! more. A wireless glove's tenth byte says which hand (`0x01` right, `0x40` left); a record
//! of a wireless glove that ends in anything else is not a record.
//!
//! The [`Framer`] starts a candidate at a `0x80` byte. A wireless candidate with a wrong last
//! byte gives up its first byte only, and the search goes on from the next `0x80` in it, so
//! garbage costs no record after it; each buffered byte keeps the arrival time of its read.
//! The protocol has no checksum C++ checks: a `0x80` in garbage just before a record makes a
//! wrong record, and the real one's header is then found again by the search.

use crate::time::Now;

/// First byte of every record.
pub const HEADER: u8 = 0x80;
/// Longest record.
pub const MAX_RECORD: usize = 10;
/// Channels served: C++'s eight (channel 0 is never set; 1–5 fingers, 6 pitch, 7 roll).
pub const CHANNELS: usize = 8;
/// Last byte of a wireless right glove's record.
pub const WIRELESS_RIGHT: u8 = 0x01;
/// Last byte of a wireless left glove's record.
pub const WIRELESS_LEFT: u8 = 0x40;

/// The channels of a record, as C++ reports them: channel 0 stays 0, channels 1–5 are the
/// fingers / 255, channels 6 and 7 pitch and roll × 180 / 255 (degrees).
pub fn channels(r: &[u8]) -> [f64; CHANNELS] {
    let mut c = [0.0; CHANNELS];
    for i in 1..=5 {
        c[i] = f64::from(r[i]) / 255.0;
    }
    c[6] = 180.0 * f64::from(r[6]) / 255.0;
    c[7] = 180.0 * f64::from(r[7]) / 255.0;
    c
}

/// A record found in the stream.
#[derive(Clone, Copy, Debug)]
pub struct Framed {
    bytes: [u8; MAX_RECORD],
    len: usize,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
}

impl Framed {
    /// The record's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

/// Finds records byte by byte. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    len: usize,
    wireless: bool,
    buf: [u8; MAX_RECORD],
    times: [Option<Now>; MAX_RECORD],
    filled: usize,
    skipped: u64,
    total_skipped: u64,
}

impl Framer {
    /// A framer for records of `len` bytes (9 or 10), checking a wireless glove's last byte.
    pub fn new(len: usize, wireless: bool) -> Framer {
        Framer {
            len: len.clamp(9, MAX_RECORD),
            wireless,
            buf: [0; MAX_RECORD],
            times: [None; MAX_RECORD],
            filled: 0,
            skipped: 0,
            total_skipped: 0,
        }
    }

    /// Forgets a partial record.
    pub fn clear(&mut self) {
        self.filled = 0;
    }

    /// Bytes skipped since the last call (and forgets them).
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn skip(&mut self, n: usize) {
        self.skipped += n as u64;
        self.total_skipped += n as u64;
    }

    /// Takes one byte that arrived at `arrived`; returns a record when it completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if self.filled == 0 && b != HEADER {
            self.skip(1);
            return None;
        }
        self.buf[self.filled] = b;
        self.times[self.filled] = Some(arrived);
        self.filled += 1;
        if self.filled < self.len {
            return None;
        }
        let last = self.buf[self.len - 1];
        if !self.wireless || last == WIRELESS_RIGHT || last == WIRELESS_LEFT {
            self.filled = 0;
            return Some(Framed {
                bytes: self.buf,
                len: self.len,
                first_byte: self.times[0].unwrap_or(arrived),
            });
        }
        // Give up the first byte and everything up to the next header.
        let next = (1..self.len)
            .find(|&i| self.buf[i] == HEADER)
            .unwrap_or(self.len);
        self.skip(next);
        self.buf.copy_within(next..self.len, 0);
        self.times.copy_within(next..self.len, 0);
        self.filled = self.len - next;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    #[test]
    fn records_after_garbage_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new(9, false);
        let rec = [0x80, 255, 0, 51, 102, 204, 0, 255, 7];
        let mut got = Vec::new();
        for (i, chunk) in [&[1u8, 2, 3][..], &rec[..4], &rec[4..], &rec[..]]
            .iter()
            .enumerate()
        {
            for &b in chunk.iter() {
                got.extend(f.push(b, at(i as u64, base)));
            }
        }
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].first_byte, at(1, base));
        assert_eq!(got[1].first_byte, at(3, base));
        assert_eq!(got[0].bytes(), rec);
        assert_eq!(f.total_skipped(), 3);
        let c = channels(got[0].bytes());
        assert_eq!(c, [0.0, 1.0, 0.0, 0.2, 0.4, 0.8, 0.0, 180.0]);
    }

    #[test]
    fn a_wireless_record_must_end_with_the_hand() {
        let base = Instant::now();
        let mut f = Framer::new(10, true);
        let good = [0x80, 1, 2, 3, 4, 5, 6, 7, 8, WIRELESS_LEFT];
        let mut got = Vec::new();
        // A header in garbage: the candidate fails on its last byte, the record after it
        // is found by the rescan.
        for &b in [&[0x80u8, 9, 9][..], &good[..]].concat().iter() {
            got.extend(f.push(b, at(0, base)));
        }
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].bytes(), good);
        assert_eq!(f.total_skipped(), 3);
    }
}
