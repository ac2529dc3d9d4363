//! A simulated IDEA drive and its motor: the device end of the serial line, for tests and for
//! a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * Answers `f` (fault code, [`SimConfig::fault`]), `l` (the position counter in 1/64
//!   steps), `:` (inputs 1–4 in bits 0–3, the outputs in bits 4–7) and `o` (`YES` while the
//!   motor moves) [`SimConfig::reply_delay`] after the command, as `` `<c><value>␍`<c>#␍ ``;
//!   bytes leave at the line's baud rate.
//! * `R` stops the motor and makes the drive deaf for [`SimConfig::boot_time`]; `Z<n>` sets
//!   the counter; `O<bits>` sets the outputs C++'s way (bit 4+k: set output k+1 to bit k);
//!   `P<name>,…` starts a program, whose lines are stored, and a bare `P` ends it, answered
//!   `` `P<bytes>␍`P#␍ ``; `A` stops the motor; `i…` is kept; anything else is ignored.
//! * `M<target>,<run speed>,…` moves the motor to `target` (1/64 steps) at the run speed (no
//!   ramps): its position, and so every `l` answer, changes as it goes.
//! * With [`SimConfig::high_limit`], a rail at that physical position stops the motor, and
//!   the input wired to it is closed while the motor is at the rail. [`IdeaSim::set_inputs`]
//!   presses the other inputs.
//! * With [`SimConfig::keep_log`], every `l` and `:` answer is logged with the time its first
//!   byte left ([`IdeaSim::positions`], [`IdeaSim::inputs_told`]), and every command heard
//!   ([`IdeaSim::heard`]).
//! * [`IdeaSim::inject`] puts bytes on the line.

use std::collections::VecDeque;
use std::fmt::Write as _;
use std::time::{Duration, Instant};

use super::answer::leading_int;
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `idea`.
pub static SIMULATOR: Simulator = Simulator {
    name: "idea",
    about: "Haydon Kerk IDEA stepper drive: answers its commands, moves the motor at the run \
            speed, a high limit switch on input 1 at 150 steps",
    baud: 57600,
    line: "vrpn_IDEA Idea0 {PATH} 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 0 0 0 0 \
           50 0.5 -60.0",
    make: |_| Box::new(IdeaSim::new(SimConfig::new())),
};

/// The line speed.
const BAUD: u32 = super::config::BAUD;

fn byte_offset(i: usize) -> Duration {
    Duration::from_micros((i as f64 * 10e6 / f64::from(BAUD)).round() as u64)
}

/// A limit switch at a rail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rail {
    /// The input (1–4) it closes.
    pub input: u8,
    /// Its physical position, 1/64 steps from where the motor starts.
    pub at: i64,
}

/// How the simulated drive behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// Time the drive is deaf after `R`.
    pub boot_time: Duration,
    /// The fault code `f` answers.
    pub fault: i64,
    /// The rail and its switch at the high end, if any.
    pub high_limit: Option<Rail>,
    /// Log the answers and commands.
    pub keep_log: bool,
}

impl SimConfig {
    /// Answers after 2 ms, 30 ms deaf after `R`, no fault, the high rail 150 steps up on
    /// input 1, no log.
    pub fn new() -> SimConfig {
        SimConfig {
            reply_delay: Duration::from_millis(2),
            boot_time: Duration::from_millis(30),
            fault: 0,
            high_limit: Some(Rail {
                input: 1,
                at: 150 * 64,
            }),
            keep_log: false,
        }
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

/// A value the drive told, and when the answer's first byte left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Told<T> {
    /// The value (steps for a position, bits for the inputs).
    pub value: T,
    /// When the answer's first byte left.
    pub at: Instant,
}

/// A move under way: physical positions (1/64 steps) and the speed (1/64 steps a second).
#[derive(Clone, Copy, Debug)]
struct Motion {
    from: i64,
    to: i64,
    start: Instant,
    speed: f64,
}

/// The simulated drive. See the module documentation.
pub struct IdeaSim {
    cfg: SimConfig,
    /// Physical position when not moving (1/64 steps); the counter is this plus `offset`.
    phys: i64,
    offset: i64,
    motion: Option<Motion>,
    inputs: u8,
    outputs: u8,
    deaf_until: Option<Instant>,
    program: Option<usize>,
    program_size: usize,
    line: Vec<u8>,
    /// Answers due: when, and the command letter they answer.
    due: VecDeque<(Instant, u8)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    positions: Vec<Told<f64>>,
    inputs_told: Vec<Told<u8>>,
    heard: Vec<String>,
    moves: u32,
}

impl IdeaSim {
    /// A drive behaving as `cfg` says, its motor at 0.
    pub fn new(cfg: SimConfig) -> IdeaSim {
        IdeaSim {
            cfg,
            phys: 0,
            offset: 0,
            motion: None,
            inputs: 0,
            outputs: 0,
            deaf_until: None,
            program: None,
            program_size: 0,
            line: Vec::new(),
            due: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            positions: Vec::new(),
            inputs_told: Vec::new(),
            heard: Vec::new(),
            moves: 0,
        }
    }

    /// Positions told (steps), with [`SimConfig::keep_log`].
    pub fn positions(&self) -> &[Told<f64>] {
        &self.positions
    }

    /// Input bits told (inputs 1–4), with [`SimConfig::keep_log`].
    pub fn inputs_told(&self) -> &[Told<u8>] {
        &self.inputs_told
    }

    /// Commands heard (without their CR), with [`SimConfig::keep_log`].
    pub fn heard(&self) -> &[String] {
        &self.heard
    }

    /// Moves started (`M` commands).
    pub fn moves(&self) -> u32 {
        self.moves
    }

    /// The output bits (output 1 in bit 0).
    pub fn outputs(&self) -> u8 {
        self.outputs
    }

    /// Sets the fault code `f` answers.
    pub fn set_fault(&mut self, code: i64) {
        self.cfg.fault = code;
    }

    /// Presses inputs: bit k closes input k+1 (the limit switch's input follows the rail).
    pub fn set_inputs(&mut self, bits: u8) {
        self.inputs = bits & 0xF;
    }

    /// The physical position at `t` (1/64 steps).
    fn phys_at(&self, t: Instant) -> i64 {
        let Some(m) = self.motion else {
            return self.phys;
        };
        let gone = (t.saturating_duration_since(m.start).as_secs_f64() * m.speed) as i64;
        let p = if m.to >= m.from {
            (m.from + gone).min(m.to)
        } else {
            (m.from - gone).max(m.to)
        };
        match self.cfg.high_limit {
            Some(r) => p.min(r.at.max(m.from)),
            None => p,
        }
    }

    /// The counter at `t` (1/64 steps).
    pub fn counter_at(&self, t: Instant) -> i64 {
        self.phys_at(t) + self.offset
    }

    fn moving_at(&self, t: Instant) -> bool {
        let Some(m) = self.motion else { return false };
        let p = self.phys_at(t);
        let stop = match self.cfg.high_limit {
            Some(r) if m.to > r.at => r.at.max(m.from),
            _ => m.to,
        };
        p != stop
    }

    fn stop_motor(&mut self, t: Instant) {
        self.phys = self.phys_at(t);
        self.motion = None;
    }

    fn input_bits_at(&self, t: Instant) -> u8 {
        let mut bits = self.inputs;
        if let Some(r) = self.cfg.high_limit {
            if self.phys_at(t) >= r.at {
                bits |= 1 << (r.input - 1);
            }
        }
        bits
    }

    /// Puts `bytes` on the line at `now`, after what is queued.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue(bytes, now);
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + byte_offset(i), b));
        }
        self.line_free = Some(start + byte_offset(bytes.len()));
        start
    }

    fn command(&mut self, c: &[u8], now: Instant) {
        if self.cfg.keep_log {
            self.heard.push(String::from_utf8_lossy(c).into_owned());
        }
        if self.deaf_until.is_some_and(|t| now < t) {
            return;
        }
        let Some((&letter, rest)) = c.split_first() else {
            return;
        };
        if let Some(stored) = self.program.as_mut() {
            if letter == b'P' && rest.is_empty() {
                self.program_size = *stored;
                self.program = None;
                self.due.push_back((now + self.cfg.reply_delay, b'P'));
            } else {
                *stored += c.len() + 1;
            }
            return;
        }
        let at = now + self.cfg.reply_delay;
        match letter {
            b'f' | b'l' | b':' | b'o' => self.due.push_back((at, letter)),
            b'R' => {
                self.stop_motor(now);
                self.due.clear();
                self.program = None;
                self.deaf_until = Some(now + self.cfg.boot_time);
            }
            b'Z' => {
                if let Some(n) = leading_int(rest) {
                    self.offset = n - self.phys_at(now);
                }
            }
            b'O' => {
                if let Some(v) = leading_int(rest) {
                    for k in 0..4 {
                        if v & (1 << (4 + k)) != 0 {
                            self.outputs &= !(1 << k);
                            self.outputs |= ((v >> k) & 1) as u8 * (1 << k);
                        }
                    }
                }
            }
            b'P' if !rest.is_empty() => self.program = Some(0),
            b'A' => self.stop_motor(now),
            b'M' => self.start_move(rest, now),
            _ => {}
        }
    }

    fn start_move(&mut self, args: &[u8], now: Instant) {
        let mut fields = args.split(|&b| b == b',').map(leading_int);
        let (Some(Some(target)), Some(Some(speed))) = (fields.next(), fields.next()) else {
            return;
        };
        self.stop_motor(now);
        self.moves += 1;
        let from = self.phys;
        self.motion = Some(Motion {
            from,
            to: target - self.offset,
            start: now,
            speed: speed.max(1) as f64 * 64.0,
        });
    }

    fn answer(&mut self, letter: u8, t: Instant) {
        let mut text = String::new();
        let log = self.cfg.keep_log;
        let _ = match letter {
            b'f' => write!(text, "`f{}", self.cfg.fault),
            b'l' => write!(text, "`l{}", self.counter_at(t)),
            b':' => write!(
                text,
                "`:{}",
                u32::from(self.input_bits_at(t)) | u32::from(self.outputs) << 4
            ),
            b'o' => write!(text, "`o{}", if self.moving_at(t) { "YES" } else { "NO" }),
            _ => write!(text, "`P{}", self.program_size),
        };
        let _ = write!(text, "\r`{}#\r", letter as char);
        let first = self.queue(text.as_bytes(), t);
        if log && letter == b'l' {
            let value = self.counter_at(t) as f64 / 64.0;
            self.positions.push(Told { value, at: first });
        }
        if log && letter == b':' {
            let value = self.input_bits_at(t);
            self.inputs_told.push(Told { value, at: first });
        }
    }
}

impl DeviceModel for IdeaSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            if b == b'\r' {
                let line = std::mem::take(&mut self.line);
                self.command(&line, now.mono);
                self.line = line;
                self.line.clear();
            } else if self.line.len() < 256 {
                self.line.push(b);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while let Some(&(t, letter)) = self.due.front() {
            if t > now.mono {
                break;
            }
            self.due.pop_front();
            self.answer(letter, t);
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
            self.due.front().map(|&(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
