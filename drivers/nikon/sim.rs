//! A simulated Nikon microscope focus: the device's end of its serial line, for tests and for
//! a simulator on a pseudo-terminal.
//!
//! It answers `rSPR` CR with `aSPR<ticks>` CR LF after 1 ms, and `fSMV<ticks>` CR with
//! `qSMVA` CR LF after 1 ms and, [`SimConfig::move_time`] later, `oSMV` CR LF with the focus
//! at `ticks`; a move beyond [`RANGE`] is answered `nSMV2` (operand error). The microscope
//! sends nothing unasked; [`NikonSim::turn_knob`] moves the focus by hand (the next position
//! request reports it). With [`SimConfig::keep_log`] it logs every position it tells
//! ([`NikonSim::sent`]) with the time the answer's first byte left.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator for `vrpn_device_sim`.
pub static SIMULATOR: Simulator = Simulator {
    name: "nikon",
    about: "Nikon microscope focus: answers position requests and focus moves",
    baud: 9600,
    line: "vrpn_nikon_controls Nikon0 {PATH}",
    make: |baud| Box::new(NikonSim::new(SimConfig::new(baud))),
};

/// The farthest the focus moves either way, in ticks.
pub const RANGE: i64 = 1_000_000;

/// How the simulated microscope behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Focus position at power-on.
    pub focus: i64,
    /// Time a move takes.
    pub move_time: Duration,
    /// Log what a client must receive.
    pub keep_log: bool,
}

impl SimConfig {
    /// A microscope at `baud`, its focus at 1234, moves taking 10 ms, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            focus: 1234,
            move_time: Duration::from_millis(10),
            keep_log: false,
        }
    }
}

/// A position the microscope told, and when the answer's first byte left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sent {
    /// The focus position in ticks.
    pub focus: i64,
    /// When the answer's first byte left.
    pub at: Instant,
}

/// The simulated microscope. See the module documentation.
pub struct NikonSim {
    cfg: SimConfig,
    focus: i64,
    command: Vec<u8>,
    /// Answers to write: when, the text, and the position it tells (to log).
    due: Vec<(Instant, Vec<u8>, Option<i64>)>,
    /// A move under way: when it ends and where.
    moving: Option<(Instant, i64)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    requests: u32,
    moves: u32,
    sent: Vec<Sent>,
}

impl NikonSim {
    /// A microscope behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> NikonSim {
        NikonSim {
            focus: cfg.focus,
            cfg,
            command: Vec::new(),
            due: Vec::new(),
            moving: None,
            out: VecDeque::new(),
            line_free: None,
            requests: 0,
            moves: 0,
            sent: Vec::new(),
        }
    }

    /// Every position told, in order.
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Position requests heard.
    pub fn requests(&self) -> u32 {
        self.requests
    }

    /// Moves heard.
    pub fn moves(&self) -> u32 {
        self.moves
    }

    /// The focus position now.
    pub fn focus(&self) -> i64 {
        self.focus
    }

    /// Moves the focus by hand.
    pub fn turn_knob(&mut self, to: i64) {
        self.focus = to;
    }

    fn byte_time(&self) -> Duration {
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    fn queue(&mut self, text: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let mut t = start;
        for &b in text {
            self.out.push_back((t, b));
            t += self.byte_time();
        }
        self.line_free = Some(t);
        start
    }

    fn command(&mut self, now: Instant) {
        let cmd = std::mem::take(&mut self.command);
        let soon = now + Duration::from_millis(1);
        if cmd == b"rSPR" {
            self.requests += 1;
            // The position told is the one when the answer is written.
            self.due.push((soon, b"aSPR".to_vec(), None));
        } else if let Some(arg) = cmd.strip_prefix(b"fSMV") {
            self.moves += 1;
            let to = std::str::from_utf8(arg)
                .ok()
                .and_then(|s| s.parse::<i64>().ok());
            match to {
                Some(to) if to.abs() <= RANGE => {
                    self.due.push((soon, b"qSMVA\r\n".to_vec(), None));
                    self.moving = Some((now + self.cfg.move_time, to));
                }
                _ => self.due.push((soon, b"nSMV2\r\n".to_vec(), None)),
            }
        }
    }
}

impl DeviceModel for NikonSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            if b == b'\r' {
                self.command(now.mono);
            } else if self.command.len() < 64 {
                self.command.push(b);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if let Some((t, to)) = self.moving {
            if t <= now.mono {
                self.moving = None;
                self.focus = to;
                self.due.push((t, b"oSMV\r\n".to_vec(), Some(to)));
            }
        }
        self.due.sort_by_key(|d| d.0);
        while self.due.first().is_some_and(|d| d.0 <= now.mono) {
            let (t, mut text, mut told) = self.due.remove(0);
            if text == b"aSPR" {
                text.extend_from_slice(format!("{}\r\n", self.focus).as_bytes());
                told = Some(self.focus);
            }
            let at = self.queue(&text, t);
            if let (Some(focus), true) = (told, self.cfg.keep_log) {
                self.sent.push(Sent { focus, at });
            }
        }
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        [
            self.out.front().map(|&(t, _)| t),
            self.moving.map(|m| m.0),
            self.due.iter().map(|d| d.0).min(),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
