//! The DynaSight reset, as a state machine over deadlines.
//!
//! The bytes are C++ VRPN's; the waits are not:
//!
//! 1. Three Ctrl-C (`03 03 03`) and `'4'`: stop output, polling mode. C++ then sleeps 1 s.
//!    Here the reset waits until the line has been quiet for [`QUIET`] (a record still on its
//!    way has arrived, the stream has stopped), and at most [`STOP_LIMIT`].
//! 2. Input flushed, status request `0x11`. C++ sleeps 2 s and reads what is there. Here the
//!    answer is checked as soon as its eight bytes arrive, and [`STATUS_LIMIT`] (C++'s 2 s)
//!    is the time-out. An answer is good when its first two bytes have bit 7 set.
//! 3. Input flushed, `03 03 03 '0'`: continuous output (`'0'` is what C++ VRPN 07.38 sends;
//!    the original DynaSight command was `'V'`). C++ sleeps 1 s more; here the reset is done
//!    at once and the watchdog starts.
//!
//! On a DynaSight that answers at once this takes about [`QUIET`] plus the answer's transit
//! time, instead of 4 s.

use std::time::{Duration, Instant};

use crate::serial::PortOps;
use crate::time::Now;

/// Stop output, polling mode.
pub const STOP: &[u8] = &[0x03, 0x03, 0x03, b'4'];
/// Status request.
pub const STATUS_REQUEST: u8 = 0x11;
/// Start continuous output.
pub const CONTINUOUS: &[u8] = &[0x03, 0x03, 0x03, b'0'];
/// Bytes in the status answer.
pub const STATUS_LEN: usize = 8;
/// Silence that shows the stream has stopped (longer than the gap between records).
pub const QUIET: Duration = Duration::from_millis(100);
/// Longest wait for the stream to stop; the status request goes out after it regardless.
pub const STOP_LIMIT: Duration = Duration::from_secs(1);
/// Longest wait for the status answer (C++'s fixed wait).
pub const STATUS_LIMIT: Duration = Duration::from_secs(2);

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// Nothing answered the status request.
    NoAnswer,
    /// Fewer than eight bytes answered it.
    Incomplete(usize),
    /// Eight bytes, but not a status record (first two bytes).
    BadStatus([u8; 2]),
}

/// What a call into the sequence led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still working.
    Working,
    /// The DynaSight answered; continuous output was requested. `kept_sending` says the
    /// stream never stopped before the status request.
    Done {
        /// The line never went quiet after the stop command.
        kept_sending: bool,
    },
    /// The attempt failed; the caller decides when to start again.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    /// Waiting for the line to go quiet after the stop command.
    Stopping {
        quiet_at: Instant,
        give_up: Instant,
    },
    /// Waiting for the status answer.
    Status {
        got: [u8; STATUS_LEN],
        len: usize,
        give_up: Instant,
        kept_sending: bool,
    },
}

/// The reset sequence. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    step: Step,
    attempts: u32,
}

impl Default for ResetSequence {
    fn default() -> ResetSequence {
        ResetSequence::new()
    }
}

impl ResetSequence {
    /// A sequence that has not started.
    pub fn new() -> ResetSequence {
        ResetSequence {
            step: Step::Idle,
            attempts: 0,
        }
    }

    /// Attempts started since the last success.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// True while an attempt runs.
    pub fn is_running(&self) -> bool {
        self.step != Step::Idle
    }

    /// Abandons the attempt (the port closed).
    pub fn stop(&mut self) {
        self.step = Step::Idle;
    }

    /// Starts an attempt: stop command.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        self.attempts += 1;
        port.write(STOP);
        self.step = Step::Stopping {
            quiet_at: now.mono + QUIET,
            give_up: now.mono + STOP_LIMIT,
        };
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.step {
            Step::Idle => None,
            Step::Stopping { quiet_at, give_up } => Some(quiet_at.min(give_up)),
            Step::Status { give_up, .. } => Some(give_up),
        }
    }

    /// Bytes arrived.
    pub fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) -> Progress {
        match &mut self.step {
            Step::Idle => Progress::Working,
            Step::Stopping { quiet_at, .. } => {
                if !bytes.is_empty() {
                    *quiet_at = arrived.mono + QUIET;
                }
                Progress::Working
            }
            Step::Status {
                got,
                len,
                kept_sending,
                ..
            } => {
                let take = bytes.len().min(STATUS_LEN - *len);
                got[*len..*len + take].copy_from_slice(&bytes[..take]);
                *len += take;
                if *len < STATUS_LEN {
                    return Progress::Working;
                }
                let (head, kept_sending) = ([got[0], got[1]], *kept_sending);
                self.step = Step::Idle;
                if head[0] & 0x80 == 0 || head[1] & 0x80 == 0 {
                    return Progress::Failed(Failure::BadStatus(head));
                }
                self.attempts = 0;
                port.flush_input();
                port.write(CONTINUOUS);
                Progress::Done { kept_sending }
            }
        }
    }

    /// Time passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        match self.step {
            Step::Idle => Progress::Working,
            Step::Stopping { quiet_at, give_up } => {
                if now.mono < quiet_at && now.mono < give_up {
                    return Progress::Working;
                }
                port.flush_input();
                port.write(&[STATUS_REQUEST]);
                self.step = Step::Status {
                    got: [0; STATUS_LEN],
                    len: 0,
                    give_up: now.mono + STATUS_LIMIT,
                    kept_sending: now.mono < quiet_at,
                };
                Progress::Working
            }
            Step::Status { len, give_up, .. } => {
                if now.mono < give_up {
                    return Progress::Working;
                }
                self.step = Step::Idle;
                Progress::Failed(if len == 0 {
                    Failure::NoAnswer
                } else {
                    Failure::Incomplete(len)
                })
            }
        }
    }
}
