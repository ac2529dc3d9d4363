//! The Crossbow reset, as a state machine over deadlines.
//!
//! C++ VRPN pulses RTS (750 ms set, 250 ms clear), sends `P` (polled mode), waits 50 ms,
//! then asks `R` (ping: `H`), `S` (serial number: `FF`, four bytes, their sum, `FF`) and
//! `v` (version text ending in `$`), with 1 s for each answer. Here the first attempt skips
//! the pulse (a device that answers needs none); later attempts pulse first:
//!
//! 1. (From attempt 2) **RTS** set for [`RTS_SET`], cleared for [`RTS_CLEAR`].
//! 2. **`P`**, then the line quiet for [`QUIET`] (at most [`QUIET_LIMIT`]: a device
//!    streaming packets stops); input flushed.
//! 3. **`RSv`**: 8 bytes `H FF s s s s sum FF`, then the version up to `$`, within
//!    [`ANSWER_WAIT`].

use std::time::{Duration, Instant};

use crate::serial::PortOps;
use crate::time::Now;

/// RTS held this long (C++'s wait).
pub const RTS_SET: Duration = Duration::from_millis(750);
/// Then cleared this long (C++'s wait).
pub const RTS_CLEAR: Duration = Duration::from_millis(250);
/// Silence that shows the device stopped sending.
pub const QUIET: Duration = Duration::from_millis(30);
/// Longest wait for it.
pub const QUIET_LIMIT: Duration = Duration::from_millis(500);
/// Wait for the answer to `RSv` (C++'s 1 s per read).
pub const ANSWER_WAIT: Duration = Duration::from_secs(1);
/// The longest version text kept.
pub const MAX_VERSION: usize = 64;

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No (complete) answer in time.
    NoAnswer,
    /// The ping or serial-number answer is malformed (its first 8 bytes).
    BadAnswer([u8; 8]),
    /// The serial number's sum is wrong.
    BadChecksum,
}

/// What a call into the sequence led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still working.
    Working,
    /// Attempt `n` started.
    Started(u32),
    /// The device answered: polled mode, ready.
    Done,
    /// The attempt failed.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    RtsSet(Instant),
    RtsClear(Instant),
    Quiet { quiet_at: Instant, give_up: Instant },
    Answer(Instant),
}

/// The reset sequence. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    step: Step,
    attempts: u32,
    answer: [u8; 8],
    len: usize,
    version: [u8; MAX_VERSION],
    version_len: usize,
    serial: u32,
}

impl Default for ResetSequence {
    fn default() -> ResetSequence {
        ResetSequence::new()
    }
}

impl ResetSequence {
    /// A sequence not started.
    pub fn new() -> ResetSequence {
        ResetSequence {
            step: Step::Idle,
            attempts: 0,
            answer: [0; 8],
            len: 0,
            version: [0; MAX_VERSION],
            version_len: 0,
            serial: 0,
        }
    }

    /// The device's serial number (after a reset).
    pub fn serial(&self) -> u32 {
        self.serial
    }

    /// Its version text (after a reset).
    pub fn version(&self) -> &[u8] {
        &self.version[..self.version_len]
    }

    /// Abandons the attempt.
    pub fn stop(&mut self) {
        self.step = Step::Idle;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.step {
            Step::Idle => None,
            Step::RtsSet(t) | Step::RtsClear(t) | Step::Answer(t) => Some(t),
            Step::Quiet { quiet_at, give_up } => Some(quiet_at.min(give_up)),
        }
    }

    /// Starts an attempt.
    pub fn start(&mut self, now: Now, port: &mut PortOps) -> Progress {
        self.attempts += 1;
        port.flush_output();
        port.flush_input();
        if self.attempts > 1 {
            port.set_rts(true);
            self.step = Step::RtsSet(now.mono + RTS_SET);
        } else {
            self.stop_streaming(now, port);
        }
        Progress::Started(self.attempts)
    }

    fn stop_streaming(&mut self, now: Now, port: &mut PortOps) {
        port.write(b"P");
        self.step = Step::Quiet {
            quiet_at: now.mono + QUIET,
            give_up: now.mono + QUIET_LIMIT,
        };
    }

    /// Time passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        match self.step {
            Step::RtsSet(t) if now.mono >= t => {
                port.set_rts(false);
                self.step = Step::RtsClear(now.mono + RTS_CLEAR);
            }
            Step::RtsClear(t) if now.mono >= t => {
                port.flush_input();
                self.stop_streaming(now, port);
            }
            Step::Quiet { quiet_at, give_up } if now.mono >= quiet_at.min(give_up) => {
                port.flush_input();
                port.write(b"RSv");
                self.len = 0;
                self.version_len = 0;
                self.step = Step::Answer(now.mono + ANSWER_WAIT);
            }
            Step::Answer(t) if now.mono >= t => {
                self.step = Step::Idle;
                return Progress::Failed(Failure::NoAnswer);
            }
            _ => {}
        }
        Progress::Working
    }

    /// Bytes arrived.
    pub fn received(&mut self, bytes: &[u8], now: Now) -> Progress {
        match &mut self.step {
            Step::Quiet { quiet_at, .. } => {
                *quiet_at = now.mono + QUIET;
                Progress::Working
            }
            Step::Answer(_) => {
                for &b in bytes {
                    if self.len < 8 {
                        self.answer[self.len] = b;
                        self.len += 1;
                        if self.len == 8 {
                            if let Some(f) = self.check() {
                                self.step = Step::Idle;
                                return Progress::Failed(f);
                            }
                        }
                    } else if b == b'$' {
                        self.step = Step::Idle;
                        self.attempts = 0;
                        return Progress::Done;
                    } else if self.version_len < MAX_VERSION {
                        self.version[self.version_len] = b;
                        self.version_len += 1;
                    }
                }
                Progress::Working
            }
            _ => Progress::Working,
        }
    }

    fn check(&mut self) -> Option<Failure> {
        let a = self.answer;
        if a[0] != b'H' || a[1] != 0xFF || a[7] != 0xFF {
            return Some(Failure::BadAnswer(a));
        }
        let sum = a[2..6].iter().fold(0u8, |s, &b| s.wrapping_add(b));
        if sum != a[6] {
            return Some(Failure::BadChecksum);
        }
        self.serial = u32::from_be_bytes([a[2], a[3], a[4], a[5]]);
        None
    }
}
