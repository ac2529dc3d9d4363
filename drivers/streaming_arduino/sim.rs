//! A simulated Arduino running VRPN's `vrpn_streaming_arduino` sketch: the device end of its
//! serial line, for tests and for a simulator on a pseudo-terminal.
//!
//! What it does, as the sketch does:
//!
//! * After power-on (or [`ArduinoSim::reboot`]) the boot loader runs for
//!   [`SimConfig::boot_time`], and what the host writes meanwhile is lost.
//! * The sketch then waits for the number of analogs (a decimal number, 1 to 8); from then on
//!   it prints a line every [`SimConfig::period`]: the analog values separated by commas, then
//!   any event markers (later numbers the host wrote), then `\n`.
//! * Line `k` (counted over the device's life) holds [`sample(k)`](sample); with
//!   [`SimConfig::keep_log`] each line is logged with the time its first byte left
//!   ([`ArduinoSim::sent`]).
//! * Faults: [`ArduinoSim::inject`] puts bytes on the line, [`ArduinoSim::mute`] silences it.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `streaming_arduino`.
pub static SIMULATOR: Simulator = Simulator {
    name: "streaming_arduino",
    about: "Streaming Arduino: boots, takes the channel count, then streams known analog lines",
    baud: 115200,
    line: "vrpn_Streaming_Arduino sa0 {PATH} 4 {BAUD}",
    make: |baud| Box::new(ArduinoSim::new(SimConfig::new(baud))),
};

/// How the simulated Arduino behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// How long the boot loader runs after power-on.
    pub boot_time: Duration,
    /// Time between lines.
    pub period: Duration,
    /// Log every line sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// An Arduino at `baud`: boots in 0.3 s, a line every 5 ms, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            boot_time: Duration::from_millis(300),
            period: Duration::from_millis(5),
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// Line `k`'s eight analog readings (0..1023); a line holds the first `N`.
pub fn sample(k: u64) -> [u16; 8] {
    let mut v = [0u16; 8];
    for (i, x) in v.iter_mut().enumerate() {
        *x = ((k * (13 + 4 * i as u64) + 97 * i as u64) % 1024) as u16;
    }
    v
}

/// A line put on the wire.
#[derive(Clone, Debug, PartialEq)]
pub struct SentLine {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// The channels a client must receive for it.
    pub values: Vec<f64>,
}

/// The simulated Arduino. See the module documentation.
pub struct ArduinoSim {
    cfg: SimConfig,
    booted_at: Option<Instant>,
    analogs: usize,
    number: Option<u32>,
    markers: Vec<u32>,
    next_line: Option<Instant>,
    count: u64,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentLine>,
    heard: Vec<u8>,
    /// Sends nothing while true (and logs nothing).
    pub mute: bool,
}

impl ArduinoSim {
    /// An Arduino behaving as `cfg` says, powered on at its first step.
    pub fn new(cfg: SimConfig) -> ArduinoSim {
        ArduinoSim {
            cfg,
            booted_at: None,
            analogs: 0,
            number: None,
            markers: Vec::new(),
            next_line: None,
            count: 0,
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            heard: Vec::new(),
            mute: false,
        }
    }

    /// Lines logged (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentLine] {
        &self.sent
    }

    /// Every byte the host wrote (lost ones included).
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// The analog count the sketch runs with (0 before it was told).
    pub fn analogs(&self) -> usize {
        self.analogs
    }

    /// Restarts the Arduino (as DTR does): the boot loader runs again from `now`.
    pub fn reboot(&mut self, now: Instant) {
        self.booted_at = Some(now + self.cfg.boot_time);
        self.analogs = 0;
        self.number = None;
        self.markers.clear();
        self.next_line = None;
    }

    /// Puts `bytes` on the line at `now`, after what is queued.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue(bytes, now);
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + self.cfg.byte_offset(i), b));
        }
        self.line_free = Some(start + self.cfg.byte_offset(bytes.len()));
        start
    }

    fn end_number(&mut self, at: Instant) {
        let Some(n) = self.number.take() else { return };
        if self.analogs == 0 {
            if (1..=8).contains(&n) {
                self.analogs = n as usize;
                self.next_line = Some(at);
            }
        } else if n > 0 {
            self.markers.push(n);
        }
    }

    fn make_line(&mut self, at: Instant) {
        let s = sample(self.count);
        self.count += 1;
        let mut text: Vec<String> = s[..self.analogs].iter().map(|v| v.to_string()).collect();
        text.extend(self.markers.drain(..).map(|m| m.to_string()));
        let line = format!("{}\n", text.join(","));
        let first = self.queue(line.as_bytes(), at);
        if self.cfg.keep_log && !self.mute {
            self.sent.push(SentLine {
                first_byte: first,
                values: s[..self.analogs].iter().map(|&v| f64::from(v)).collect(),
            });
        }
    }
}

impl DeviceModel for ArduinoSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        if self.booted_at.map_or(true, |t| now.mono < t) {
            return;
        }
        for &b in bytes {
            if b.is_ascii_digit() {
                let d = u32::from(b - b'0');
                self.number = Some(self.number.unwrap_or(0).saturating_mul(10) + d);
            } else {
                self.end_number(now.mono);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.booted_at.is_none() {
            self.reboot(now.mono);
        }
        while let Some(t) = self.next_line.filter(|&t| t <= now.mono) {
            self.make_line(t);
            self.next_line = Some(t + self.cfg.period);
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
        [self.out.front().map(|&(t, _)| t), self.next_line]
            .into_iter()
            .flatten()
            .min()
    }
}
