//! The IDEA reset as a state machine over deadlines, in C++'s order:
//!
//! 1. flush the input, `R` (software reset); ask `f` until the drive answers (C++ sleeps
//!    250 ms first; here the first ask goes [`FIRST_ASK`] after `R` and is repeated every
//!    [`ASK_AGAIN`] for [`BOOT_TIME`]); a fault code other than 0 fails the attempt;
//! 2. `Z0` (position 0), `O<bits>` (the outputs the line sets), `:` (the inputs);
//! 3. `l` (the position);
//! 4. the limit program: `Pfoundlimit,1,1`, `A`, `X`, `P`, answered `` `P<size> ``;
//! 5. with a nonzero initial move: that move at the line's fraction, then `o` until the drive
//!    says it stopped ([`MOVE_POLL`] apart);
//! 6. with a forward initial move and a high limit switch, the limit hunt: `l`, `:`, and while
//!    the switch is open another move of the same length, until it closes;
//! 7. `Z<reset location × 64>` and `l`: the reset is done and the position's answer starts the
//!    stream.
//!
//! Each answer has [`ANSWER_TIME`] ([`PROGRAM_TIME`] for the program); answers of another
//! kind (a repeated `f`, a late one) are passed over.

use std::time::{Duration, Instant};

use super::answer::{Answer, Command};
use super::config::Idea;
use super::moves::{outputs_value, write_move};
use crate::serial::PortOps;
use crate::time::Now;

/// From `R` to the first `f`.
pub const FIRST_ASK: Duration = Duration::from_millis(20);
/// Between two `f` while the drive does not answer.
pub const ASK_AGAIN: Duration = Duration::from_millis(50);
/// Longest wait for the drive to answer `f` after `R`.
pub const BOOT_TIME: Duration = Duration::from_secs(1);
/// Time an answer has (C++: 30 ms; generous for a loaded host).
pub const ANSWER_TIME: Duration = Duration::from_millis(200);
/// Time the program's answer has (as C++).
pub const PROGRAM_TIME: Duration = Duration::from_millis(300);
/// Between the moving-status questions.
pub const MOVE_POLL: Duration = Duration::from_millis(10);
/// Most moves of one limit hunt.
pub const MAX_HUNT_MOVES: u32 = 10_000;

/// How an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No answer to `f`.
    NoFaultStatus,
    /// The drive reports this fault code.
    Fault(i64),
    /// No answer to `:`.
    NoIo,
    /// No answer to `l`.
    NoPosition,
    /// No answer to the limit program.
    NoProgram,
    /// No answer to `o`.
    NoMoveStatus,
    /// The high limit switch never closed.
    HuntTooLong,
}

impl Failure {
    /// The error text (C++'s where it has one).
    pub fn text(self) -> &'static str {
        match self {
            Failure::NoFaultStatus => "reset(): Bad fault status report (no answer to f)",
            Failure::Fault(_) => "Drive reports a fault",
            Failure::NoIo => "reset(): Bad I/O status report (no answer to :)",
            Failure::NoPosition => "reset(): Bad position report (no answer to l)",
            Failure::NoProgram => "reset(): Could not write limit program (no answer to P)",
            Failure::NoMoveStatus => "Bad movement status report (no answer to o)",
            Failure::HuntTooLong => "reset(): the high limit switch never closed",
        }
    }
}

/// What a step led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still going.
    Working,
    /// Done: the position is set and `l` written.
    Done,
    /// This attempt failed.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    Booting { ask_at: Instant, give_up: Instant },
    Io { by: Instant },
    Position { by: Instant },
    Program { by: Instant },
    MoveStatus { by: Instant },
    MoveWait { ask_at: Instant },
    HuntPosition { by: Instant },
    HuntIo { by: Instant },
}

/// The reset. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    cfg: Idea,
    step: Step,
    position: i64,
    inputs: u8,
    hunt_moves: u32,
    into_limit: bool,
}

fn send(port: &mut PortOps, args: std::fmt::Arguments<'_>) {
    if let Some(c) = Command::new(args) {
        port.write(c.bytes());
    }
}

impl ResetSequence {
    /// A reset for the drive `cfg` describes, not started.
    pub fn new(cfg: &Idea) -> ResetSequence {
        ResetSequence {
            cfg: cfg.clone(),
            step: Step::Idle,
            position: 0,
            inputs: 0,
            hunt_moves: 0,
            into_limit: false,
        }
    }

    /// The position (1/64 steps) the drive was set to, once done.
    pub fn position(&self) -> i64 {
        self.position
    }

    /// The inputs read last (bit 0: input 1).
    pub fn inputs(&self) -> u8 {
        self.inputs
    }

    /// Whether a move of this reset was refused because its limit switch was closed (C++
    /// warns "Asked to move into limit").
    pub fn take_into_limit(&mut self) -> bool {
        std::mem::take(&mut self.into_limit)
    }

    /// Starts: flushes the input and resets the drive.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        port.flush_input();
        port.write(b"R\r");
        self.hunt_moves = 0;
        self.step = Step::Booting {
            ask_at: now.mono + FIRST_ASK,
            give_up: now.mono + BOOT_TIME,
        };
    }

    /// Abandons the reset.
    pub fn stop(&mut self) {
        self.step = Step::Idle;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.step {
            Step::Idle => None,
            Step::Booting { ask_at, give_up } => Some(ask_at.min(give_up)),
            Step::MoveWait { ask_at } => Some(ask_at),
            Step::Io { by }
            | Step::Position { by }
            | Step::Program { by }
            | Step::MoveStatus { by }
            | Step::HuntPosition { by }
            | Step::HuntIo { by } => Some(by),
        }
    }

    fn fail(&mut self, f: Failure) -> Progress {
        self.step = Step::Idle;
        Progress::Failed(f)
    }

    /// A move to `to` steps at the line's fraction, then the question whether it is done.
    fn start_move(&mut self, to: f64, now: Now, port: &mut PortOps) -> Progress {
        let from = self.position as f64 / 64.0;
        let (cfg, inputs) = (&self.cfg, self.inputs);
        let outcome = write_move(cfg, from, inputs, to, cfg.fraction, &mut |b| port.write(b));
        if outcome == super::moves::Outcome::IntoLimit {
            self.into_limit = true;
        }
        port.write(b"o\r");
        self.step = Step::MoveStatus {
            by: now.mono + ANSWER_TIME,
        };
        Progress::Working
    }

    /// After a move (or the program when there is none): hunt for the high limit, or finish.
    fn after_move(&mut self, now: Now, port: &mut PortOps) -> Progress {
        if self.cfg.initial_move > 0.0 && self.cfg.high_limit.is_some() {
            port.write(b"l\r");
            self.step = Step::HuntPosition {
                by: now.mono + ANSWER_TIME,
            };
            return Progress::Working;
        }
        self.finish(port)
    }

    fn finish(&mut self, port: &mut PortOps) -> Progress {
        let at = (64.0 * self.cfg.reset_location) as i64;
        send(port, format_args!("Z{at}"));
        port.write(b"l\r");
        self.position = at;
        self.step = Step::Idle;
        Progress::Done
    }

    /// An answer arrived (its first byte at `now`).
    pub fn answer(&mut self, a: Answer, now: Now, port: &mut PortOps) -> Progress {
        let by = now.mono + ANSWER_TIME;
        match (self.step, a) {
            (Step::Booting { .. }, Answer::Fault(0)) => {
                port.write(b"Z0\r");
                send(port, format_args!("O{}", outputs_value(&self.cfg.outputs)));
                port.write(b":\r");
                self.position = 0;
                self.step = Step::Io { by };
                Progress::Working
            }
            (Step::Booting { .. }, Answer::Fault(code)) => self.fail(Failure::Fault(code)),
            (Step::Io { .. }, Answer::Io(bits)) => {
                self.inputs = (bits & 0xF) as u8;
                port.write(b"l\r");
                self.step = Step::Position { by };
                Progress::Working
            }
            (Step::Position { .. }, Answer::Position(p)) => {
                self.position = p;
                for line in [&b"Pfoundlimit,1,1\r"[..], b"A\r", b"X\r", b"P\r"] {
                    port.write(line);
                }
                self.step = Step::Program {
                    by: now.mono + PROGRAM_TIME,
                };
                Progress::Working
            }
            (Step::Program { .. }, Answer::Program(_)) => {
                if self.cfg.initial_move != 0.0 {
                    return self.start_move(self.cfg.initial_move, now, port);
                }
                self.after_move(now, port)
            }
            (Step::MoveStatus { .. }, Answer::Moving(true)) => {
                self.step = Step::MoveWait {
                    ask_at: now.mono + MOVE_POLL,
                };
                Progress::Working
            }
            (Step::MoveStatus { .. }, Answer::Moving(false)) => self.after_move(now, port),
            (Step::HuntPosition { .. }, Answer::Position(p)) => {
                self.position = p;
                port.write(b":\r");
                self.step = Step::HuntIo { by };
                Progress::Working
            }
            (Step::HuntIo { .. }, Answer::Io(bits)) => {
                self.inputs = (bits & 0xF) as u8;
                let high = self.cfg.high_limit.unwrap_or(1);
                if self.inputs & (1 << (high - 1)) != 0 {
                    return self.finish(port);
                }
                self.hunt_moves += 1;
                if self.hunt_moves > MAX_HUNT_MOVES {
                    return self.fail(Failure::HuntTooLong);
                }
                let to = self.position as f64 / 64.0 + self.cfg.initial_move;
                self.start_move(to, now, port)
            }
            // Answers of another kind: repeated or late ones.
            _ => Progress::Working,
        }
    }

    /// A deadline passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        let t = now.mono;
        match self.step {
            Step::Idle => Progress::Working,
            Step::Booting { give_up, .. } if t >= give_up => self.fail(Failure::NoFaultStatus),
            Step::Booting { ask_at, give_up } => {
                if t >= ask_at {
                    port.write(b"f\r");
                    self.step = Step::Booting {
                        ask_at: t + ASK_AGAIN,
                        give_up,
                    };
                }
                Progress::Working
            }
            Step::MoveWait { ask_at } => {
                if t >= ask_at {
                    port.write(b"o\r");
                    self.step = Step::MoveStatus {
                        by: t + ANSWER_TIME,
                    };
                }
                Progress::Working
            }
            Step::Io { by } if t >= by => self.fail(Failure::NoIo),
            Step::Position { by } | Step::HuntPosition { by } if t >= by => {
                self.fail(Failure::NoPosition)
            }
            Step::HuntIo { by } if t >= by => self.fail(Failure::NoIo),
            Step::Program { by } if t >= by => self.fail(Failure::NoProgram),
            Step::MoveStatus { by } if t >= by => self.fail(Failure::NoMoveStatus),
            _ => Progress::Working,
        }
    }
}
