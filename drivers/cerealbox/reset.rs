//! The CerealBox reset, as a state machine over deadlines.
//!
//! 1. Flush the input and write `T`: the box detects the baud rate and answers with its
//!    44-character banner, which must start `Copyright (c), BG Systems` and name EEPROM
//!    version 3.07 (characters 38, 40 and 41), with the box type letter at 42. Bytes before
//!    the banner's first character are passed over.
//! 2. Write the configuration command ([`Layout::config_command`]) and read the two-character
//!    acknowledgement, which must start with `a`.
//! 3. Write `pE`, the request for the first record: the box is polled from then on.
//!
//! Each answer has [`ANSWER_TIMEOUT`] (as C++ VRPN), but the reset moves on as soon as it
//! arrives, so it takes a few milliseconds rather than C++'s fixed waits of up to 4 s. A
//! failed attempt is reported; the lifecycle starts the next [`RETRY_PAUSE`] later.

use std::time::{Duration, Instant};

use super::record::{Layout, BANNER_LEN, BANNER_PREFIX, BANNER_REQUEST, REQUEST};
use crate::serial::PortOps;
use crate::time::Now;

/// Time the box has for each answer (as C++ VRPN).
pub const ANSWER_TIMEOUT: Duration = Duration::from_secs(2);
/// Pause between a failed attempt and the next.
pub const RETRY_PAUSE: Duration = Duration::from_millis(500);

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// Nothing came back for `T`.
    NoBanner,
    /// Part of the banner (this many characters), then nothing.
    ShortBanner(usize),
    /// The banner names another EEPROM version (its three digit characters).
    BadVersion([u8; 3]),
    /// Nothing came back for the configuration command.
    NoAck,
    /// One character of the acknowledgement, then nothing.
    ShortAck,
    /// The acknowledgement did not start with `a`.
    BadAck(u8),
}

/// What a call ended with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still resetting.
    Busy,
    /// The banner came from a box of this type; the configuration was sent.
    Found(u8),
    /// Acknowledged; the first record was requested.
    Done,
    /// The attempt failed (the sequence is idle); the next is for [`RETRY_PAUSE`] later.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Idle,
    Banner { deadline: Instant },
    Ack { deadline: Instant },
    Done,
}

/// The reset of one box.
#[derive(Debug)]
pub struct ResetSequence {
    command: [u8; 10],
    stage: Stage,
    banner: [u8; BANNER_LEN],
    got: usize,
    ack: u8,
    attempts: u32,
}

impl ResetSequence {
    /// A reset that configures `layout`, idle until [`start`](Self::start).
    pub fn new(layout: &Layout) -> ResetSequence {
        ResetSequence {
            command: layout.config_command(),
            stage: Stage::Idle,
            banner: [0; BANNER_LEN],
            got: 0,
            ack: 0,
            attempts: 0,
        }
    }

    /// Attempts since the last success.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// Starts an attempt: flushes the input and asks for the banner.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        self.attempts += 1;
        self.got = 0;
        port.flush_input();
        port.write(BANNER_REQUEST);
        self.stage = Stage::Banner {
            deadline: now.mono + ANSWER_TIMEOUT,
        };
    }

    /// Stops (the port closed).
    pub fn stop(&mut self) {
        self.stage = Stage::Idle;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.stage {
            Stage::Banner { deadline } | Stage::Ack { deadline } => Some(deadline),
            Stage::Idle | Stage::Done => None,
        }
    }

    /// Notices a time-out.
    pub fn poll(&mut self, now: Now) -> Progress {
        match self.stage {
            Stage::Banner { deadline } if now.mono >= deadline => {
                let f = if self.got == 0 {
                    Failure::NoBanner
                } else {
                    Failure::ShortBanner(self.got)
                };
                self.fail(now, f)
            }
            Stage::Ack { deadline } if now.mono >= deadline => {
                let f = if self.got == 0 {
                    Failure::NoAck
                } else {
                    Failure::ShortAck
                };
                self.fail(now, f)
            }
            _ => Progress::Busy,
        }
    }

    /// Takes bytes that arrived at `now`; returns what happened and how many bytes it used
    /// (the rest, after [`Progress::Done`], are records).
    pub fn received(&mut self, bytes: &[u8], now: Now, port: &mut PortOps) -> (Progress, usize) {
        for (i, &b) in bytes.iter().enumerate() {
            let p = self.byte(b, now, port);
            if p != Progress::Busy {
                return (p, i + 1);
            }
        }
        (Progress::Busy, bytes.len())
    }

    fn byte(&mut self, b: u8, now: Now, port: &mut PortOps) -> Progress {
        match self.stage {
            Stage::Banner { .. } => {
                if self.got < BANNER_PREFIX.len() {
                    // Look for the prefix; its first character occurs only once in it.
                    self.got = if b == BANNER_PREFIX[self.got] {
                        self.got + 1
                    } else {
                        usize::from(b == BANNER_PREFIX[0])
                    };
                    self.banner[..self.got].copy_from_slice(&BANNER_PREFIX[..self.got]);
                    return Progress::Busy;
                }
                self.banner[self.got] = b;
                self.got += 1;
                if self.got < BANNER_LEN {
                    return Progress::Busy;
                }
                let version = [self.banner[38], self.banner[40], self.banner[41]];
                if version != *b"307" {
                    return self.fail(now, Failure::BadVersion(version));
                }
                port.write(&self.command);
                self.got = 0;
                self.stage = Stage::Ack {
                    deadline: now.mono + ANSWER_TIMEOUT,
                };
                Progress::Found(self.banner[42])
            }
            Stage::Ack { .. } => {
                if self.got == 0 {
                    self.ack = b;
                    self.got = 1;
                    return Progress::Busy;
                }
                if self.ack != b'a' {
                    return self.fail(now, Failure::BadAck(self.ack));
                }
                port.write(REQUEST);
                self.stage = Stage::Done;
                self.attempts = 0;
                Progress::Done
            }
            Stage::Idle | Stage::Done => Progress::Busy,
        }
    }

    fn fail(&mut self, _now: Now, failure: Failure) -> Progress {
        self.stage = Stage::Idle;
        Progress::Failed(failure)
    }
}
