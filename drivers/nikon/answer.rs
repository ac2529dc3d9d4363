//! The microscope's answers, pure: lines that start with `a`, `n`, `q` or `o` and end with
//! CR LF, found byte by byte ([`Framer`]) and read ([`Answer::parse`]).
//!
//! | Command         | Answers                                   |
//! |-----------------|-------------------------------------------|
//! | `rSPR` CR       | `aSPR<ticks>` CR LF, or `nSPR<error>` CR LF |
//! | `fSMV<ticks>` CR | `qSMVA` CR LF (moving), then `oSMV` CR LF (there), or `nSMV<error>` CR LF |

use crate::time::Now;

/// The command that asks for the focus position.
pub const ASK_FOCUS: &[u8] = b"rSPR\r";
/// Longest answer kept (C++ keeps 256 bytes; every answer is far shorter).
pub const MAX_LINE: usize = 64;
/// Bytes that can start an answer.
const STARTS: &[u8] = b"anqo";

/// Writes the command that moves the focus to `ticks` into `out`; returns its length.
pub fn move_command(ticks: i64, out: &mut [u8; 32]) -> usize {
    let mut n = 0;
    for &b in b"fSMV" {
        out[n] = b;
        n += 1;
    }
    n += write_int(ticks, &mut out[n..]);
    out[n] = b'\r';
    n + 1
}

/// Writes `v` in decimal into `out`; returns its length.
fn write_int(v: i64, out: &mut [u8]) -> usize {
    let mut digits = [0u8; 20];
    let mut m = v.unsigned_abs();
    let mut k = 0;
    loop {
        digits[k] = b'0' + (m % 10) as u8;
        k += 1;
        m /= 10;
        if m == 0 {
            break;
        }
    }
    let mut n = 0;
    if v < 0 {
        out[0] = b'-';
        n = 1;
    }
    for i in (0..k).rev() {
        out[n] = digits[i];
        n += 1;
    }
    n
}

/// One answer of the microscope.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// `aSPR`: the focus position, in ticks.
    Focus(i64),
    /// `nSPR`: the position request failed with this error code.
    FocusError(i64),
    /// `qSMVA`: a move is under way.
    Moving,
    /// `oSMV`: the move reached the position asked for.
    Arrived,
    /// `nSMV`: the move failed with this error code.
    MoveError(i64),
}

impl Answer {
    /// Reads one line (without its CR LF); `None` for a line no answer starts like.
    pub fn parse(line: &[u8]) -> Option<Answer> {
        let rest = |p: &[u8]| line.strip_prefix(p).map(leading_int);
        if let Some(v) = rest(b"aSPR") {
            Some(Answer::Focus(v))
        } else if let Some(v) = rest(b"nSPR") {
            Some(Answer::FocusError(v))
        } else if line.starts_with(b"qSMVA") {
            Some(Answer::Moving)
        } else if line.starts_with(b"oSMV") {
            Some(Answer::Arrived)
        } else {
            rest(b"nSMV").map(Answer::MoveError)
        }
    }
}

/// The integer at the start of `s`, as C's `atoi` reads it (blanks, a sign, digits; 0 when
/// there are none).
fn leading_int(s: &[u8]) -> i64 {
    let s = match s.iter().position(|b| !b.is_ascii_whitespace()) {
        Some(i) => &s[i..],
        None => return 0,
    };
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    let mut v: i64 = 0;
    for &d in digits.iter().take_while(|b| b.is_ascii_digit()) {
        v = v.saturating_mul(10).saturating_add(i64::from(d - b'0'));
    }
    if neg {
        -v
    } else {
        v
    }
}

/// C++'s meaning of the error codes in `nSPR`/`nSMV` answers (from Nikon's manual).
pub fn error_text(code: i64) -> &'static str {
    match code {
        1 => "Command error",
        2 => "Operand error",
        3 => "Processing timeout error",
        4 => "Receive buffer overflow error",
        5 => "Device not mounted",
        6 => "Drive count overflow error",
        7 => "Processing prohibited error",
        _ => "unknown error",
    }
}

/// What one byte led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Nothing yet.
    More,
    /// An answer, stamped with the arrival of its first byte.
    Answer(Answer, Now),
    /// A whole line that is no answer: this many bytes were skipped.
    Unknown(usize),
}

/// Finds answers byte by byte. Bytes that cannot start one are counted as skipped.
#[derive(Clone, Debug)]
pub struct Framer {
    line: [u8; MAX_LINE],
    len: usize,
    first: Option<Now>,
    skipped: u64,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer {
            line: [0; MAX_LINE],
            len: 0,
            first: None,
            skipped: 0,
        }
    }

    /// Forgets a partial answer.
    pub fn clear(&mut self) {
        self.len = 0;
        self.first = None;
    }

    /// Bytes skipped since the last call.
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    /// Takes one byte that arrived at `now`.
    pub fn push(&mut self, b: u8, now: Now) -> Step {
        if self.len == 0 {
            if !STARTS.contains(&b) {
                self.skipped += 1;
                return Step::More;
            }
            self.first = Some(now);
        }
        self.line[self.len] = b;
        self.len += 1;
        let n = self.len;
        if n > 2 && self.line[n - 2] == b'\r' && self.line[n - 1] == b'\n' {
            let at = self.first.unwrap_or(now);
            let answer = Answer::parse(&self.line[..n - 2]);
            self.clear();
            return match answer {
                Some(a) => Step::Answer(a, at),
                None => {
                    self.skipped += n as u64;
                    Step::Unknown(n)
                }
            };
        }
        if n == MAX_LINE {
            self.skipped += n as u64;
            self.clear();
        }
        Step::More
    }
}
