//! A simulated Virtual Presence joystick: the joystick's end of its serial line, for tests
//! and for a simulator on a pseudo-terminal.
//!
//! Every [`SimConfig::period`] (unless [`SimConfig::idle`]) it sends message `k`
//! ([`message(k)`](message)): the eight buttons pressed and released in their own rhythms.
//! Bits of the button word that are no button are sent clear and the fourth byte as `00`
//! (what the real joystick puts there is not known; no driver reads it), so `FF` appears
//! only at a message's start. Bytes leave at the line's rate; with [`SimConfig::keep_log`]
//! each message is logged with the time its first byte left.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::message::{BUTTONS, MASKS, SYNC};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// For `vrpn_device_sim`.
pub static SIMULATOR: Simulator = Simulator {
    name: "vpjoystick",
    about: "Virtual Presence joystick: 8 buttons, a message every 20 ms",
    baud: 9600,
    line: "vrpn_VPJoystick VPJoystick0 {PATH} {BAUD}",
    make: |baud| Box::new(VpJoystickSim::new(SimConfig::new(baud))),
};

/// How the simulated joystick behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between messages.
    pub period: Duration,
    /// Sends nothing while true.
    pub idle: bool,
    /// Log every message sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A joystick at `baud`, a message every 20 ms, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(20),
            idle: false,
            keep_log: false,
        }
    }
}

/// The buttons held in message `k`: button `i` changes every `i + 2` messages.
pub fn pressed(k: u64) -> [bool; BUTTONS] {
    std::array::from_fn(|i| (k / (i as u64 + 2)) % 2 == 1)
}

/// Message `k`'s bytes.
pub fn message(k: u64) -> [u8; 4] {
    let held = pressed(k);
    let mut word = 0u16;
    for (m, &p) in MASKS.iter().zip(&held) {
        if !p {
            word |= m;
        }
    }
    let [hi, lo] = word.to_be_bytes();
    [SYNC, hi, lo, 0]
}

/// A message put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentMessage {
    /// When its first byte left the joystick.
    pub first_byte: Instant,
    /// The buttons it says are held.
    pub pressed: [bool; BUTTONS],
}

/// The button changes (button, pressed, message index in `log`) a client must receive for
/// the messages in `log`, read by a driver that saw them all.
pub fn expected(log: &[SentMessage]) -> Vec<(usize, bool, usize)> {
    let mut out = Vec::new();
    let mut state = [false; BUTTONS];
    for (k, m) in log.iter().enumerate() {
        for (i, (&was, &now)) in state.iter().zip(&m.pressed).enumerate() {
            if was != now {
                out.push((i, now, k));
            }
        }
        state = m.pressed;
    }
    out
}

/// The simulated joystick. See the module documentation.
pub struct VpJoystickSim {
    cfg: SimConfig,
    count: u64,
    next: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentMessage>,
}

impl VpJoystickSim {
    /// A joystick behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> VpJoystickSim {
        VpJoystickSim {
            cfg,
            count: 0,
            next: None,
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
        }
    }

    /// The messages sent so far (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentMessage] {
        &self.sent
    }

    /// Stops or resumes sending.
    pub fn set_idle(&mut self, idle: bool) {
        self.cfg.idle = idle;
    }

    fn send_message(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        let byte_time =
            Duration::from_micros((10e6 / f64::from(self.cfg.baud.max(1))).round() as u64);
        let mut t = self.line_free.map_or(at, |f| f.max(at));
        let first = t;
        for b in message(k) {
            self.out.push_back((t, b));
            t += byte_time;
        }
        self.line_free = Some(t);
        if self.cfg.keep_log {
            self.sent.push(SentMessage {
                first_byte: first,
                pressed: pressed(k),
            });
        }
    }
}

impl DeviceModel for VpJoystickSim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let next = *self.next.get_or_insert(now.mono);
        if next <= now.mono {
            if !self.cfg.idle {
                self.send_message(next);
            }
            self.next = Some(next + self.cfg.period);
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
        [self.out.front().map(|&(t, _)| t), self.next]
            .into_iter()
            .flatten()
            .min()
    }
}
