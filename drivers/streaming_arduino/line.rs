//! The sketch's lines, read byte by byte: `v0,v1,…,vN-1[,markers…]\n`, decimal integers.
//!
//! As C++ reads them (`>>` into an `int`, then one separator character): blanks before a
//! number are skipped, a number may have a sign, and any one non-blank character separates
//! two numbers. Numbers after the first `N` (the sketch's event markers) are ignored.
//!
//! A line that does not hold `N` numbers is skipped whole, and nothing is reported for it.
//! Bytes that cannot start a line (anything but a blank, a sign or a digit) are skipped before
//! it, so garbage without digits or newlines costs no line after it. Each line carries the
//! arrival time of the read holding its first byte.

use crate::time::Now;

/// Most numbers kept from a line.
pub const MAX_VALUES: usize = 8;
/// Digits beyond this make a number too large for C++'s `int`.
const MAX_DIGITS: u32 = 10;

/// A complete line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// The first `N` numbers.
    pub values: [i32; MAX_VALUES],
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
}

/// What the reader is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Between lines: skipping what cannot start one.
    Idle,
    /// Expecting a number (blanks skipped).
    Number,
    /// Inside a number.
    Digits,
    /// After a number, before its separator.
    Separator,
    /// The line is complete or broken: ignoring the rest up to its newline.
    Rest,
}

/// What a newline ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ended {
    /// A line with enough numbers.
    Line(Line),
    /// A line without them (its length in bytes, newline included).
    Bad(usize),
}

/// Reads lines byte by byte. See the module documentation.
#[derive(Clone, Debug)]
pub struct LineReader {
    wanted: usize,
    state: State,
    values: [i32; MAX_VALUES],
    count: usize,
    negative: bool,
    value: i64,
    digits: u32,
    broken: bool,
    bytes: usize,
    first: Option<Now>,
    skipped: u64,
}

impl LineReader {
    /// A reader of lines holding at least `wanted` numbers (1..=[`MAX_VALUES`]).
    pub fn new(wanted: usize) -> LineReader {
        LineReader {
            wanted: wanted.clamp(1, MAX_VALUES),
            state: State::Idle,
            values: [0; MAX_VALUES],
            count: 0,
            negative: false,
            value: 0,
            digits: 0,
            broken: false,
            bytes: 0,
            first: None,
            skipped: 0,
        }
    }

    /// Forgets a partial line; with `mid_line`, the bytes up to the next newline are skipped
    /// too (after a reset the first line read may have lost its start).
    pub fn clear(&mut self, mid_line: bool) {
        self.state = if mid_line { State::Rest } else { State::Idle };
        self.count = 0;
        self.broken = mid_line;
        self.bytes = 0;
    }

    /// Bytes skipped between lines since the last call (and forgets them).
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    fn end_number(&mut self) {
        let v = if self.negative {
            -self.value
        } else {
            self.value
        };
        if self.digits == 0 || self.digits > MAX_DIGITS || i32::try_from(v).is_err() {
            self.broken = true;
            self.state = State::Rest;
            return;
        }
        if self.count < self.wanted {
            self.values[self.count] = v as i32;
        }
        self.count += 1;
        self.state = if self.count >= self.wanted {
            State::Rest
        } else {
            State::Separator
        };
    }

    fn start_number(&mut self, b: u8) {
        self.negative = b == b'-';
        self.value = 0;
        self.digits = 0;
        self.state = State::Digits;
        if b.is_ascii_digit() {
            self.value = i64::from(b - b'0');
            self.digits = 1;
        }
    }

    /// Takes one byte that arrived at `arrived`; returns what a newline ended.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Ended> {
        let blank = b == b' ' || b == b'\t' || b == b'\r';
        if self.state == State::Idle {
            if b == b'\n' || !(blank || b == b'-' || b == b'+' || b.is_ascii_digit()) {
                self.skipped += 1;
                return None;
            }
            self.first = Some(arrived);
            self.state = State::Number;
            self.count = 0;
            self.broken = false;
            self.bytes = 0;
        }
        self.bytes += 1;
        if b == b'\n' {
            if self.state == State::Digits {
                self.end_number();
            }
            let ended = if !self.broken && self.count >= self.wanted {
                Ended::Line(Line {
                    values: self.values,
                    first_byte: self.first.unwrap_or(arrived),
                })
            } else {
                Ended::Bad(self.bytes)
            };
            self.state = State::Idle;
            self.count = 0;
            self.broken = false;
            return Some(ended);
        }
        match self.state {
            State::Idle | State::Rest => {}
            State::Number => {
                if blank {
                } else if b == b'-' || b == b'+' || b.is_ascii_digit() {
                    self.start_number(b);
                } else {
                    self.broken = true;
                    self.state = State::Rest;
                }
            }
            State::Digits => {
                if b.is_ascii_digit() {
                    self.value = (self.value * 10 + i64::from(b - b'0')).min(i64::MAX / 20);
                    self.digits += 1;
                } else {
                    self.end_number();
                    if self.state == State::Separator && !blank {
                        self.state = State::Number;
                    }
                }
            }
            State::Separator => {
                if !blank {
                    self.state = State::Number;
                }
            }
        }
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

    fn read(r: &mut LineReader, text: &[u8], t: Now) -> Vec<Ended> {
        text.iter().filter_map(|&b| r.push(b, t)).collect()
    }

    fn line(values: &[i32], t: Now) -> Ended {
        let mut v = [0; MAX_VALUES];
        v[..values.len()].copy_from_slice(values);
        Ended::Line(Line {
            values: v,
            first_byte: t,
        })
    }

    #[test]
    fn lines_markers_separators_and_bad_lines() {
        let base = Instant::now();
        let mut r = LineReader::new(3);
        let t = at(0, base);
        assert_eq!(read(&mut r, b"1023,0,5\n", t), [line(&[1023, 0, 5], t)]);
        assert_eq!(
            read(&mut r, b"7, -8 ;+9,42,43\n", t),
            [line(&[7, -8, 9], t)]
        );
        assert_eq!(read(&mut r, b"1,2\n", t), [Ended::Bad(4)]);
        assert_eq!(read(&mut r, b"1,,2,3\n", t), [Ended::Bad(7)]);
        assert_eq!(read(&mut r, b"1,99999999999,3\n", t), [Ended::Bad(16)]);
        assert_eq!(read(&mut r, b"1,2,3", t), []);
        let t2 = at(5, base);
        assert_eq!(read(&mut r, b"\n", t2), [line(&[1, 2, 3], t)]);
    }

    #[test]
    fn garbage_without_digits_costs_no_line_and_lines_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut r = LineReader::new(2);
        let mut got = read(&mut r, b"xyz\x01\n", at(0, base));
        got.extend(read(&mut r, b"12,", at(1, base)));
        got.extend(read(&mut r, b"34\n", at(2, base)));
        assert_eq!(got, [line(&[12, 34], at(1, base))]);
        assert_eq!(r.take_skipped(), 5);
    }

    #[test]
    fn after_a_reset_the_first_partial_line_is_dropped() {
        let base = Instant::now();
        let mut r = LineReader::new(1);
        r.clear(true);
        let got = read(&mut r, b"23\n45\n", at(0, base));
        assert_eq!(got, [Ended::Bad(3), line(&[45], at(0, base))]);
    }
}
