//! Finding Liberty / Patriot records in the byte stream, one byte at a time.
//!
//! A record starts with `LY`, `PA` or `LU`; its third byte is the station, which gives its
//! length (a station with a stylus has four bytes more); its last byte is a space. A candidate
//! that fails (a station the tracker does not have, no space at the end) gives up only its
//! first byte: the bytes after it are searched again for a start, so a record that follows
//! garbage, or hides in a broken one, is still found (C++ VRPN flushes the whole input buffer
//! instead). Each buffered byte keeps the arrival time of its read: a record carries the time
//! of its own first byte.

use super::record::{self, Pose, HEADER_LEN, STATIONS, STYLUS_RECORD_LEN};
use crate::time::Now;

/// Why a candidate was given up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Invalid {
    /// A station outside 1..=8 (the byte as received).
    Station(u8),
    /// The last byte was not a space (the byte as received).
    NoSpace(u8),
}

/// A record found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// Its values.
    pub pose: Pose,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped since the previous record.
    pub skipped: u32,
    /// Why the last candidate before it was given up, if one was.
    pub rejected: Option<Invalid>,
}

/// The byte-wise record finder. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    /// Stations whose records carry the stylus field.
    stylus: [bool; STATIONS],
    buf: [u8; STYLUS_RECORD_LEN],
    times: [Option<Now>; STYLUS_RECORD_LEN],
    len: usize,
    skipped: u32,
    rejected: Option<Invalid>,
    total_skipped: u64,
}

impl Framer {
    /// A framer whose stations `stylus[i]` (sensor *i*) carry the stylus field.
    pub fn new(stylus: [bool; STATIONS]) -> Framer {
        Framer {
            stylus,
            buf: [0; STYLUS_RECORD_LEN],
            times: [None; STYLUS_RECORD_LEN],
            len: 0,
            skipped: 0,
            rejected: None,
            total_skipped: 0,
        }
    }

    /// Forgets a partial record.
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
        self.rejected = None;
    }

    /// Bytes dropped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    /// The length of a record from `station`, if the tracker has it.
    fn record_len(&self, station: u8) -> Option<usize> {
        let sensor = usize::from(station).checked_sub(1)?;
        let stylus = *self.stylus.get(sensor)?;
        Some(if stylus {
            STYLUS_RECORD_LEN
        } else {
            record::RECORD_LEN
        })
    }

    /// Whether the buffered bytes can still be the start of a record (`Err`: why not), and
    /// the record's length once the station is in.
    fn check(&self) -> Result<Option<usize>, Option<Invalid>> {
        if !record::is_first(self.buf[0]) {
            return Err(None);
        }
        if self.len < 2 {
            return Ok(None);
        }
        if !record::is_start(self.buf[0], self.buf[1]) {
            return Err(None);
        }
        if self.len < 3 {
            return Ok(None);
        }
        match self.record_len(self.buf[2]) {
            Some(n) => Ok(Some(n)),
            None => Err(Some(Invalid::Station(self.buf[2]))),
        }
    }

    /// Drops the first buffered byte and whatever after it cannot start a record, keeping
    /// the rest (with their times) to look at again.
    fn give_up_first(&mut self) {
        let next = (1..self.len)
            .find(|&i| record::is_first(self.buf[i]))
            .unwrap_or(self.len);
        self.skipped = self.skipped.saturating_add(next as u32);
        self.total_skipped += next as u64;
        self.buf.copy_within(next..self.len, 0);
        self.times.copy_within(next..self.len, 0);
        self.len -= next;
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        loop {
            if self.len == 0 {
                return None;
            }
            let want = match self.check() {
                Ok(None) => return None,
                Ok(Some(n)) => n,
                Err(why) => {
                    if why.is_some() {
                        self.rejected = why;
                    }
                    self.give_up_first();
                    continue;
                }
            };
            if self.len < want {
                return None;
            }
            let last = self.buf[want - 1];
            if last != b' ' {
                self.rejected = Some(Invalid::NoSpace(last));
                self.give_up_first();
                continue;
            }
            let framed = Framed {
                pose: record::decode(&self.buf[..want]),
                first_byte: self.times[0].unwrap_or(arrived),
                skipped: std::mem::take(&mut self.skipped),
                rejected: self.rejected.take(),
            };
            // Nothing can follow the completing byte in the buffer.
            self.len = 0;
            debug_assert!(want >= HEADER_LEN);
            return Some(framed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::liberty::record::encode;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn rec(start: &[u8; 2], station: u8, stylus: Option<u32>) -> Vec<u8> {
        let mut v = Vec::new();
        encode(
            *start,
            station,
            [1.0, 2.0, 3.0],
            [1.0, 0.0, 0.0, 0.0],
            station.into(),
            stylus,
            &mut v,
        );
        v
    }

    #[test]
    fn records_are_found_after_garbage_false_starts_and_broken_records() {
        let base = Instant::now();
        let mut stylus = [false; STATIONS];
        stylus[1] = true;
        let mut f = Framer::new(stylus);
        let mut out = Vec::new();
        let mut feed = |bytes: &[u8], ms: u64, out: &mut Vec<Framed>| {
            for &b in bytes {
                out.extend(f.push(b, at(ms, base)));
            }
        };
        feed(b"xxLPL", 0, &mut out);
        feed(&rec(b"LY", 1, None), 1, &mut out);
        // A station-2 record with the stylus field, split over two reads.
        let two = rec(b"PA", 2, Some(1));
        feed(&two[..10], 2, &mut out);
        feed(&two[10..], 3, &mut out);
        // A record cut short (no space where it should end), then a whole one: the cut one's
        // bytes are searched again and the next is found.
        let three = rec(b"LU", 3, None);
        feed(&three[..20], 4, &mut out);
        feed(&three, 5, &mut out);
        // A station the tracker does not have.
        feed(&rec(b"LY", 9, None)[..3], 6, &mut out);
        feed(&rec(b"LY", 8, None), 7, &mut out);
        let got: Vec<(usize, Option<bool>, u32, Now)> = out
            .iter()
            .map(|r| (r.pose.sensor, r.pose.stylus, r.skipped, r.first_byte))
            .collect();
        assert_eq!(
            got,
            [
                (0, None, 5, at(1, base)),
                (1, Some(true), 0, at(2, base)),
                (2, None, 20, at(5, base)),
                (7, None, 3, at(7, base)),
            ]
        );
        assert_eq!(out[3].rejected, Some(Invalid::Station(9)));
        assert_eq!(f.total_skipped(), 28);
    }
}
