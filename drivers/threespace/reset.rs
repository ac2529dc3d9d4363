//! The 3SPACE / ISOTRAK reset, as a state machine over deadlines.
//!
//! The bytes are C++ VRPN's; the waits are not (C++ sleeps 2 s after every byte of the break,
//! 10 or 20 s after a Ctrl-Y, 2 s before and 1 s after the status request, 1 s after each
//! setting):
//!
//! 1. **Break**, escalating with the attempt *n* (attempts since the last good one), one byte
//!    every [`BREAK_GAP`]:
//!    * 3SPACE: CR if *n* > 1, `Y` if *n* > 7, `t` if *n* > 4, `W` Ctrl-K (factory defaults,
//!      saved) if *n* > 3, then Ctrl-Y (reinitialise) always;
//!    * ISOTRAK: CR if *n* > 1, Ctrl-Y if *n* > 2, then `c` (stop continuous output).
//! 2. **Quiet**: the line must stay silent for [`QUIET`] (a record on its way has arrived;
//!    at most [`QUIET_LIMIT`]); then the input is flushed.
//! 3. **Status**: `S`; the answer starts with `2` and is [`Model`]'s status length (3SPACE:
//!    55 bytes ending in LF; ISOTRAK: 21 bytes), or ends early with an LF. No answer within
//!    [`STATUS_WAIT`] plus its transmission fails the attempt — unless a Ctrl-Y went out:
//!    then the tracker is reinitialising, and `S` is repeated every [`REBOOT_POLL`] for up
//!    to [`REBOOT_LIMIT`].
//! 4. **Configure**: the settings, one every [`CONFIG_GAP`]: `O2,11` CR (position and
//!    quaternion); the ISOTRAK also `x0.2,0.2,0.8,0.8` CR and `v0.2,0.2,0.8,0.8` CR
//!    (filters), `R1` CR (alignment), `b1` CR (boresight), `u` (metric), then the entry's
//!    extra reset commands (`*N` pauses N seconds).
//! 5. **Barrier**: input flushed, `S` again; its answer shows every setting was read (the
//!    replies to extra commands before it are dropped). None within [`BARRIER_WAIT`] fails
//!    the attempt.
//! 6. **Stream**: input flushed, `f` (binary records), `C` (continuous output). Done.

use std::time::{Duration, Instant};

use super::record::Model;
use crate::config::continuation::{command_bytes, ResetStep};
use crate::serial::PortOps;
use crate::time::Now;

/// Time between the bytes of the break.
pub const BREAK_GAP: Duration = Duration::from_millis(100);
/// Silence that shows output has stopped.
pub const QUIET: Duration = Duration::from_millis(100);
/// Longest wait for silence; the status request goes out after it regardless.
pub const QUIET_LIMIT: Duration = Duration::from_secs(2);
/// Wait for a status answer (C++'s fixed wait), plus the answer's transmission time.
pub const STATUS_WAIT: Duration = Duration::from_secs(1);
/// How long a tracker reinitialising after Ctrl-Y may take to answer (C++ waits 10 s for
/// the 3SPACE, 20 s for the ISOTRAK).
pub const REBOOT_LIMIT: Duration = Duration::from_secs(25);
/// How often `S` is repeated while the tracker reinitialises.
pub const REBOOT_POLL: Duration = Duration::from_millis(500);
/// Time between two settings.
pub const CONFIG_GAP: Duration = Duration::from_millis(50);
/// Wait for the status answer after the settings, plus its transmission time.
pub const BARRIER_WAIT: Duration = Duration::from_secs(2);

/// Ctrl-Y: reinitialise.
pub const CTRL_Y: u8 = 0x19;
/// Ctrl-K: save the settings.
pub const CTRL_K: u8 = 0x0B;

/// Bytes of the status answer.
pub const fn status_len(model: Model) -> usize {
    match model {
        Model::ThreeSpace => 55,
        Model::Isotrak => 21,
    }
}

/// The break bytes of attempt `n` (1-based), in order.
pub fn break_bytes(model: Model, n: u32) -> ([u8; 6], usize) {
    let mut b = [0u8; 6];
    let mut len = 0;
    let mut push = |x: u8| {
        b[len] = x;
        len += 1;
    };
    if n > 1 {
        push(b'\r');
    }
    match model {
        Model::ThreeSpace => {
            if n > 7 {
                push(b'Y');
            }
            if n > 3 {
                if n > 4 {
                    push(b't');
                }
                push(b'W');
                push(CTRL_K);
            }
            push(CTRL_Y);
        }
        Model::Isotrak => {
            if n > 2 {
                push(CTRL_Y);
            }
            push(b'c');
        }
    }
    (b, len)
}

/// The fixed settings of `model`, in order (each a separate write).
pub fn settings(model: Model) -> &'static [&'static [u8]] {
    match model {
        Model::ThreeSpace => &[b"O2,11\r"],
        Model::Isotrak => &[
            b"O2,11\r",
            b"x0.2,0.2,0.8,0.8\r",
            b"v0.2,0.2,0.8,0.8\r",
            b"R1\r",
            b"b1\r",
            b"u",
        ],
    }
}

/// Why an attempt failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No status answer (`n` bytes of one).
    NoStatus(usize),
    /// An answer that is not a status (its first bytes, at most 16).
    BadStatus([u8; 16], usize),
    /// No status answer after the settings.
    NoBarrier,
}

/// What a call into the sequence led to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still working.
    Working,
    /// The break was sent (attempt `n`): say so.
    Started(u32),
    /// A good status answer of `len` bytes arrived.
    GoodStatus {
        /// Its length.
        len: usize,
        /// Bytes that still came after the stop command, before the line went quiet.
        after_stop: usize,
    },
    /// The tracker streams: the reset is over.
    Done,
    /// The attempt failed; the caller starts the next.
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
    Status {
        give_up: Instant,
        reboot_until: Option<Instant>,
    },
    Settings {
        next: usize,
        at: Instant,
    },
    Barrier {
        give_up: Instant,
    },
}

/// The reset sequence. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    model: Model,
    baud: u32,
    extra: Vec<ResetStep>,
    step: Step,
    attempts: u32,
    breaks: ([u8; 6], usize),
    after_stop: usize,
    answer: [u8; 64],
    len: usize,
    first_len: usize,
    scratch: Vec<u8>,
}

impl ResetSequence {
    /// A sequence for `model` on a line at `baud`, with the entry's extra commands.
    pub fn new(model: Model, baud: u32, extra: Vec<ResetStep>) -> ResetSequence {
        ResetSequence {
            model,
            baud,
            extra,
            step: Step::Idle,
            attempts: 0,
            breaks: ([0; 6], 0),
            after_stop: 0,
            answer: [0; 64],
            len: 0,
            first_len: 0,
            scratch: Vec::with_capacity(128),
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

    /// Starts an attempt: the first break byte.
    pub fn start(&mut self, now: Now, port: &mut PortOps) -> Progress {
        self.attempts += 1;
        self.breaks = break_bytes(self.model, self.attempts);
        self.break_byte(0, now, port);
        Progress::Started(self.attempts)
    }

    fn sent_ctrl_y(&self) -> bool {
        self.breaks.0[..self.breaks.1].contains(&CTRL_Y)
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
            Step::Quiet { quiet_at, give_up } => Some(quiet_at.min(give_up)),
            Step::Status { give_up, .. } | Step::Barrier { give_up } => Some(give_up),
        }
    }

    fn ask_status(&mut self, now: Now, port: &mut PortOps, reboot_until: Option<Instant>) {
        port.flush_input();
        port.write(b"S");
        self.len = 0;
        let wait = if reboot_until.is_some() {
            REBOOT_POLL
        } else {
            STATUS_WAIT
        } + self.transmission(status_len(self.model));
        self.step = Step::Status {
            give_up: now.mono + wait,
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
                let reboot = self.sent_ctrl_y().then(|| now.mono + REBOOT_LIMIT);
                self.ask_status(now, port, reboot);
                Progress::Working
            }
            Step::Status {
                give_up,
                reboot_until,
            } => {
                if now.mono < give_up {
                    return Progress::Working;
                }
                if self.len == 0 && reboot_until.is_some_and(|t| now.mono < t) {
                    // Still reinitialising: ask again.
                    self.ask_status(now, port, reboot_until);
                    return Progress::Working;
                }
                self.step = Step::Idle;
                self.status_failure()
            }
            Step::Settings { next, at } => {
                if now.mono < at {
                    return Progress::Working;
                }
                self.setting(next, now, port);
                Progress::Working
            }
            Step::Barrier { give_up } => {
                if now.mono < give_up {
                    return Progress::Working;
                }
                self.step = Step::Idle;
                Progress::Failed(Failure::NoBarrier)
            }
        }
    }

    fn status_failure(&self) -> Progress {
        if self.len > 0 && self.answer[0] == b'2' || self.len == 0 {
            return Progress::Failed(Failure::NoStatus(self.len));
        }
        let mut head = [0u8; 16];
        let n = self.len.min(16);
        head[..n].copy_from_slice(&self.answer[..n]);
        Progress::Failed(Failure::BadStatus(head, n))
    }

    /// Writes setting `i` (the fixed ones, then the extra commands); after the last, the
    /// barrier.
    fn setting(&mut self, i: usize, now: Now, port: &mut PortOps) {
        let fixed = settings(self.model);
        if i < fixed.len() {
            port.write(fixed[i]);
            self.step = Step::Settings {
                next: i + 1,
                at: now.mono + CONFIG_GAP,
            };
            return;
        }
        match self.extra.get(i - fixed.len()) {
            Some(ResetStep::Command(c)) => {
                self.scratch.clear();
                command_bytes(c, &mut self.scratch);
                port.write(&self.scratch);
                self.step = Step::Settings {
                    next: i + 1,
                    at: now.mono + CONFIG_GAP,
                };
            }
            Some(ResetStep::Pause(s)) => {
                self.step = Step::Settings {
                    next: i + 1,
                    at: now.mono + Duration::from_secs(u64::from(*s)),
                };
            }
            None => {
                port.flush_input();
                port.write(b"S");
                self.len = 0;
                self.step = Step::Barrier {
                    give_up: now.mono + BARRIER_WAIT + self.transmission(self.first_len),
                };
            }
        }
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
            Step::Status { .. } => {
                for &b in bytes {
                    if self.len < self.answer.len() {
                        self.answer[self.len] = b;
                        self.len += 1;
                    }
                    let full = self.len >= status_len(self.model) || b == b'\n';
                    if !full {
                        continue;
                    }
                    let good =
                        self.answer[0] == b'2' && (self.model == Model::Isotrak || b == b'\n');
                    if !good {
                        self.step = Step::Idle;
                        return self.status_failure();
                    }
                    self.first_len = self.len;
                    self.attempts = 0;
                    self.setting(0, now, port);
                    return Progress::GoodStatus {
                        len: self.first_len,
                        after_stop: self.after_stop,
                    };
                }
                Progress::Working
            }
            Step::Barrier { .. } => {
                for &b in bytes {
                    if self.len < self.answer.len() {
                        self.answer[self.len] = b;
                        self.len += 1;
                    }
                    let line_end = b == b'\n' || self.len == self.first_len;
                    if !line_end {
                        continue;
                    }
                    if self.answer[0] == b'2' && self.len == self.first_len {
                        port.flush_input();
                        port.write(b"fC");
                        self.step = Step::Idle;
                        return Progress::Done;
                    }
                    // A reply to an extra command: dropped.
                    self.len = 0;
                }
                Progress::Working
            }
        }
    }
}
