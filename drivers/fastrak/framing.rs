//! Finding records in the byte stream, one byte at a time, and finding them again after
//! garbage without losing the records that follow it.
//!
//! A candidate record starts at a `'0'`. Each byte is checked as soon as it arrives: the
//! station must be one the driver configured, the status a space or a letter, and the byte at
//! the station's record length a space. When a check fails, C++ throws away everything the
//! port has buffered; we instead drop only the candidate's `'0'` and look for the next `'0'`
//! among the bytes already held, so a record that begins inside a broken one is still found.
//!
//! Every byte keeps the time of the read that carried it, so a record is stamped with the
//! arrival of its first byte even when it completes several reads later or is found by a
//! rescan.

use super::record::{Record, StationFormat, MAX_RECORD_LEN, MAX_STATIONS};
use crate::time::Now;

/// Why bytes were dropped while looking for a record (the first reason of a resync episode).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reject {
    /// Looking for `'0'`, found this byte.
    NotRecordStart(u8),
    /// The station byte is not a configured station.
    BadStation(u8),
    /// The status byte is neither a space nor a letter.
    BadStatus(u8),
    /// The byte where the record should end is not a space.
    NoClosingSpace(u8),
}

/// Bytes dropped before a record was found again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resync {
    /// The first problem seen.
    pub reason: Reject,
    /// How many bytes were dropped.
    pub skipped: u64,
}

/// A complete, valid record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// The decoded record.
    pub record: Record,
    /// When its first byte arrived.
    pub first_byte: Now,
    /// The garbage dropped just before it, if any.
    pub resync: Option<Resync>,
}

/// The record framer: bytes in, [`Framed`] records out. Fixed buffers, no allocation.
#[derive(Clone, Debug)]
pub struct Framer {
    /// Record length per station (index = station − 1); 0 for stations not configured.
    lens: [usize; MAX_STATIONS],
    formats: [StationFormat; MAX_STATIONS],
    window: [u8; MAX_RECORD_LEN],
    times: [Option<Now>; MAX_RECORD_LEN],
    len: usize,
    /// Bytes of the window already checked as a prefix of the candidate.
    checked: usize,
    /// Length of the candidate once its station byte is known.
    expected: usize,
    resync: Option<Resync>,
    total_skipped: u64,
}

impl Framer {
    /// A framer for stations `1..=formats.len()` with these record layouts.
    pub fn new(formats: &[StationFormat]) -> Framer {
        assert!(!formats.is_empty() && formats.len() <= MAX_STATIONS);
        let mut lens = [0; MAX_STATIONS];
        let mut fmts = [StationFormat::PLAIN; MAX_STATIONS];
        for (i, f) in formats.iter().enumerate() {
            lens[i] = f.record_len();
            fmts[i] = *f;
        }
        Framer {
            lens,
            formats: fmts,
            window: [0; MAX_RECORD_LEN],
            times: [None; MAX_RECORD_LEN],
            len: 0,
            checked: 0,
            expected: 0,
            resync: None,
            total_skipped: 0,
        }
    }

    /// Forgets any partial record (after a reset or a reopen).
    pub fn clear(&mut self) {
        self.len = 0;
        self.checked = 0;
        self.expected = 0;
        self.resync = None;
    }

    /// Bytes dropped in total since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn station_len(&self, b: u8) -> Option<usize> {
        let i = b.checked_sub(b'1')? as usize;
        self.lens.get(i).copied().filter(|&l| l > 0)
    }

    /// Adds one byte that arrived in the read at `at`. Call [`next_record`](Self::next_record)
    /// until it returns `None` before pushing the next byte.
    pub fn push(&mut self, byte: u8, at: Now) {
        if self.len == MAX_RECORD_LEN {
            // Only reachable if the caller skipped next_record; keep the newest bytes.
            self.drop_front(1, Reject::NotRecordStart(self.window[0]));
        }
        self.window[self.len] = byte;
        self.times[self.len] = Some(at);
        self.len += 1;
    }

    /// The next complete record among the bytes pushed so far, if any.
    pub fn next_record(&mut self) -> Option<Framed> {
        while self.checked < self.len {
            let i = self.checked;
            let b = self.window[i];
            let problem = match i {
                0 => (b != b'0').then_some(Reject::NotRecordStart(b)),
                1 => match self.station_len(b) {
                    Some(l) => {
                        self.expected = l;
                        None
                    }
                    None => Some(Reject::BadStation(b)),
                },
                2 => (b != b' ' && !b.is_ascii_alphabetic()).then_some(Reject::BadStatus(b)),
                _ if i + 1 == self.expected => (b != b' ').then_some(Reject::NoClosingSpace(b)),
                _ => None,
            };
            if let Some(reason) = problem {
                self.reject(reason);
                continue;
            }
            self.checked += 1;
            if self.checked == self.expected {
                return Some(self.take_record());
            }
        }
        None
    }

    fn take_record(&mut self) -> Framed {
        let n = self.expected;
        let station = self.window[1] - b'1';
        let record = Record::decode(&self.window[..n], &self.formats[station as usize]);
        let first_byte = self.times[0].expect("every held byte has a time");
        self.window.copy_within(n..self.len, 0);
        self.times.copy_within(n..self.len, 0);
        self.len -= n;
        self.checked = 0;
        self.expected = 0;
        Framed {
            record,
            first_byte,
            resync: self.resync.take(),
        }
    }

    /// Drops the candidate's start and every following byte up to the next `'0'`.
    fn reject(&mut self, reason: Reject) {
        let next_start = self.window[1..self.len]
            .iter()
            .position(|&b| b == b'0')
            .map_or(self.len, |p| p + 1);
        self.drop_front(next_start, reason);
    }

    fn drop_front(&mut self, n: usize, reason: Reject) {
        self.window.copy_within(n..self.len, 0);
        self.times.copy_within(n..self.len, 0);
        self.len -= n;
        self.checked = 0;
        self.expected = 0;
        self.total_skipped += n as u64;
        let r = self.resync.get_or_insert(Resync { reason, skipped: 0 });
        r.skipped += n as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::super::record::ButtonFormat;
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn record(station: u8, x: f32) -> Vec<u8> {
        let mut b = vec![b'0', b'0' + station, b' '];
        for v in [x, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.push(b' ');
        b
    }

    fn at(base: Instant, ms: u64) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(1000, 0).plus(Duration::from_millis(ms)),
        }
    }

    /// Feeds `chunks` (each arriving at its index in ms) and returns (station, x, arrival ms).
    fn run(framer: &mut Framer, chunks: &[Vec<u8>]) -> Vec<(u8, f32, u64)> {
        let base = Instant::now();
        let mut out = Vec::new();
        for (i, chunk) in chunks.iter().enumerate() {
            for &b in chunk {
                framer.push(b, at(base, i as u64));
                while let Some(f) = framer.next_record() {
                    let ms = (f.first_byte.mono - base).as_millis() as u64;
                    out.push((f.record.station, f.record.pos_inches[0], ms));
                }
            }
        }
        out
    }

    fn plain(n: usize) -> Framer {
        Framer::new(&vec![StationFormat::PLAIN; n])
    }

    #[test]
    fn records_split_anywhere_keep_their_first_byte_time() {
        let mut stream = record(1, 1.0);
        stream.extend(record(2, 2.0));
        for cut in 1..stream.len() {
            let mut f = plain(4);
            let got = run(&mut f, &[stream[..cut].to_vec(), stream[cut..].to_vec()]);
            let second_start = if cut <= 32 { 1 } else { 0 };
            assert_eq!(got, vec![(1, 1.0, 0), (2, 2.0, second_start)], "cut {cut}");
        }
    }

    #[test]
    fn garbage_before_between_and_inside_is_skipped_without_losing_records() {
        let mut f = plain(4);
        let mut truncated = record(3, 9.0);
        truncated.truncate(20);
        let chunks = vec![
            b"xyz0".to_vec(),   // garbage, with a lone '0'
            record(1, 1.0),     // found after the garbage
            b"005".to_vec(),    // '0' then '0' (bad station), then '5' (bad station)
            truncated,          // a record cut short by a lost byte run
            record(2, 2.0),     // begins inside the broken candidate: must not be lost
            b"01\x01".to_vec(), // bad status byte
            record(4, 4.0),
        ];
        let got = run(&mut f, &chunks);
        assert_eq!(got, vec![(1, 1.0, 1), (2, 2.0, 4), (4, 4.0, 6)]);
        assert!(f.total_skipped() >= 3 + 3 + 20 + 3);
    }

    #[test]
    fn resync_reports_the_first_reason_once() {
        let mut f = plain(2);
        let base = Instant::now();
        let mut bad_end = record(1, 5.0);
        *bad_end.last_mut().unwrap() = b'!';
        let mut stream = b"ab".to_vec();
        stream.extend(bad_end);
        stream.extend(record(2, 7.0));
        stream.extend(record(1, 8.0));
        let mut found = Vec::new();
        for &b in &stream {
            f.push(b, at(base, 0));
            while let Some(r) = f.next_record() {
                found.push(r);
            }
        }
        assert_eq!(found.len(), 2);
        let resync = found[0].resync.expect("garbage was reported");
        assert_eq!(resync.reason, Reject::NotRecordStart(b'a'));
        assert_eq!(resync.skipped, 2 + 32);
        assert_eq!(found[1].resync, None);
    }

    #[test]
    fn unconfigured_stations_are_rejected() {
        let mut f = plain(2);
        let got = run(&mut f, &[record(3, 3.0), record(2, 2.0)]);
        assert_eq!(got, vec![(2, 2.0, 1)]);
    }

    #[test]
    fn a_longer_record_hides_a_shorter_one() {
        // Station 1 has buttons (34 bytes), station 2 is plain (32): a station-1 candidate cut
        // short contains a whole station-2 record, which the rescan must find.
        let stylus = StationFormat {
            timestamp: false,
            buttons: ButtonFormat::FastrakStylus,
            joystick: false,
        };
        let mut f = Framer::new(&[stylus, StationFormat::PLAIN]);
        let got = run(&mut f, &[b"01 ".to_vec(), record(2, 2.0), b"01".to_vec()]);
        assert_eq!(got, vec![(2, 2.0, 1)]);
    }
}
