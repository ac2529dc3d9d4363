//! A simulated Biosciences Tools temperature controller: the device end of its serial line,
//! for tests and for a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * Commands end with a carriage return. `Tn` (n = 1..6) is answered after
//!   [`SimConfig::reply_delay`] with a reading, `NN.NC\r` (`E` for the external channels 3 and
//!   6); `S1 0370` and `S2 …` set the reference temperatures, `ON` and `OFF` the control;
//!   settings are not answered ([`BioSim::settings`] shows them).
//! * The `k`-th reading (counted over the controller's life) of channel `n` is
//!   [`reading(k, n)`](reading) tenths of a degree; with [`SimConfig::keep_log`] each answer
//!   that changes what the host knows is logged with every channel's value as the host must
//!   see it and the time its first byte left ([`BioSim::sent`]).
//! * Bytes leave at 115200 baud. Faults: [`BioSim::inject`], [`BioSim::mute`].

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::READINGS;
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `biosciences`.
pub static SIMULATOR: Simulator = Simulator {
    name: "biosciences",
    about: "BiosciencesTools temperature controller: answers set-point commands and polls with known readings",
    baud: 115200,
    line: "vrpn_BiosciencesTools Bio0 {PATH} 37.0 37.0 0",
    make: |_| Box::new(BioSim::new(SimConfig::new())),
};

/// How the simulated controller behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time from a request to the first byte of its answer.
    pub reply_delay: Duration,
    /// Log every answer that changes a channel.
    pub keep_log: bool,
}

impl SimConfig {
    /// Answers after 3 ms, no log.
    pub fn new() -> SimConfig {
        SimConfig {
            reply_delay: Duration::from_millis(3),
            keep_log: false,
        }
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

fn byte_offset(i: usize) -> Duration {
    Duration::from_micros((i as f64 * 10e6 / f64::from(super::config::BAUD)).round() as u64)
}

/// Reading `k` of channel `n` (0..6), in tenths of a degree: between 20.0 and 44.9.
pub fn reading(k: u64, n: usize) -> i32 {
    200 + ((k * 7 + n as u64 * 13) % 250) as i32
}

/// An answer put on the line.
#[derive(Clone, Debug, PartialEq)]
pub struct SentReading {
    /// When its first byte left the controller.
    pub first_byte: Instant,
    /// The six channels a client must receive.
    pub channels: Vec<f64>,
}

/// The controller's settings as the host last set them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Reference temperatures, °C (`None` before they were set).
    pub reference: [Option<f64>; 2],
    /// Temperature control on.
    pub control: bool,
}

/// The simulated controller. See the module documentation.
pub struct BioSim {
    cfg: SimConfig,
    settings: Settings,
    command: Vec<u8>,
    count: u64,
    told: [f64; READINGS],
    pending: VecDeque<(Instant, usize)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentReading>,
    heard: Vec<u8>,
    /// Sends nothing while true.
    pub mute: bool,
}

impl BioSim {
    /// A controller behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> BioSim {
        BioSim {
            cfg,
            settings: Settings {
                reference: [None; 2],
                control: false,
            },
            command: Vec::new(),
            count: 0,
            told: [0.0; READINGS],
            pending: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            heard: Vec::new(),
            mute: false,
        }
    }

    /// Answers logged (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentReading] {
        &self.sent
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// The settings in force.
    pub fn settings(&self) -> Settings {
        self.settings
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

    fn command(&mut self, now: Instant) {
        let c = std::mem::take(&mut self.command);
        match c.as_slice() {
            [b'T', n @ b'1'..=b'6'] => {
                self.pending
                    .push_back((now + self.cfg.reply_delay, usize::from(n - b'1')));
            }
            b"ON" => self.settings.control = true,
            b"OFF" => self.settings.control = false,
            [b'S', ch @ (b'1' | b'2'), b' ', rest @ ..] => {
                let text = String::from_utf8_lossy(rest);
                if let Ok(v) = text.trim().parse::<i32>() {
                    // Three digits of whole degrees, one of tenths.
                    self.settings.reference[usize::from(ch - b'1')] = Some(f64::from(v) / 10.0);
                }
            }
            _ => {}
        }
    }

    fn answer(&mut self, at: Instant, n: usize) {
        let tenths = reading(self.count, n);
        self.count += 1;
        let unit = if n == 2 || n == 5 { 'E' } else { 'C' };
        let text = format!("{}.{}{unit}\r", tenths / 10, tenths % 10);
        let first = self.queue(text.as_bytes(), at);
        if self.mute {
            return;
        }
        let v = f64::from(tenths) / 10.0;
        if self.told[n] != v {
            self.told[n] = v;
            if self.cfg.keep_log {
                self.sent.push(SentReading {
                    first_byte: first,
                    channels: self.told.to_vec(),
                });
            }
        }
    }
}

impl DeviceModel for BioSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        for &b in bytes {
            if b == b'\r' {
                self.command(now.mono);
            } else {
                self.command.push(b);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while let Some(&(t, n)) = self.pending.front() {
            if t > now.mono {
                break;
            }
            self.pending.pop_front();
            self.answer(t, n);
        }
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            if !self.mute {
                out.push(b);
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        [
            self.out.front().map(|&(t, _)| t),
            self.pending.front().map(|&(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
