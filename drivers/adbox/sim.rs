//! A simulated AD-Box: the device's end of its serial line, for tests and for a simulator on
//! a pseudo-terminal.
//!
//! Each `U` is answered [`SimConfig::reply_delay`] later with answer `k` ([`answer`]), of the
//! length [`SimConfig::len`] (14, 18 or 19 bytes), a byte per character time at the line's
//! speed, or all at once with [`SimConfig::burst`]. With [`SimConfig::keep_log`] it logs what a
//! client must receive ([`AdBoxSim::sent`]): the button changes and the analog channels of
//! each answer, with the time its first byte left.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::frame::{Layout, MAX_ANSWER, REQUEST};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator for `vrpn_device_sim`.
pub static SIMULATOR: Simulator = Simulator {
    name: "adbox",
    about: "Fraunhofer IMK AD-Box: 24 buttons and 8 analog channels of known values per `U`",
    baud: 19200,
    line: "vrpn_ADBox ADBox0 {PATH} {BAUD}",
    make: |baud| Box::new(AdBoxSim::new(SimConfig::new(baud))),
};

/// How the simulated box behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Answer length: 14, 18 or 19.
    pub len: usize,
    /// Time from a `U` to its answer's first byte.
    pub reply_delay: Duration,
    /// Log what a client must receive.
    pub keep_log: bool,
    /// Write each answer whole, when its first byte is due. On a pseudo-terminal the
    /// simulator's thread can be descheduled for longer than the driver's 200 ms wait for a
    /// byte (a loaded machine): paced bytes would then cut an answer in two, which a real
    /// box never does, and the driver rightly drops it.
    pub burst: bool,
}

impl SimConfig {
    /// A 19-byte box at `baud`, answering after 3 ms, bytes paced, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            len: 19,
            reply_delay: Duration::from_millis(3),
            keep_log: false,
            burst: false,
        }
    }
}

/// Answer `k` of a box of `layout`: button `(k / 8) % buttons` pressed for four answers in
/// eight (its bit cleared; every digital byte stays above 3), analog channel `c` at
/// `(7k + 131c) % 1024` (never one step from the previous value, so C++'s flicker filter
/// leaves it alone).
pub fn answer(layout: Layout, k: u64, out: &mut [u8; MAX_ANSWER]) {
    out[..layout.digital].fill(0xFF);
    if k % 8 < 4 {
        let b = ((k / 8) % layout.buttons() as u64) as usize;
        out[b / 8] &= !(1 << (b % 8));
    }
    for c in 0..layout.channels() {
        let v = (7 * k + 131 * c as u64) % 1024;
        out[layout.digital + 2 * c] = (v >> 8) as u8;
        out[layout.digital + 2 * c + 1] = v as u8;
    }
}

/// What a client must receive.
#[derive(Clone, Debug, PartialEq)]
pub enum Sent {
    /// A button change.
    Button(usize, bool, Instant),
    /// An Analog report: every channel.
    Analog(Vec<f64>, Instant),
}

/// The simulated box. See the module documentation.
pub struct AdBoxSim {
    cfg: SimConfig,
    layout: Layout,
    count: u64,
    due: VecDeque<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    buttons: Vec<bool>,
    requests: u64,
    sent: Vec<Sent>,
}

impl AdBoxSim {
    /// A box behaving as `cfg` says (a length other than 14 or 18 is 19).
    pub fn new(cfg: SimConfig) -> AdBoxSim {
        let layout = Layout::of_len(cfg.len).unwrap_or(Layout {
            len: 19,
            digital: 3,
        });
        AdBoxSim {
            buttons: vec![false; layout.buttons()],
            cfg,
            layout,
            count: 0,
            due: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            requests: 0,
            sent: Vec::new(),
        }
    }

    /// What a client must have received.
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Requests heard.
    pub fn requests(&self) -> u64 {
        self.requests
    }

    /// Answers sent.
    pub fn answers(&self) -> u64 {
        self.count
    }

    fn byte_time(&self) -> Duration {
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    fn send_answer(&mut self, at: Instant) {
        let mut a = [0u8; MAX_ANSWER];
        answer(self.layout, self.count, &mut a);
        self.count += 1;
        let start = self.line_free.map_or(at, |f| f.max(at));
        let mut t = start;
        for &b in &a[..self.layout.len] {
            self.out.push_back((t, b));
            if !self.cfg.burst {
                t += self.byte_time();
            }
        }
        self.line_free = Some(t);
        if !self.cfg.keep_log {
            return;
        }
        for i in 0..self.layout.buttons() {
            let pressed = self.layout.pressed(&a, i);
            if pressed != self.buttons[i] {
                self.buttons[i] = pressed;
                self.sent.push(Sent::Button(i, pressed, start));
            }
        }
        let channels = (0..self.layout.channels())
            .map(|c| f64::from(self.layout.raw(&a, c)) / 1023.0)
            .collect();
        self.sent.push(Sent::Analog(channels, start));
    }
}

impl DeviceModel for AdBoxSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            if b == REQUEST {
                self.requests += 1;
                self.due.push_back(now.mono + self.cfg.reply_delay);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while self.due.front().is_some_and(|&t| t <= now.mono) {
            let t = self.due.pop_front().unwrap_or(now.mono);
            // Whole answers leave now: a late thread logs when they really left.
            self.send_answer(if self.cfg.burst { now.mono } else { t });
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
        [self.out.front().map(|&(t, _)| t), self.due.front().copied()]
            .into_iter()
            .flatten()
            .min()
    }
}
