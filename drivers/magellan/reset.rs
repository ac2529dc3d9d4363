//! The Magellan reset, as a state machine over deadlines.
//!
//! The driver flushes the input, then the reset commands are written one byte at a time,
//! [`BYTE_GAP`] apart, because the device loses characters that come in a burst. Each command
//! is answered by a record, so the answers are read with the same framer as reports: the
//! reset succeeds as soon as every expected answer has come, in order. Axis and key records
//! that the device sends in between (the puck was touched) are left to the driver, and no answer
//! within [`REPLY_TIMEOUT`] of the last byte written, or a wrong one, fails the attempt; the
//! next starts [`RETRY_PAUSE`] later.
//!
//! | Mode | Written | Answers |
//! |---|---|---|
//! | normal | `z` `m3` `c30` `nH` `bH`, each with CR | `z` `m3` `c30` `nH` `b`, each with CR |
//! | `altreset` | `z` `m3` `nH` `p?0` `q00`, each with CR | the same |
//!
//! `z` zeroes the puck, `m3` selects 3-D mode (translations and rotations), `c30` turns
//! compression off, `nH` sets the null radius to 8, `bH` beeps; the alternative string of
//! older units sets the report periods (`p?0`) and the sensitivity (`q00`) instead of the
//! compression and the beep.
//!
//! C++ VRPN sleeps 1 s before the first reset and always waits for the whole time-out before
//! looking at the answer; here the reset ends when the last answer arrives, about 90 ms after
//! the port opens at 9600 baud (15 bytes, 5 ms apart, then the answers).

use std::time::{Duration, Instant};

use super::framer::Record;
use crate::serial::PortOps;
use crate::time::Now;

/// Pause before each byte after the first (C++ VRPN uses the same pacing).
pub const BYTE_GAP: Duration = Duration::from_millis(5);
/// Time the device has to answer after the last byte written (as C++ VRPN).
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(1);
/// Pause between a failed attempt and the next.
pub const RETRY_PAUSE: Duration = Duration::from_millis(500);

/// The commands of one kind of reset and the answers they get.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResetPlan {
    /// Bytes written, CRs included.
    pub commands: &'static [u8],
    /// The records that answer them, in order.
    pub answers: &'static [&'static [u8]],
}

/// The answer to the zeroing command: from then on the puck's axes read 0.
pub const ZERO_ANSWER: &[u8] = b"z\r";

/// The reset of current units.
pub const NORMAL: ResetPlan = ResetPlan {
    commands: b"z\rm3\rc30\rnH\rbH\r",
    answers: &[b"z\r", b"m3\r", b"c30\r", b"nH\r", b"b\r"],
};

/// The reset of older units (`altreset`).
pub const ALTERNATIVE: ResetPlan = ResetPlan {
    commands: b"z\rm3\rnH\rp?0\rq00\r",
    answers: &[b"z\r", b"m3\r", b"nH\r", b"p?0\r", b"q00\r"],
};

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// Not a byte came back.
    NoResponse,
    /// Some answers (`got` of `want`), then nothing more.
    TooFew {
        /// Answers received.
        got: usize,
        /// Answers expected.
        want: usize,
    },
    /// An answer other than the one expected.
    WrongAnswer {
        /// Index of the expected answer.
        index: usize,
        /// The record that came instead.
        got: Record,
    },
}

/// What a call ended with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still resetting.
    Busy,
    /// Every answer came: reports follow.
    Done,
    /// The attempt failed; the next starts after [`RETRY_PAUSE`].
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Idle,
    Writing { next: usize },
    Answers { deadline: Instant },
    Pause { until: Instant },
    Done,
}

/// The reset of one device.
#[derive(Debug)]
pub struct ResetSequence {
    plan: ResetPlan,
    stage: Stage,
    wake: Option<Instant>,
    matched: usize,
    saw_bytes: bool,
    attempts: u32,
}

impl ResetSequence {
    /// A reset following `plan`, idle until [`start`](Self::start).
    pub fn new(plan: ResetPlan) -> ResetSequence {
        ResetSequence {
            plan,
            stage: Stage::Idle,
            wake: None,
            matched: 0,
            saw_bytes: false,
            attempts: 0,
        }
    }

    /// The plan.
    pub fn plan(&self) -> ResetPlan {
        self.plan
    }

    /// Attempts since the last success.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// True while waiting out the pause after a failed attempt (answers are not expected).
    pub fn is_pausing(&self) -> bool {
        matches!(self.stage, Stage::Pause { .. })
    }

    /// Starts an attempt: writes the first byte. (The caller flushes the input before a
    /// reset's first attempt; later attempts keep it, so records in flight survive and late
    /// answers to the previous attempt count for this one.)
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        self.attempts += 1;
        self.matched = 0;
        self.saw_bytes = false;
        port.write(&self.plan.commands[..1]);
        self.stage = Stage::Writing { next: 1 };
        self.wake = Some(now.mono + BYTE_GAP);
    }

    /// Stops (the port closed).
    pub fn stop(&mut self) {
        self.stage = Stage::Idle;
        self.wake = None;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.stage {
            Stage::Writing { .. } => self.wake,
            Stage::Answers { deadline } => Some(deadline),
            Stage::Pause { until } => Some(until),
            Stage::Idle | Stage::Done => None,
        }
    }

    /// Bytes arrived (some answer, or anything at all).
    pub fn saw_bytes(&mut self) {
        self.saw_bytes = true;
    }

    /// Writes the next byte, notices a time-out, or ends the pause.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        match self.stage {
            Stage::Writing { next } if self.wake.is_some_and(|w| now.mono >= w) => {
                port.write(&self.plan.commands[next..next + 1]);
                if next + 1 == self.plan.commands.len() {
                    self.wake = None;
                    self.stage = Stage::Answers {
                        deadline: now.mono + REPLY_TIMEOUT,
                    };
                } else {
                    self.wake = Some(now.mono + BYTE_GAP);
                    self.stage = Stage::Writing { next: next + 1 };
                }
                Progress::Busy
            }
            Stage::Answers { deadline } if now.mono >= deadline => {
                let want = self.plan.answers.len();
                let failure = if self.matched == 0 && !self.saw_bytes {
                    Failure::NoResponse
                } else {
                    Failure::TooFew {
                        got: self.matched,
                        want,
                    }
                };
                self.fail(now, failure)
            }
            Stage::Pause { until } if now.mono >= until => {
                self.start(now, port);
                Progress::Busy
            }
            _ => Progress::Busy,
        }
    }

    /// A record other than an axis or key record arrived while resetting.
    pub fn record(&mut self, record: &Record, now: Now) -> Progress {
        if !matches!(self.stage, Stage::Writing { .. } | Stage::Answers { .. }) {
            return Progress::Busy;
        }
        if record.bytes() != self.plan.answers[self.matched] {
            let index = self.matched;
            return self.fail(
                now,
                Failure::WrongAnswer {
                    index,
                    got: *record,
                },
            );
        }
        self.matched += 1;
        if self.matched < self.plan.answers.len() {
            return Progress::Busy;
        }
        self.stage = Stage::Done;
        self.wake = None;
        self.attempts = 0;
        Progress::Done
    }

    fn fail(&mut self, now: Now, failure: Failure) -> Progress {
        self.wake = None;
        self.stage = Stage::Pause {
            until: now.mono + RETRY_PAUSE,
        };
        Progress::Failed(failure)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_answers_are_the_commands_as_the_device_echoes_them() {
        for plan in [NORMAL, ALTERNATIVE] {
            let joined: Vec<u8> = plan.answers.concat();
            let n = plan.commands.iter().filter(|&&b| b == b'\r').count();
            assert_eq!(n, plan.answers.len());
            if plan == NORMAL {
                assert_eq!(joined, b"z\rm3\rc30\rnH\rb\r");
                assert_eq!(plan.commands.len(), 15);
            } else {
                assert_eq!(joined, plan.commands);
                // The spec's table says 17 bytes; the string itself has 16.
                assert_eq!(plan.commands.len(), 16);
            }
            for a in plan.answers {
                assert_eq!(super::super::record::record_len(a[0]), Some(a.len()));
            }
        }
    }
}
