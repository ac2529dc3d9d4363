//! Simulated SGI dial and button boxes on one serial line, for tests and for a simulator on a
//! pseudo-terminal.
//!
//! What they do:
//!
//! * Each reset byte `0x20` is answered `0x20` and restarts the dials' counters; `50 xx FF` enables the dials (and, as C++ notes, disables the buttons),
//!   `71 …` enables and `73 …` activates the buttons, `75 b0 b1 b2 b3` sets the lights
//!   ([`SgiSim::lights`]).
//! * Once enabled, an event every [`SimConfig::period`]: event `k` (counted over the
//!   simulator's life) presses or releases a button (every third event) or turns a dial by a
//!   step that drifts upwards, so the dials' channels saturate (see [`event`]).
//! * [`expected`] turns the log into the reports a client must receive, computed here
//!   independently of the driver (toggles, the saturating channels, revolutions).
//! * With [`SimConfig::keep_log`] every event is logged with the time its first byte left;
//!   [`SgiSim::mute`] makes the boxes silent (they hear; their events and answers are lost and
//!   not logged); [`SgiSim::inject`] puts bytes on the line.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `sgibox`.
pub static SIMULATOR: Simulator = Simulator {
    name: "sgibox",
    about: "SGI dial and button boxes: answer the reset, then send known button and dial events",
    baud: 9600,
    line: "vrpn_raw_SGIBox Sgibox0 {PATH} 0 1 2 3",
    make: |_| Box::new(SgiSim::new(SimConfig::new())),
};

/// How the simulated boxes behave.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time between events once enabled.
    pub period: Duration,
    /// Log every event sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// An event every 25 ms.
    pub fn new() -> SimConfig {
        SimConfig {
            period: Duration::from_millis(25),
            keep_log: false,
        }
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

/// What an event does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// Button `b` goes down (true) or up: the button box's byte.
    Button(usize, bool),
    /// Dial `d` moves to a position: the dial box's three bytes.
    Dial(usize, i16),
    /// The boxes were reset (their counters restart at 0); nothing is sent.
    Reset,
}

/// The button event `k` acts on, or the dial and step: every third event a button
/// (`(k / 3) * 7 % 32`), else dial `k * 5 % 8` by `k * 37 % 81 − 30` counts.
pub fn event(k: u64) -> Result<usize, (usize, i16)> {
    if k % 3 == 2 {
        Ok(((k / 3) * 7 % 32) as usize)
    } else {
        Err(((k * 5 % 8) as usize, (k * 37 % 81) as i16 - 30))
    }
}

/// An event put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sent {
    /// When its first byte left the boxes.
    pub first_byte: Instant,
    /// The event.
    pub event: Event,
}

/// A report a client must receive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Report {
    /// Button `b` changed.
    Button(usize, bool),
    /// All eight dial channels.
    Analog([f64; 8]),
    /// Dial `d` turned this many revolutions.
    Dial(usize, f64),
}

/// The reports a client must receive for `log` (with each the index of its event), with
/// `toggles` toggling buttons: a momentary button reports each change; a toggle reports
/// its new state at each press. A dial's channel is its position against a middle that
/// follows it past ±200 counts, divided by 400; a turn is the position's change / 200.
/// Also returns the toggles that end on (the lights).
pub fn expected(log: &[Sent], toggles: &[u32]) -> (Vec<(Report, usize)>, u32) {
    let mut out = Vec::new();
    let mut pressed = [false; 32];
    let mut on = 0u32;
    let (mut last, mut mid) = ([0i32; 8], [0i32; 8]);
    let mut chans = [0.0; 8];
    for (i, s) in log.iter().enumerate() {
        match s.event {
            Event::Reset => {
                last = [0; 8];
                mid = [0; 8];
            }
            Event::Button(b, p) => {
                let was = pressed[b];
                pressed[b] = p;
                if toggles.contains(&(b as u32)) {
                    if p && !was {
                        on ^= 1 << b;
                        out.push((Report::Button(b, on & 1 << b != 0), i));
                    }
                } else if p != was {
                    out.push((Report::Button(b, p), i));
                }
            }
            Event::Dial(d, pos) => {
                let p = i32::from(pos);
                if p - mid[d] > 200 {
                    mid[d] = p - 200;
                } else if p - mid[d] < -200 {
                    mid[d] = p + 200;
                }
                let c = f64::from(p - mid[d]) / 400.0;
                if c != chans[d] {
                    chans[d] = c;
                    out.push((Report::Analog(chans), i));
                }
                let turned = f64::from(p - last[d]) / 200.0;
                last[d] = p;
                if turned != 0.0 {
                    out.push((Report::Dial(d, turned), i));
                }
            }
        }
    }
    (out, on)
}

/// The simulated boxes. See the module documentation.
pub struct SgiSim {
    cfg: SimConfig,
    dials_on: bool,
    buttons_enabled: bool,
    buttons_active: bool,
    lights: u32,
    positions: [i16; 8],
    pressed: [bool; 32],
    command: Vec<u8>,
    next_event: Option<Instant>,
    count: u64,
    out: VecDeque<(Instant, u8)>,
    /// Silent while true: events and answers are lost and not logged.
    pub mute: bool,
    sent: Vec<Sent>,
    resets: u64,
}

impl SgiSim {
    /// Boxes behaving as `cfg` says, waiting to be reset and enabled.
    pub fn new(cfg: SimConfig) -> SgiSim {
        SgiSim {
            cfg,
            dials_on: false,
            buttons_enabled: false,
            buttons_active: false,
            lights: 0,
            positions: [0; 8],
            pressed: [false; 32],
            command: Vec::new(),
            next_event: None,
            count: 0,
            out: VecDeque::new(),
            mute: false,
            sent: Vec::new(),
            resets: 0,
        }
    }

    /// Events sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// The lights (bit *i* is light *i*).
    pub fn lights(&self) -> u32 {
        self.lights
    }

    /// Reset bytes received.
    pub fn resets(&self) -> u64 {
        self.resets
    }

    /// Puts `bytes` on the line at `now`.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.out.extend(bytes.iter().map(|&b| (now, b)));
    }

    fn log(&mut self, at: Instant, event: Event) {
        if self.cfg.keep_log {
            self.sent.push(Sent {
                first_byte: at,
                event,
            });
        }
    }

    fn command_byte(&mut self, b: u8, now: Instant) {
        if self.command.is_empty() && b == 0x20 {
            self.resets += 1;
            // The counters restart; the buttons stay as the hands left them.
            self.positions = [0; 8];
            self.dials_on = false;
            self.buttons_enabled = false;
            self.buttons_active = false;
            self.log(now, Event::Reset);
            if !self.mute {
                self.out.push_back((now + Duration::from_millis(2), 0x20));
            }
            return;
        }
        self.command.push(b);
        let want = match self.command[0] {
            0x50 => 3,
            0x71 | 0x73 | 0x75 => 5,
            _ => {
                self.command.clear();
                return;
            }
        };
        if self.command.len() < want {
            return;
        }
        let c = std::mem::take(&mut self.command);
        match c[0] {
            0x50 => {
                self.dials_on = true;
                self.buttons_enabled = false;
            }
            0x71 => self.buttons_enabled = true,
            0x73 => self.buttons_active = true,
            _ => self.lights = u32::from_le_bytes([c[1], c[2], c[3], c[4]]),
        }
        if self.dials_on && self.next_event.is_none() {
            self.next_event = Some(now + self.cfg.period);
        }
    }

    fn make_event(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        match event(k) {
            Ok(b) => {
                if !(self.buttons_enabled && self.buttons_active) {
                    return;
                }
                let p = !self.pressed[b];
                self.pressed[b] = p;
                if !self.mute {
                    self.out.push_back((at, super::record::button_byte(b, p)));
                    self.log(at, Event::Button(b, p));
                }
            }
            Err((d, step)) => {
                // A reset box sends no turns until its dials are enabled.
                if !self.dials_on {
                    return;
                }
                let pos = self.positions[d].wrapping_add(step);
                self.positions[d] = pos;
                if !self.mute {
                    let [h, l] = pos.to_be_bytes();
                    // Three bytes at 9600 baud: about a millisecond apart.
                    for (i, b) in [0x30 + d as u8, h, l].into_iter().enumerate() {
                        self.out
                            .push_back((at + Duration::from_micros(1042 * i as u64), b));
                    }
                    self.log(at, Event::Dial(d, pos));
                }
            }
        }
    }
}

impl DeviceModel for SgiSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            self.command_byte(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while let Some(t) = self.next_event.filter(|&t| t <= now.mono) {
            self.make_event(t);
            // A simulator that was not stepped for a while (unplugged) does not catch up.
            self.next_event = Some((t + self.cfg.period).max(now.mono));
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
        [self.out.front().map(|&(t, _)| t), self.next_event]
            .into_iter()
            .flatten()
            .min()
    }
}
