//! The drive's answers and the host's commands, pure.
//!
//! Every command is ASCII ended by CR. A command that answers gets two CR-ended lines back,
//! `` `<c><value> `` and `` `<c># ``, where `<c>` is the command's letter:
//!
//! | Command | Answer                    | Meaning                                  |
//! |---------|---------------------------|------------------------------------------|
//! | `f`     | `` `f<code>␍`f#␍ ``       | fault status (0: no fault)               |
//! | `l`     | `` `l<pos>␍`l#␍ ``        | position, in 1/64 steps                  |
//! | `:`     | `` `:<bits>␍`:#␍ ``       | inputs (bit 0: input 1 … bit 3: input 4) |
//! | `o`     | `` `oYES␍`o#␍ `` or `NO`  | is the motor moving                      |
//! | `P` (ending a program) | `` `P<size>␍`P#␍ `` | program stored                  |
//!
//! `R` (software reset), `Z<pos>` (set the position), `O<bits>` (outputs), `i…` (input
//! interrupts), `M…` (move), `A`, `X` and `P<name>,<page>,<n>` (program text) get no answer.
//!
//! The [`Framer`] finds answers byte by byte: a back-quote starts one; anything that does not
//! fit is skipped (counted) and a back-quote inside it starts the next answer, so garbage
//! costs no answer after it. Each answer keeps the arrival time of its first byte.

use std::fmt::{self, Write as _};

use crate::time::Now;

/// Longest value kept in an answer (positions are at most 11 characters).
pub const MAX_VALUE: usize = 24;
/// Longest command the driver writes (a move with twelve numbers).
pub const MAX_COMMAND: usize = 160;

/// One answer of the drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// `f`: the fault status.
    Fault(i64),
    /// `l`: the position in 1/64 steps.
    Position(i64),
    /// `:`: the input and output bits.
    Io(i64),
    /// `o`: whether the motor is moving.
    Moving(bool),
    /// `P`: a program was stored (its size).
    Program(i64),
    /// A well-formed answer to a command the driver does not send.
    Other(u8),
}

/// A command being written, in a fixed buffer (writing one allocates nothing).
#[derive(Clone)]
pub struct Command {
    buf: [u8; MAX_COMMAND],
    len: usize,
}

impl Command {
    /// The command `args` formats to, with its CR; `None` if it does not fit.
    pub fn new(args: fmt::Arguments<'_>) -> Option<Command> {
        let mut c = Command {
            buf: [0; MAX_COMMAND],
            len: 0,
        };
        c.write_fmt(args).ok()?;
        c.write_str("\r").ok()?;
        Some(c)
    }

    /// Its bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }
}

impl fmt::Write for Command {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        if end > MAX_COMMAND {
            return Err(fmt::Error);
        }
        self.buf[self.len..end].copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// The leading integer of `v` as C's `%d` reads it (optional sign, then digits); `None` when
/// there is none.
pub fn leading_int(v: &[u8]) -> Option<i64> {
    let (neg, digits) = match v.first() {
        Some(b'-') => (true, &v[1..]),
        Some(b'+') => (false, &v[1..]),
        _ => (false, v),
    };
    let n = digits.iter().take_while(|b| b.is_ascii_digit()).count();
    if n == 0 {
        return None;
    }
    let mut x: i64 = 0;
    for &d in &digits[..n] {
        x = x.saturating_mul(10).saturating_add(i64::from(d - b'0'));
    }
    Some(if neg { -x } else { x })
}

impl Answer {
    /// Reads the first line of an answer to `letter` (without its CR); `None` when the value
    /// does not read.
    pub fn parse(letter: u8, value: &[u8]) -> Option<Answer> {
        Some(match letter {
            b'f' => Answer::Fault(leading_int(value)?),
            b'l' => Answer::Position(leading_int(value)?),
            b':' => Answer::Io(leading_int(value)?),
            b'P' => Answer::Program(leading_int(value)?),
            b'o' => Answer::Moving(value.first() == Some(&b'Y')),
            other => Answer::Other(other),
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Waiting for a back-quote.
    Idle,
    /// After the back-quote: the command letter.
    Letter,
    /// The value, up to CR.
    Value,
    /// The second line: back-quote, letter, `#`, CR (how many of them came).
    Tail(u8),
}

/// Finds answers in the byte stream. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    state: State,
    letter: u8,
    value: [u8; MAX_VALUE],
    len: usize,
    /// Bytes of the answer under way (skipped if it breaks).
    taken: u64,
    first: Option<Now>,
    skipped: u64,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// A framer waiting for an answer.
    pub fn new() -> Framer {
        Framer {
            state: State::Idle,
            letter: 0,
            value: [0; MAX_VALUE],
            len: 0,
            taken: 0,
            first: None,
            skipped: 0,
        }
    }

    /// Forgets a partial answer.
    pub fn clear(&mut self) {
        self.state = State::Idle;
        self.taken = 0;
    }

    /// Bytes skipped since the last call (and forgets them).
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    /// The answer under way broke at byte `b`: its bytes are skipped, and `b` may start the
    /// next one.
    fn broken(&mut self, b: u8, arrived: Now) {
        self.skipped += self.taken;
        self.taken = 0;
        self.state = State::Idle;
        self.start(b, arrived);
    }

    fn start(&mut self, b: u8, arrived: Now) {
        if b == b'`' {
            self.state = State::Letter;
            self.first = Some(arrived);
            self.taken = 1;
        } else {
            self.skipped += 1;
        }
    }

    /// Takes one byte that arrived at `arrived`; returns an answer and its first byte's time
    /// when it completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<(Answer, Now)> {
        match self.state {
            State::Idle => self.start(b, arrived),
            State::Letter => {
                if b.is_ascii_graphic() && b != b'`' && b != b'#' {
                    self.letter = b;
                    self.len = 0;
                    self.taken += 1;
                    self.state = State::Value;
                } else {
                    self.broken(b, arrived);
                }
            }
            State::Value => {
                if b == b'\r' {
                    self.taken += 1;
                    self.state = State::Tail(0);
                } else if self.len < MAX_VALUE && b != b'`' && b != b'\n' {
                    self.value[self.len] = b;
                    self.len += 1;
                    self.taken += 1;
                } else {
                    self.broken(b, arrived);
                }
            }
            State::Tail(n) => {
                let want = [b'`', self.letter, b'#', b'\r'][usize::from(n)];
                if b != want {
                    self.broken(b, arrived);
                    return None;
                }
                self.taken += 1;
                if n < 3 {
                    self.state = State::Tail(n + 1);
                    return None;
                }
                self.state = State::Idle;
                let taken = std::mem::take(&mut self.taken);
                let first = self.first.unwrap_or(arrived);
                match Answer::parse(self.letter, &self.value[..self.len]) {
                    Some(a) => return Some((a, first)),
                    None => self.skipped += taken,
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

    #[test]
    fn commands_are_formatted_without_allocating_and_end_in_cr() {
        let c = Command::new(format_args!("M{},{}", -640, 3200)).unwrap();
        assert_eq!(c.bytes(), b"M-640,3200\r");
        assert!(Command::new(format_args!("{}", "x".repeat(MAX_COMMAND))).is_none());
    }

    #[test]
    fn answers_after_garbage_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new();
        let mut got = Vec::new();
        let pieces: [&[u8]; 6] = [
            b"zz`l12",
            b"8\r`l#\r",
            b"`:5\r`:#\r`oNO\r`o#",
            b"\r``f0\r`f#\r",
            b"`lxx\r`l#\r`P12\r`P",
            b"#\r`oYES\r`o#\r",
        ];
        for (i, p) in pieces.iter().enumerate() {
            for &b in p.iter() {
                got.extend(f.push(b, at(i as u64, base)));
            }
        }
        let answers: Vec<Answer> = got.iter().map(|g| g.0).collect();
        assert_eq!(
            answers,
            [
                Answer::Position(128),
                Answer::Io(5),
                Answer::Moving(false),
                Answer::Fault(0),
                Answer::Program(12),
                Answer::Moving(true),
            ]
        );
        assert_eq!(got[0].1, at(0, base));
        assert_eq!(got[2].1, at(2, base));
        // "zz", the lone back-quote and the unreadable position.
        assert_eq!(f.take_skipped(), 2 + 1 + 9);
    }

    #[test]
    fn values_read_as_c_reads_them() {
        assert_eq!(leading_int(b"-3840"), Some(-3840));
        assert_eq!(leading_int(b"+7x"), Some(7));
        assert_eq!(leading_int(b"x7"), None);
        assert_eq!(Answer::parse(b'o', b"NO"), Some(Answer::Moving(false)));
    }
}
