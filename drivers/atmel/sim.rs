//! A simulated Atmel board: the device's end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! It has 64 byte registers. A lone address byte is a read: [`SimConfig::reply_delay`] after
//! it is known to be alone (no value byte within two character times) the board answers with
//! the address byte and the value byte ([`super::command`]). An address byte followed by a
//! value byte is a write: the register takes the value and the two bytes are echoed. The
//! registers in [`SimConfig::inputs`] are inputs: register `r` answers its `k`-th read with
//! [`input_value`]`(r, k)`. Every [`SimConfig::keepalive`] of quiet the board sends one byte
//! `0x00` of its own accord (C++ waits for such bytes; what the real board sends is not
//! known). With [`SimConfig::keep_log`] it logs every read it answered, with the time the
//! answer's first byte left, and every write.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::command::{register_of, MAX_REGISTER};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator for `vrpn_device_sim`.
pub static SIMULATOR: Simulator = Simulator {
    name: "atmel",
    about: "Atmel board: registers 0 and 1 are inputs of known values, 2 and 3 are memory",
    baud: 9600,
    line: "vrpn_Atmel Atmel0 {PATH} {BAUD} 4\nvrpn_Atmel 0 RO\nvrpn_Atmel 1 RO\n\
           vrpn_Atmel 2 RW\nvrpn_Atmel 3 WO\nvrpn_Atmel -1 END",
    make: |baud| Box::new(AtmelSim::new(SimConfig::new(baud))),
};

/// Register `r`'s value at its `k`-th read, for an input register.
pub fn input_value(r: usize, k: u64) -> u8 {
    ((r as u64 * 37 + 11 * k) % 256) as u8
}

/// How the simulated board behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Registers that are inputs (bit `r` for register `r`).
    pub inputs: u64,
    /// Time from a request to its answer's first byte.
    pub reply_delay: Duration,
    /// Quiet after which the board sends a byte of its own accord (`None`: never).
    pub keepalive: Option<Duration>,
    /// Log what a client must receive.
    pub keep_log: bool,
    /// Write each answer whole (on a pseudo-terminal, where the simulator's thread can be
    /// descheduled between two bytes for longer than the driver waits for an answer).
    pub burst: bool,
}

impl SimConfig {
    /// A board at `baud` whose registers 0 and 1 are inputs, answering after 1 ms, sending a
    /// byte after 250 ms of quiet, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            inputs: 0b11,
            reply_delay: Duration::from_millis(1),
            keepalive: Some(Duration::from_millis(250)),
            keep_log: false,
            burst: false,
        }
    }
}

/// A read the board answered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Answered {
    /// The register.
    pub register: usize,
    /// Its value.
    pub value: u8,
    /// When the answer's first byte left.
    pub at: Instant,
}

/// An answer to send: when, its bytes, and the read it answers (register and value, to log).
type Due = (Instant, [u8; 2], Option<(usize, u8)>);

/// The simulated board. See the module documentation.
pub struct AtmelSim {
    cfg: SimConfig,
    registers: [u8; MAX_REGISTER + 1],
    reads: [u64; MAX_REGISTER + 1],
    /// An address byte that may be a read or the start of a write, and when it came.
    pending: Option<(u8, Instant)>,
    due: VecDeque<Due>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    last_out: Option<Instant>,
    answered: Vec<Answered>,
    writes: Vec<(usize, u8)>,
}

impl AtmelSim {
    /// A board behaving as `cfg` says; register `r` holds `r` at power-on.
    pub fn new(cfg: SimConfig) -> AtmelSim {
        let mut registers = [0u8; MAX_REGISTER + 1];
        for (r, v) in registers.iter_mut().enumerate() {
            *v = r as u8;
        }
        AtmelSim {
            cfg,
            registers,
            reads: [0; MAX_REGISTER + 1],
            pending: None,
            due: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            last_out: None,
            answered: Vec::new(),
            writes: Vec::new(),
        }
    }

    /// Every read answered (with [`SimConfig::keep_log`]).
    pub fn answered(&self) -> &[Answered] {
        &self.answered
    }

    /// Every write, in order: register and value.
    pub fn writes(&self) -> &[(usize, u8)] {
        &self.writes
    }

    /// Changes the time from a request to its answer (a board, or a simulator's thread,
    /// held up).
    pub fn set_reply_delay(&mut self, delay: Duration) {
        self.cfg.reply_delay = delay;
    }

    /// Register `r`'s value.
    pub fn register(&self, r: usize) -> u8 {
        self.registers[r]
    }

    fn byte_time(&self) -> Duration {
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    /// A lone address byte: answer the read.
    fn read(&mut self, address: u8, now: Instant) {
        let Some(r) = register_of(address).filter(|&r| r <= MAX_REGISTER) else {
            return;
        };
        if self.cfg.inputs & (1 << r) != 0 {
            self.registers[r] = input_value(r, self.reads[r]);
        }
        self.reads[r] += 1;
        let v = self.registers[r];
        let answer = [(address & !1) | v >> 7, v & 0x7F];
        self.due
            .push_back((now + self.cfg.reply_delay, answer, Some((r, v))));
    }

    fn send(&mut self, at: Instant, bytes: [u8; 2], read: Option<(usize, u8)>) {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let mut t = start;
        for b in bytes {
            self.out.push_back((t, b));
            if !self.cfg.burst {
                t += self.byte_time();
            }
        }
        self.line_free = Some(t);
        if let (Some((register, value)), true) = (read, self.cfg.keep_log) {
            self.answered.push(Answered {
                register,
                value,
                at: start,
            });
        }
    }
}

impl DeviceModel for AtmelSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            if b & 0x80 != 0 {
                if let Some((a, _)) = self.pending.take() {
                    self.read(a, now.mono);
                }
                self.pending = Some((b, now.mono));
            } else if let Some((a, _)) = self.pending.take() {
                if let Some(r) = register_of(a) {
                    let v = b | (a & 1) << 7;
                    self.registers[r] = v;
                    self.writes.push((r, v));
                    self.due
                        .push_back((now.mono + self.cfg.reply_delay, [a, b], None));
                }
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if let Some((a, at)) = self.pending {
            if now.mono >= at + 2 * self.byte_time() {
                self.pending = None;
                self.read(a, at + 2 * self.byte_time());
            }
        }
        while self.due.front().is_some_and(|&(t, _, _)| t <= now.mono) {
            if let Some((t, bytes, read)) = self.due.pop_front() {
                // Whole answers leave now: a late thread logs when they really left.
                self.send(if self.cfg.burst { now.mono } else { t }, bytes, read);
            }
        }
        let before = out.len();
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
        let quiet = self.pending.is_none() && self.due.is_empty() && self.out.is_empty();
        if let (Some(k), true) = (self.cfg.keepalive, quiet && out.len() == before) {
            let last = *self.last_out.get_or_insert(now.mono);
            if now.mono >= last + k {
                out.push(0x00);
            }
        }
        if out.len() > before {
            self.last_out = Some(now.mono);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let read = self.pending.map(|(_, at)| at + 2 * self.byte_time());
        let keepalive = self.cfg.keepalive.zip(self.last_out).map(|(k, t)| t + k);
        [
            read,
            self.due.front().map(|&(t, _, _)| t),
            self.out.front().map(|&(t, _)| t),
            keepalive,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
