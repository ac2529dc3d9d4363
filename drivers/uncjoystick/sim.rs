//! A simulated UNC joystick box: the device end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * `r` is answered, after [`SimConfig::reply_delay`], with one record per channel 0-7 (16
//!   bytes) holding the current values; `j` starts records on change: one every
//!   [`SimConfig::period`], event `k` (counted over the simulator's life) moving channel
//!   `k % 8` to [`value(k)`](value). Everything received is kept ([`JoystickSim::heard`]).
//! * [`expected`] turns the log into the reports a client must receive, computed here
//!   independently of the driver (rest positions from the last answer, scaling, buttons).
//! * It is powered by the line: a simulator not stepped for 300 ms (unplugged) starts again
//!   quiet, waiting for `r` and `j`.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] every record is logged
//!   with the time its first byte left. [`JoystickSim::mute`] makes it silent (it hears,
//!   answers nothing; records made meanwhile are lost and not logged).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{Pair, SCALE};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `uncjoystick`.
pub static SIMULATOR: Simulator = Simulator {
    name: "uncjoystick",
    about: "UNC joystick box: answers the reset, then sends known stick, slider and button changes",
    baud: 19200,
    line: "vrpn_Joystick Joybox0 {PATH} {BAUD} 10.0",
    make: |baud| Box::new(JoystickSim::new(SimConfig::new(baud))),
};

/// How the simulated box behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between records in change mode.
    pub period: Duration,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// Log every record sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A box at `baud`: a change every 20 ms, answers after 2 ms.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(20),
            reply_delay: Duration::from_millis(2),
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The value event `k` gives its channel (`k % 8`): for the buttons' channel the low two
/// bits cycle (a clear bit is a pressed button), for the others a 10-bit count that changes
/// every time.
pub fn value(k: u64) -> u16 {
    if k % 8 == 7 {
        ((k / 8) % 4) as u16
    } else {
        100 + ((k * 37) % 800) as u16
    }
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sent {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// Channel and value.
    pub channel: u8,
    /// The 10-bit value.
    pub value: u16,
    /// Part of an answer to `r` (the index of the record in it).
    pub answer: Option<u8>,
}

/// A report a client must receive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Report {
    /// Button `i` changed.
    Button(usize, bool),
    /// All seven channels.
    Analog([f64; 7]),
}

/// Everything a client connected from the start must receive for `log`: per answer to `r`
/// (after its eighth record) and per record in change mode, the buttons that changed, then
/// every channel. Each with the index in `log` of the record whose first byte stamps it (an
/// answer's first record).
pub fn expected(log: &[Sent]) -> Vec<(Report, usize)> {
    let mut rest = [512u16; 7];
    let mut raw = [512u16; 7];
    let mut buttons = [false; 2];
    let mut out = Vec::new();
    let mut answer_start = 0;
    for (i, s) in log.iter().enumerate() {
        if s.answer == Some(0) {
            answer_start = i;
        }
        // An answer's reports are stamped with its first record.
        let stamp = if s.answer.is_some() { answer_start } else { i };
        let c = usize::from(s.channel);
        if c == 7 {
            let now = [s.value & 1 == 0, s.value & 2 == 0];
            for b in 0..2 {
                if now[b] != buttons[b] {
                    buttons[b] = now[b];
                    out.push((Report::Button(b, now[b]), stamp));
                }
            }
        } else {
            raw[c] = s.value;
            if s.answer.is_some() && c != 0 {
                rest[c] = s.value;
            }
        }
        let complete = match s.answer {
            Some(n) => n == 7,
            None => true,
        };
        if complete {
            let mut ch = [0.0; 7];
            for (c, v) in ch.iter_mut().enumerate() {
                let x = ((f64::from(rest[c]) - f64::from(raw[c])) / SCALE[c]).clamp(-0.5, 0.5);
                *v = if c == 0 { -x } else { x };
            }
            out.push((Report::Analog(ch), stamp));
        }
    }
    out
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Quiet,
    Changes,
}

/// The simulated box. See the module documentation.
pub struct JoystickSim {
    cfg: SimConfig,
    mode: Mode,
    values: [u16; 8],
    next_event: Option<Instant>,
    count: u64,
    last_step: Option<Instant>,
    answer_at: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    /// Silent while true: answers nothing, its records are lost and not logged.
    pub mute: bool,
    sent: Vec<Sent>,
    heard: Vec<u8>,
}

impl JoystickSim {
    /// A box behaving as `cfg` says, sticks near their centres, buttons up.
    pub fn new(cfg: SimConfig) -> JoystickSim {
        JoystickSim {
            cfg,
            mode: Mode::Quiet,
            values: [300, 503, 506, 509, 512, 515, 518, 0b11],
            next_event: None,
            count: 0,
            last_step: None,
            answer_at: None,
            out: VecDeque::new(),
            line_free: None,
            mute: false,
            sent: Vec::new(),
            heard: Vec::new(),
        }
    }

    /// Records sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Everything the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// Puts `bytes` on the line at `now`, after what is already queued.
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

    fn send(&mut self, channel: u8, answer: Option<u8>, at: Instant) {
        let value = self.values[usize::from(channel)];
        let first = self.queue(&Pair { channel, value }.encode(), at);
        if self.cfg.keep_log {
            self.sent.push(Sent {
                first_byte: first,
                channel,
                value,
                answer,
            });
        }
    }
}

impl DeviceModel for JoystickSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        for &b in bytes {
            match b {
                b'r' => self.answer_at = Some(now.mono + self.cfg.reply_delay),
                b'j' if self.mode == Mode::Quiet => {
                    self.mode = Mode::Changes;
                    self.next_event = Some(now.mono + self.cfg.period);
                }
                _ => {}
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self
            .last_step
            .is_some_and(|t| now.mono > t + Duration::from_millis(300))
        {
            // Unplugged, so powered off: it comes back quiet.
            self.mode = Mode::Quiet;
            self.next_event = None;
            self.answer_at = None;
        }
        self.last_step = Some(now.mono);
        if let Some(t) = self.answer_at.filter(|&t| t <= now.mono) {
            self.answer_at = None;
            if !self.mute {
                for c in 0..8 {
                    self.send(c, Some(c), t);
                }
            }
        }
        while let Some(t) = self.next_event.filter(|&t| t <= now.mono) {
            let k = self.count;
            self.count += 1;
            let channel = (k % 8) as u8;
            self.values[usize::from(channel)] = value(k);
            if !self.mute {
                self.send(channel, None, t);
            }
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
        [
            self.out.front().map(|&(t, _)| t),
            self.next_event,
            self.answer_at,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
