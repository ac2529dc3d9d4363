//! A simulated Global Haptics Orb: the device's end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! It answers the reset byte `81` with `FC` after 1 ms. Every [`SimConfig::period`] (unless
//! [`SimConfig::idle`]) it sends event `k`'s byte ([`event_byte(k)`](event_byte)): the 30
//! buttons pressed and released in turn, between them thumbwheel and trackball ticks. With
//! [`SimConfig::keep_log`] it logs what a client must receive ([`OrbSim::sent`]), from the
//! byte table and C++'s constants, with the time each byte left.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::event::{
    DIALS, PRESS, RELEASE, RESET, RESET_ANSWER, REV_PER_TICK_BALL, REV_PER_TICK_WHEEL,
};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `orb`.
pub static SIMULATOR: Simulator = Simulator {
    name: "orb",
    about: "Global Haptics Orb: answers the reset, then sends known button, rocker and dial events",
    baud: 19200,
    line: "vrpn_GlobalHapticsOrb Orb0 {PATH} {BAUD}",
    make: |baud| Box::new(OrbSim::new(SimConfig::new(baud))),
};

/// How the simulated Orb behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Time between events.
    pub period: Duration,
    /// Sends no events (answers the reset byte all the same).
    pub idle: bool,
    /// Sends its first event only once it has answered a reset byte (so that a test sees
    /// every event from the first on).
    pub after_reset: bool,
    /// Log what a client must receive.
    pub keep_log: bool,
}

impl SimConfig {
    /// An Orb at `baud`, an event every 5 ms from its first reset on, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(5),
            idle: false,
            after_reset: true,
            keep_log: false,
        }
    }
}

/// Event `k`'s byte: in each group of four, a button's press or release (button `k / 8 %
/// 30`), then a wheel tick, a ball x tick and a ball y tick whose directions change slowly
/// (the wheel goes past a whole turn, where its analog channel stops).
pub fn event_byte(k: u64) -> u8 {
    let button = ((k / 8) % 30) as usize;
    let dir = (k / 80) % 2 == 0;
    match k % 4 {
        0 if k % 8 == 0 => PRESS[button],
        0 => RELEASE[button],
        1 => {
            if dir {
                0xE0
            } else {
                0xE1
            }
        }
        2 => {
            if dir {
                0xF2
            } else {
                0xF3
            }
        }
        _ => {
            if (k / 100) % 2 == 0 {
                0xF0
            } else {
                0xF1
            }
        }
    }
}

/// What a client must receive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sent {
    /// A button change.
    Button(usize, bool, Instant),
    /// An Analog report: the three channels.
    Analog([f64; DIALS], Instant),
    /// A dial update: revolutions.
    Dial(usize, f64, Instant),
}

/// The simulated Orb. See the module documentation.
pub struct OrbSim {
    cfg: SimConfig,
    count: u64,
    next: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    pending: Vec<Instant>,
    channels: [f64; DIALS],
    buttons: [bool; 30],
    resets_heard: u32,
    sent: Vec<Sent>,
}

impl OrbSim {
    /// An Orb behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> OrbSim {
        OrbSim {
            cfg,
            count: 0,
            next: None,
            out: VecDeque::new(),
            line_free: None,
            pending: Vec::new(),
            channels: [0.0; DIALS],
            buttons: [false; 30],
            resets_heard: 0,
            sent: Vec::new(),
        }
    }

    /// What a client must have received.
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Reset bytes heard.
    pub fn resets_heard(&self) -> u32 {
        self.resets_heard
    }

    /// Starts or stops the events.
    pub fn set_idle(&mut self, idle: bool) {
        self.cfg.idle = idle;
    }

    fn byte_time(&self) -> Duration {
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    fn queue_at(&mut self, b: u8, at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        self.out.push_back((start, b));
        self.line_free = Some(start + self.byte_time());
        start
    }

    fn send_event(&mut self, at: Instant) {
        let b = event_byte(self.count);
        self.count += 1;
        let t = self.queue_at(b, at);
        if !self.cfg.keep_log {
            return;
        }
        if let Some(i) = PRESS.iter().position(|&p| p == b) {
            if !self.buttons[i] {
                self.buttons[i] = true;
                self.sent.push(Sent::Button(i, true, t));
            }
            return;
        }
        if let Some(i) = RELEASE.iter().position(|&p| p == b) {
            if self.buttons[i] {
                self.buttons[i] = false;
                self.sent.push(Sent::Button(i, false, t));
            }
            return;
        }
        let (i, rev) = match b {
            0xE0 => (0, REV_PER_TICK_WHEEL),
            0xE1 => (0, -REV_PER_TICK_WHEEL),
            0xF2 => (1, REV_PER_TICK_BALL),
            0xF3 => (1, -REV_PER_TICK_BALL),
            0xF0 => (2, REV_PER_TICK_BALL),
            _ => (2, -REV_PER_TICK_BALL),
        };
        let v = (self.channels[i] + rev).clamp(-1.0, 1.0);
        if v != self.channels[i] {
            self.channels[i] = v;
            self.sent.push(Sent::Analog(self.channels, t));
        }
        self.sent.push(Sent::Dial(i, rev, t));
    }
}

impl OrbSim {
    fn flush_out(&mut self, now: Now, out: &mut Vec<u8>) {
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
    }
}

impl DeviceModel for OrbSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            if b == RESET {
                self.resets_heard += 1;
                self.pending.push(now.mono + Duration::from_millis(1));
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let due: Vec<Instant> = self
            .pending
            .iter()
            .copied()
            .filter(|&t| t <= now.mono)
            .collect();
        self.pending.retain(|&t| t > now.mono);
        for t in due {
            self.queue_at(RESET_ANSWER, t);
        }
        if self.cfg.after_reset && self.resets_heard == 0 {
            return self.flush_out(now, out);
        }
        let next = *self.next.get_or_insert(now.mono + Duration::from_millis(2));
        if next <= now.mono {
            if !self.cfg.idle {
                self.send_event(next);
            }
            self.next = Some(next + self.cfg.period);
        }
        self.flush_out(now, out);
    }

    fn next_deadline(&self) -> Option<Instant> {
        [
            self.out.front().map(|&(t, _)| t),
            self.next,
            self.pending.iter().copied().min(),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
