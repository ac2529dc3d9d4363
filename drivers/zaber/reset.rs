//! The Zaber reset as a state machine over deadlines: renumber the chain, then ask each device
//! in turn for its position and set it up, until one does not answer.
//!
//! The bytes are C++'s: `[0, 2, 0…]` (renumber: every device answers with its new number),
//! then for device `n` = 1, 2, … : position (23), mode 16 (40), speed 128 (41), acceleration
//! 128 (42), each command [`COMMAND_GAP`] after the previous; the four answers (24 bytes) must
//! start with `[n, 23]`, and their data is the device's position. A device that sends nothing
//! within [`PROBE_TIME`] of the last command ends the chain. C++ sleeps 1 s before and 1 s
//! after renumbering; here the renumbering ends once the answers stop for [`QUIET`] (at most
//! [`RENUMBER_TIME`]).

use std::time::{Duration, Instant};

use super::reply::{command, LEN, POSITION, RENUMBER, SET_ACCELERATION, SET_MODE, SET_SPEED};
use crate::serial::PortOps;
use crate::time::Now;

/// Longest wait for the renumbering's answers.
pub const RENUMBER_TIME: Duration = Duration::from_secs(1);
/// Silence after the last renumbering answer that ends the wait.
pub const QUIET: Duration = Duration::from_millis(100);
/// Time between the four commands to one device (as C++).
pub const COMMAND_GAP: Duration = Duration::from_millis(10);
/// Time the four answers have after the last command (C++: 30 ms; at 9600 baud 24 bytes take
/// 25 ms).
pub const PROBE_TIME: Duration = Duration::from_millis(100);
/// Most devices in a chain (device numbers are one byte).
pub const MAX_DEVICES: usize = 254;

/// How an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No device answered.
    NoDevices,
    /// Device `device` sent `got` of the 24 bytes.
    Short {
        /// The device probed.
        device: u8,
        /// Bytes received.
        got: usize,
    },
    /// Device `device`'s answer did not start `[device, 23]`.
    BadAnswer {
        /// The device probed.
        device: u8,
        /// The answer's first two bytes.
        got: [u8; 2],
    },
}

/// What a step led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still going.
    Working,
    /// The chain has `devices` devices.
    Done {
        /// How many answered.
        devices: usize,
    },
    /// This attempt failed.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    Renumber {
        until: Instant,
        quiet: Option<Instant>,
    },
    Probe {
        device: u8,
        written: usize,
        next: Instant,
    },
}

/// The reset. See the module documentation.
#[derive(Clone, Debug)]
pub struct ResetSequence {
    step: Step,
    answer: [u8; 4 * LEN],
    got: usize,
    /// Each device's position and the time its answer's first byte arrived.
    positions: [(i32, Option<Now>); MAX_DEVICES],
}

impl Default for ResetSequence {
    fn default() -> ResetSequence {
        ResetSequence::new()
    }
}

impl ResetSequence {
    /// A reset not started.
    pub fn new() -> ResetSequence {
        ResetSequence {
            step: Step::Idle,
            answer: [0; 4 * LEN],
            got: 0,
            positions: [(0, None); MAX_DEVICES],
        }
    }

    /// The positions read by the last completed reset (device 1 first).
    pub fn positions(&self) -> &[(i32, Option<Now>)] {
        &self.positions
    }

    /// Starts: flushes the input and renumbers the chain.
    pub fn start(&mut self, now: Now, port: &mut PortOps) {
        port.flush_input();
        port.write(&command(0, RENUMBER, 0));
        self.step = Step::Renumber {
            until: now.mono + RENUMBER_TIME,
            quiet: None,
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
            Step::Renumber { until, quiet } => Some(quiet.map_or(until, |q| q.min(until))),
            Step::Probe { next, .. } => Some(next),
        }
    }

    fn probe(&mut self, device: u8, now: Now, port: &mut PortOps) {
        port.flush_input();
        port.write(&command(device, POSITION, 0));
        self.got = 0;
        self.step = Step::Probe {
            device,
            written: 1,
            next: now.mono + COMMAND_GAP,
        };
    }

    /// Bytes arrived at `now`.
    pub fn received(&mut self, bytes: &[u8], now: Now, port: &mut PortOps) -> Progress {
        match self.step {
            Step::Idle => Progress::Working,
            Step::Renumber { until, .. } => {
                // Renumbering answers: the wait ends once they stop.
                self.step = Step::Renumber {
                    until,
                    quiet: Some(now.mono + QUIET),
                };
                Progress::Working
            }
            Step::Probe { device, .. } => {
                if self.got == 0 && !bytes.is_empty() {
                    self.positions[usize::from(device) - 1].1 = Some(now);
                }
                let n = bytes.len().min(self.answer.len() - self.got);
                self.answer[self.got..self.got + n].copy_from_slice(&bytes[..n]);
                self.got += n;
                if self.got < self.answer.len() {
                    return Progress::Working;
                }
                self.checked(device, now, port)
            }
        }
    }

    /// The four answers of `device` are in.
    fn checked(&mut self, device: u8, now: Now, port: &mut PortOps) -> Progress {
        let a = self.answer;
        if a[0] != device || a[1] != POSITION {
            self.step = Step::Idle;
            return Progress::Failed(Failure::BadAnswer {
                device,
                got: [a[0], a[1]],
            });
        }
        self.positions[usize::from(device) - 1].0 = i32::from_le_bytes([a[2], a[3], a[4], a[5]]);
        if usize::from(device) >= MAX_DEVICES {
            self.step = Step::Idle;
            return Progress::Done {
                devices: MAX_DEVICES,
            };
        }
        self.probe(device + 1, now, port);
        Progress::Working
    }

    /// A deadline passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        match self.step {
            Step::Idle => Progress::Working,
            Step::Renumber { until, quiet } => {
                if now.mono >= until || quiet.is_some_and(|q| now.mono >= q) {
                    self.probe(1, now, port);
                }
                Progress::Working
            }
            Step::Probe {
                device,
                written,
                next,
            } => {
                if now.mono < next {
                    return Progress::Working;
                }
                if written < 4 {
                    let (cmd, data) =
                        [(SET_MODE, 16), (SET_SPEED, 128), (SET_ACCELERATION, 128)][written - 1];
                    port.write(&command(device, cmd, data));
                    let gap = if written == 3 {
                        PROBE_TIME
                    } else {
                        COMMAND_GAP
                    };
                    self.step = Step::Probe {
                        device,
                        written: written + 1,
                        next: now.mono + gap,
                    };
                    return Progress::Working;
                }
                self.step = Step::Idle;
                match self.got {
                    0 if device == 1 => Progress::Failed(Failure::NoDevices),
                    0 => Progress::Done {
                        devices: usize::from(device) - 1,
                    },
                    got => Progress::Failed(Failure::Short { device, got }),
                }
            }
        }
    }
}
