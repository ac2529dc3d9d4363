//! The Liberty / Patriot reset, as a state machine over deadlines.
//!
//! The bytes are C++ VRPN's; the waits are not (C++ sleeps 2 s after every byte of the break,
//! 20 s after a Ctrl-Y, 2 s before and 1 s after the WhoAmI request, 1 s after each filter
//! command, 2 s after the extra commands: about 15 s per reset):
//!
//! 1. **Break**, one byte every [`BREAK_GAP`]: CR `F` `0` CR (ASCII output), then Ctrl-Y CR
//!    (reinitialise) if the attempt *n* > 2, then `P` (one record, which ends continuous
//!    output).
//! 2. **Quiet**: the line must stay silent for [`QUIET`] (at most [`QUIET_LIMIT`]); then the
//!    input is flushed.
//! 3. **WhoAmI**: Ctrl-V CR; the answer is complete at the configured length (195 by
//!    default) or after [`QUIET`] without a byte, and is good when it starts with `0`. None
//!    within [`STATUS_WAIT`] plus its transmission fails the attempt — unless a Ctrl-Y went
//!    out: the request is then repeated every [`REBOOT_POLL`] for up to [`REBOOT_LIMIT`].
//! 4. **Settings**, one every [`CONFIG_GAP`]: `O<s>,2,7,8,0` CR for stations 1 to 8
//!    (`O<s>,2,7,8,10,0` for a station with a stylus): position, quaternion, time stamp,
//!    \[stylus\], space; `X0,1,0,0` CR and `Y0,1,0,0` CR (no filtering, as C++ configures it);
//!    the entry's extra reset commands (`*N` pauses N seconds).
//! 5. **Settle**: the line quiet for [`QUIET`] (replies to the settings, a Patriot's
//!    complaints about stations it lacks), at most [`QUIET_LIMIT`]; input flushed.
//! 6. **Stream**: `F1` CR (binary), `C` CR (continuous), `Q0` CR (C++'s time-stamp clear).

use std::time::{Duration, Instant};

use crate::config::continuation::{command_bytes, ResetStep};
use crate::serial::PortOps;
use crate::time::Now;

/// Time between the bytes of the break.
pub const BREAK_GAP: Duration = Duration::from_millis(100);
/// Silence that shows output (or an answer) has ended.
pub const QUIET: Duration = Duration::from_millis(100);
/// Longest wait for silence.
pub const QUIET_LIMIT: Duration = Duration::from_secs(2);
/// Wait for the WhoAmI answer (C++'s fixed wait), plus its transmission time.
pub const STATUS_WAIT: Duration = Duration::from_secs(1);
/// How long a tracker reinitialising after Ctrl-Y may take (C++ waits 20 s).
pub const REBOOT_LIMIT: Duration = Duration::from_secs(25);
/// How often WhoAmI is repeated while the tracker reinitialises.
pub const REBOOT_POLL: Duration = Duration::from_millis(500);
/// Time between two settings.
pub const CONFIG_GAP: Duration = Duration::from_millis(50);
/// The WhoAmI answer's length unless the entry says otherwise (C++'s default).
pub const DEFAULT_WHOAMI_LEN: usize = 195;
/// The longest WhoAmI answer an entry may name (C++'s limit).
pub const MAX_WHOAMI_LEN: usize = 1024;

/// Ctrl-Y: reinitialise.
pub const CTRL_Y: u8 = 0x19;
/// Ctrl-V: WhoAmI.
pub const CTRL_V: u8 = 0x16;
/// The WhoAmI request.
pub const WHOAMI: &[u8] = &[CTRL_V, b'\r'];
/// Written once the tracker is configured: binary records, continuous output, time stamp
/// cleared (three writes).
pub const STREAM: [&[u8]; 3] = [b"F1\r", b"C\r", b"Q0\r"];

/// The break bytes of attempt `n` (1-based).
pub fn break_bytes(n: u32) -> ([u8; 7], usize) {
    let mut b = [b'\r', b'F', b'0', b'\r', 0, 0, 0];
    let mut len = 4;
    if n > 2 {
        b[4] = CTRL_Y;
        b[5] = b'\r';
        len = 6;
    }
    b[len] = b'P';
    (b, len + 1)
}

/// The output-list command of station `s` (1-based).
pub fn output_list(s: usize, stylus: bool, out: &mut Vec<u8>) {
    use std::io::Write;
    let _ = write!(out, "O{s},2,7,8{},0\r", if stylus { ",10" } else { "" });
}

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No answer to WhoAmI.
    NoAnswer,
    /// An answer that does not start with `0` (its first bytes, at most 16).
    BadStatus([u8; 16], usize),
}

/// What a call into the sequence led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still working.
    Working,
    /// The first break byte went out (attempt `n`).
    Started(u32),
    /// A good WhoAmI answer of `len` bytes arrived; `after_stop` bytes came after the break.
    GoodStatus {
        /// Its length.
        len: usize,
        /// Bytes that came before the line went quiet.
        after_stop: usize,
    },
    /// The tracker streams: the reset is over.
    Done,
    /// The attempt failed.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    Break {
        next: usize,
        at: Instant,
    },
    Quiet {
        quiet_at: Instant,
        give_up: Instant,
    },
    WhoAmI {
        give_up: Instant,
        quiet_at: Option<Instant>,
        reboot_until: Option<Instant>,
    },
    Settings {
        next: usize,
        at: Instant,
    },
    Settle {
        quiet_at: Instant,
        give_up: Instant,
    },
}

/// The reset sequence. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    baud: u32,
    whoami_len: usize,
    stylus: [bool; 8],
    extra: Vec<ResetStep>,
    step: Step,
    attempts: u32,
    breaks: ([u8; 7], usize),
    after_stop: usize,
    head: [u8; 16],
    len: usize,
    scratch: Vec<u8>,
}

impl ResetSequence {
    /// A sequence on a line at `baud` for a tracker whose WhoAmI answer has `whoami_len`
    /// bytes, with styluses on the stations `stylus[i]` (sensor *i*) and the entry's extra
    /// commands.
    pub fn new(
        baud: u32,
        whoami_len: usize,
        stylus: [bool; 8],
        extra: Vec<ResetStep>,
    ) -> ResetSequence {
        ResetSequence {
            baud,
            whoami_len,
            stylus,
            extra,
            step: Step::Idle,
            attempts: 0,
            breaks: ([0; 7], 0),
            after_stop: 0,
            head: [0; 16],
            len: 0,
            scratch: Vec::with_capacity(64),
        }
    }

    /// Attempts started since the last good one.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// Abandons the attempt.
    pub fn stop(&mut self) {
        self.step = Step::Idle;
    }

    fn transmission(&self, bytes: usize) -> Duration {
        Duration::from_micros((bytes as u64 * 10_000_000) / u64::from(self.baud.max(1)))
    }

    /// Writes break byte `i`; after the last, waits for the line to go quiet.
    fn break_byte(&mut self, i: usize, now: Now, port: &mut PortOps) {
        port.write(&self.breaks.0[i..i + 1]);
        if i + 1 < self.breaks.1 {
            self.step = Step::Break {
                next: i + 1,
                at: now.mono + BREAK_GAP,
            };
        } else {
            self.after_stop = 0;
            self.step = Step::Quiet {
                quiet_at: now.mono + QUIET,
                give_up: now.mono + QUIET_LIMIT,
            };
        }
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.step {
            Step::Idle => None,
            Step::Break { at, .. } | Step::Settings { at, .. } => Some(at),
            Step::Quiet { quiet_at, give_up } | Step::Settle { quiet_at, give_up } => {
                Some(quiet_at.min(give_up))
            }
            Step::WhoAmI {
                give_up, quiet_at, ..
            } => Some(quiet_at.map_or(give_up, |q| q.min(give_up))),
        }
    }

    /// Starts an attempt: the first break byte.
    pub fn start(&mut self, now: Now, port: &mut PortOps) -> Progress {
        self.attempts += 1;
        self.breaks = break_bytes(self.attempts);
        self.break_byte(0, now, port);
        Progress::Started(self.attempts)
    }

    fn ask(&mut self, now: Now, port: &mut PortOps, reboot_until: Option<Instant>) {
        port.flush_input();
        port.write(WHOAMI);
        self.len = 0;
        let wait = if reboot_until.is_some() {
            REBOOT_POLL
        } else {
            STATUS_WAIT
        };
        self.step = Step::WhoAmI {
            give_up: now.mono + wait + self.transmission(self.whoami_len),
            quiet_at: None,
            reboot_until,
        };
    }

    /// Time passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        match self.step {
            Step::Idle => Progress::Working,
            Step::Break { next, at } => {
                if now.mono < at {
                    return Progress::Working;
                }
                self.break_byte(next, now, port);
                Progress::Working
            }
            Step::Quiet { quiet_at, give_up } => {
                if now.mono < quiet_at && now.mono < give_up {
                    return Progress::Working;
                }
                let ctrl_y = self.breaks.0[..self.breaks.1].contains(&CTRL_Y);
                self.ask(now, port, ctrl_y.then(|| now.mono + REBOOT_LIMIT));
                Progress::Working
            }
            Step::WhoAmI {
                give_up,
                quiet_at,
                reboot_until,
            } => {
                if quiet_at.is_some_and(|q| now.mono >= q) {
                    return self.answered(now, port);
                }
                if now.mono < give_up {
                    return Progress::Working;
                }
                if self.len > 0 {
                    return self.answered(now, port);
                }
                if reboot_until.is_some_and(|t| now.mono < t) {
                    self.ask(now, port, reboot_until);
                    return Progress::Working;
                }
                self.step = Step::Idle;
                Progress::Failed(Failure::NoAnswer)
            }
            Step::Settings { next, at } => {
                if now.mono < at {
                    return Progress::Working;
                }
                self.setting(next, now, port);
                Progress::Working
            }
            Step::Settle { quiet_at, give_up } => {
                if now.mono < quiet_at && now.mono < give_up {
                    return Progress::Working;
                }
                port.flush_input();
                for w in STREAM {
                    port.write(w);
                }
                self.step = Step::Idle;
                Progress::Done
            }
        }
    }

    /// The WhoAmI answer is complete: check it and go on.
    fn answered(&mut self, now: Now, port: &mut PortOps) -> Progress {
        if self.head[0] != b'0' {
            self.step = Step::Idle;
            let n = self.len.min(16);
            return Progress::Failed(Failure::BadStatus(self.head, n));
        }
        self.attempts = 0;
        let len = self.len;
        self.setting(0, now, port);
        Progress::GoodStatus {
            len,
            after_stop: self.after_stop,
        }
    }

    /// Writes setting `i` (output lists, filters, extra commands); after the last, settles.
    fn setting(&mut self, i: usize, now: Now, port: &mut PortOps) {
        self.scratch.clear();
        let mut wait = CONFIG_GAP;
        match i {
            0..=7 => output_list(i + 1, self.stylus[i], &mut self.scratch),
            8 => self.scratch.extend_from_slice(b"X0,1,0,0\r"),
            9 => self.scratch.extend_from_slice(b"Y0,1,0,0\r"),
            _ => match self.extra.get(i - 10) {
                Some(ResetStep::Command(c)) => command_bytes(c, &mut self.scratch),
                Some(ResetStep::Pause(s)) => wait = Duration::from_secs(u64::from(*s)),
                None => {
                    self.step = Step::Settle {
                        quiet_at: now.mono + QUIET,
                        give_up: now.mono + QUIET_LIMIT,
                    };
                    return;
                }
            },
        }
        if !self.scratch.is_empty() {
            port.write(&self.scratch);
        }
        self.step = Step::Settings {
            next: i + 1,
            at: now.mono + wait,
        };
    }

    /// Bytes arrived.
    pub fn received(&mut self, bytes: &[u8], now: Now, port: &mut PortOps) -> Progress {
        match &mut self.step {
            Step::Idle | Step::Break { .. } | Step::Settings { .. } => Progress::Working,
            Step::Quiet { quiet_at, .. } => {
                self.after_stop += bytes.len();
                *quiet_at = now.mono + QUIET;
                Progress::Working
            }
            Step::Settle { quiet_at, .. } => {
                *quiet_at = now.mono + QUIET;
                Progress::Working
            }
            Step::WhoAmI { quiet_at, .. } => {
                for &b in bytes.iter().take(self.whoami_len.saturating_sub(self.len)) {
                    if self.len < self.head.len() {
                        self.head[self.len] = b;
                    }
                    self.len += 1;
                }
                *quiet_at = Some(now.mono + QUIET);
                if self.len >= self.whoami_len {
                    return self.answered(now, port);
                }
                Progress::Working
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn break_and_output_lists_are_c_plus_plus_s() {
        let (b, n) = break_bytes(1);
        assert_eq!(&b[..n], b"\rF0\rP");
        let (b, n) = break_bytes(3);
        assert_eq!(&b[..n], b"\rF0\r\x19\rP");
        let mut v = Vec::new();
        output_list(3, true, &mut v);
        output_list(8, false, &mut v);
        assert_eq!(v, b"O3,2,7,8,10,0\rO8,2,7,8,0\r");
    }
}
