//! The Polaris reset, as a state machine over deadlines.
//!
//! The commands are C++ VRPN's; the waits are deadlines, and every command waits for its
//! reply (C++ blocks on each reply with no time limit, and sleeps 100 ms three times):
//!
//! 1. **RTS pulse** at 9600 baud: RTS set for [`RTS_PULSE`], cleared, [`SETTLE`] for the
//!    tracker's `RESET` message, input flushed.
//! 2. **`COMM 50000`**: the tracker is to talk at 115200 baud (C++ asks for 1 228 739 baud
//!    with `COMM 70000`, a rate Linux serial ports cannot be set to by name). A `RESET`
//!    reply is answered by asking again; after `OKAY` the port follows after
//!    [`SWITCH_WAIT`]. No reply within [`COMM_WAIT`]: the tracker may still be at 115200
//!    from before (the RTS pulse reaches no tracker through every adapter), so the port
//!    switches anyway and the attempt goes on; `INIT` tells whether it was right.
//! 3. **`INIT `**, **`IRATE 0`** (20 Hz illumination, C++'s choice).
//! 4. **Each tool**: `PHRQ *********1****` (a port handle for a passive tool: the handle in
//!    the reply), its `.rom` image in 64-byte chunks `PVWR hhAAAA<128 hex digits>`,
//!    `PINIT hh`, `PENA hhD` (dynamic tool). A tool the tracker refuses (`ERROR` to `PHRQ`
//!    or `PINIT`) is reported and left out; the others go on, as in C++.
//! 5. **`TSTART 80`** (tracking, frame counter zeroed). Every command waits at most
//!    [`REPLY_WAIT`] for its reply; none, or an `ERROR` where C++ gives up, fails the attempt.

use std::time::{Duration, Instant};

use super::reply::hex;
use crate::serial::PortOps;
use crate::time::Now;

/// How long RTS is held.
pub const RTS_PULSE: Duration = Duration::from_millis(100);
/// Time for the tracker to restart after the pulse.
pub const SETTLE: Duration = Duration::from_millis(100);
/// The tracker's speed after a reset.
pub const START_BAUD: u32 = 9600;
/// The speed it is switched to.
pub const FAST_BAUD: u32 = 115_200;
/// The command that switches it (115200 baud, 8 bits, no parity, 1 stop bit, no handshake).
pub const COMM: &[u8] = b"COMM 50000\r";
/// The wait for `COMM`'s reply.
pub const COMM_WAIT: Duration = Duration::from_millis(300);
/// The tracker needs this long after its `OKAY` before the host changes speed.
pub const SWITCH_WAIT: Duration = Duration::from_millis(100);
/// The wait for any other reply.
pub const REPLY_WAIT: Duration = Duration::from_secs(2);
/// Bytes of a `.rom` image per `PVWR`.
pub const CHUNK: usize = 64;
/// The largest `.rom` image (C++'s limit).
pub const MAX_ROM: usize = 1024;

/// A command of the reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// `COMM 50000`.
    Comm,
    /// `INIT `.
    Init,
    /// `IRATE 0`.
    Irate,
    /// `PHRQ` for tool `t` (0-based, in the entry's order).
    Phrq(usize),
    /// `PVWR` of chunk `c` of tool `t`'s image.
    Pvwr(usize, usize),
    /// `PINIT` of tool `t`'s handle.
    Pinit(usize),
    /// `PENA` of tool `t`'s handle.
    Pena(usize),
    /// `TSTART 80`.
    Tstart,
}

/// Why an attempt failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// No reply to a command within its wait.
    NoReply(Command),
    /// `ERROR` (with its code) to a command the reset cannot do without.
    Refused(Command, u8),
    /// A reply that is neither `OKAY` nor what the command asks for.
    Unexpected(Command),
}

/// What a call into the sequence led to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Still working.
    Working,
    /// The attempt `n` started.
    Started(u32),
    /// `COMM` went unanswered: the port switched on the chance the tracker is fast already.
    AssumedFast,
    /// Tool `t` was refused (its command and the error code); the others go on.
    ToolRefused(usize, Command, u8),
    /// Tracking: the reset is over.
    Done,
    /// The attempt failed.
    Failed(Failure),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    RtsHeld(Instant),
    Settling(Instant),
    Waiting { cmd: Command, until: Instant },
    Switching(Instant),
}

/// The reset sequence. See the module documentation.
pub struct ResetSequence {
    roms: Vec<Vec<u8>>,
    handles: Vec<Option<u8>>,
    step: Step,
    attempts: u32,
    assumed_fast: bool,
    scratch: Vec<u8>,
}

impl ResetSequence {
    /// A sequence for tools with these `.rom` images (each padded to whole chunks).
    pub fn new(roms: Vec<Vec<u8>>) -> ResetSequence {
        let n = roms.len();
        ResetSequence {
            roms,
            handles: vec![None; n],
            step: Step::Idle,
            attempts: 0,
            assumed_fast: false,
            scratch: Vec::with_capacity(256),
        }
    }

    /// The port handle of each tool, where it has one (after a reset).
    pub fn handles(&self) -> &[Option<u8>] {
        &self.handles
    }

    /// Attempts started since the last good one.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// Abandons the attempt.
    pub fn stop(&mut self) {
        self.step = Step::Idle;
    }

    /// When [`poll`](Self::poll) is next needed.
    pub fn deadline(&self) -> Option<Instant> {
        match self.step {
            Step::Idle => None,
            Step::RtsHeld(t) | Step::Settling(t) | Step::Switching(t) => Some(t),
            Step::Waiting { until, .. } => Some(until),
        }
    }

    /// Starts an attempt: the port back at 9600 baud, RTS set.
    pub fn start(&mut self, now: Now, port: &mut PortOps) -> Progress {
        self.attempts += 1;
        self.assumed_fast = false;
        self.handles.iter_mut().for_each(|h| *h = None);
        port.set_baud(START_BAUD);
        port.set_rts(true);
        self.step = Step::RtsHeld(now.mono + RTS_PULSE);
        Progress::Started(self.attempts)
    }

    fn send(&mut self, cmd: Command, now: Now, port: &mut PortOps) {
        self.scratch.clear();
        command_bytes(cmd, &self.roms, &self.handles, &mut self.scratch);
        port.write(&self.scratch);
        let wait = if cmd == Command::Comm {
            COMM_WAIT
        } else {
            REPLY_WAIT
        };
        self.step = Step::Waiting {
            cmd,
            until: now.mono + wait,
        };
    }

    /// The command after `cmd` (tools without a handle are passed over).
    fn after(&self, cmd: Command) -> Command {
        let first_of = |t: usize| {
            if t < self.roms.len() {
                Command::Phrq(t)
            } else {
                Command::Tstart
            }
        };
        match cmd {
            Command::Comm => Command::Init,
            Command::Init => Command::Irate,
            Command::Irate => first_of(0),
            Command::Phrq(t) if self.handles[t].is_none() => first_of(t + 1),
            Command::Phrq(t) => Command::Pvwr(t, 0),
            Command::Pvwr(t, c) if (c + 1) * CHUNK < self.roms[t].len() => Command::Pvwr(t, c + 1),
            Command::Pvwr(t, _) => Command::Pinit(t),
            Command::Pinit(t) if self.handles[t].is_none() => first_of(t + 1),
            Command::Pinit(t) => Command::Pena(t),
            Command::Pena(t) => first_of(t + 1),
            Command::Tstart => Command::Tstart,
        }
    }

    /// Time passed.
    pub fn poll(&mut self, now: Now, port: &mut PortOps) -> Progress {
        match self.step {
            Step::Idle => Progress::Working,
            Step::RtsHeld(t) if now.mono >= t => {
                port.set_rts(false);
                self.step = Step::Settling(now.mono + SETTLE);
                Progress::Working
            }
            Step::Settling(t) if now.mono >= t => {
                port.flush_input();
                self.send(Command::Comm, now, port);
                Progress::Working
            }
            Step::Switching(t) if now.mono >= t => {
                port.set_baud(FAST_BAUD);
                self.send(Command::Init, now, port);
                Progress::Working
            }
            Step::Waiting { cmd, until } if now.mono >= until => {
                if cmd == Command::Comm {
                    self.assumed_fast = true;
                    port.flush_input();
                    port.set_baud(FAST_BAUD);
                    self.send(Command::Init, now, port);
                    return Progress::AssumedFast;
                }
                self.step = Step::Idle;
                Progress::Failed(Failure::NoReply(cmd))
            }
            _ => Progress::Working,
        }
    }

    /// A reply arrived (its body, without CRC).
    pub fn reply(&mut self, body: &[u8], now: Now, port: &mut PortOps) -> Progress {
        let Step::Waiting { cmd, .. } = self.step else {
            // Nothing asked: a `RESET` after the pulse, or a late reply.
            return Progress::Working;
        };
        if body.starts_with(b"RESET") {
            if cmd == Command::Comm {
                self.send(Command::Comm, now, port);
                return Progress::Working;
            }
            self.step = Step::Idle;
            return Progress::Failed(Failure::Unexpected(cmd));
        }
        let error = body
            .strip_prefix(b"ERROR")
            .map(|code| code.get(..2).and_then(hex).unwrap_or(0) as u8);
        match (cmd, error) {
            (Command::Phrq(t), Some(code)) | (Command::Pinit(t), Some(code)) => {
                self.handles[t] = None;
                let next = self.after(cmd);
                self.send(next, now, port);
                return Progress::ToolRefused(t, cmd, code);
            }
            (_, Some(code)) => {
                self.step = Step::Idle;
                return Progress::Failed(Failure::Refused(cmd, code));
            }
            (Command::Phrq(t), None) => match body.get(..2).and_then(hex) {
                Some(h) if body.len() == 2 => self.handles[t] = Some(h as u8),
                _ => {
                    self.step = Step::Idle;
                    return Progress::Failed(Failure::Unexpected(cmd));
                }
            },
            (_, None) if !body.starts_with(b"OKAY") => {
                self.step = Step::Idle;
                return Progress::Failed(Failure::Unexpected(cmd));
            }
            _ => {}
        }
        match cmd {
            Command::Comm => {
                self.step = Step::Switching(now.mono + SWITCH_WAIT);
                Progress::Working
            }
            Command::Tstart => {
                self.step = Step::Idle;
                self.attempts = 0;
                Progress::Done
            }
            _ => {
                let next = self.after(cmd);
                self.send(next, now, port);
                Progress::Working
            }
        }
    }

    /// True when the attempt went on at 115200 baud without the tracker's word.
    pub fn assumed_fast(&self) -> bool {
        self.assumed_fast
    }
}

/// The bytes of `cmd`, CR included.
pub fn command_bytes(cmd: Command, roms: &[Vec<u8>], handles: &[Option<u8>], out: &mut Vec<u8>) {
    use std::io::Write;
    let h = |t: usize| handles[t].unwrap_or(0);
    let _ = match cmd {
        Command::Comm => write!(out, "COMM 50000"),
        Command::Init => write!(out, "INIT "),
        Command::Irate => write!(out, "IRATE 0"),
        Command::Phrq(_) => write!(out, "PHRQ *********1****"),
        Command::Pvwr(t, c) => {
            let _ = write!(out, "PVWR {:02X}{:04x}", h(t), c * CHUNK);
            for b in &roms[t][c * CHUNK..(c + 1) * CHUNK] {
                let _ = write!(out, "{b:02x}");
            }
            Ok(())
        }
        Command::Pinit(t) => write!(out, "PINIT {:02X}", h(t)),
        Command::Pena(t) => write!(out, "PENA {:02X}D", h(t)),
        Command::Tstart => write!(out, "TSTART 80"),
    };
    out.push(b'\r');
}

/// A `.rom` image padded with zeros to whole chunks, as it is sent.
pub fn padded(mut rom: Vec<u8>) -> Vec<u8> {
    let n = rom.len().div_ceil(CHUNK).max(1) * CHUNK;
    rom.resize(n, 0);
    rom
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_are_c_plus_plus_s_with_hex_handles() {
        let roms = vec![padded(vec![0xAB; 70])];
        let handles = [Some(0x0A)];
        let mut v = Vec::new();
        command_bytes(Command::Pvwr(0, 1), &roms, &handles, &mut v);
        let mut want = b"PVWR 0A0040".to_vec();
        want.extend(b"ab".repeat(6));
        want.extend(b"00".repeat(58));
        want.push(b'\r');
        assert_eq!(v, want);
        v.clear();
        command_bytes(Command::Pena(0), &roms, &handles, &mut v);
        command_bytes(Command::Pinit(0), &roms, &handles, &mut v);
        command_bytes(Command::Phrq(0), &roms, &handles, &mut v);
        assert_eq!(v, b"PENA 0AD\rPINIT 0A\rPHRQ *********1****\r");
        assert_eq!(roms[0].len(), 128);
    }
}
