//! A simulated Wanda: the device end of its serial line, for tests and for a simulator on a
//! pseudo-terminal.
//!
//! What it does:
//!
//! * It sends `M3` when it powers up (its first moment on the line) and again when RTS rises
//!   after a fall, as a serial mouse does.
//! * The ball is pushed in bursts: [`SimConfig::burst`] records [`SimConfig::period`] apart,
//!   then [`SimConfig::pause`] of silence (the ball let go). Record `k` (counted over the
//!   simulator's life) holds [`sample(k)`](sample); a record carries the yellow-button byte
//!   while yellow is down and once after it is released, as a Logitech mouse does its middle
//!   button.
//! * [`expected`] turns the log of what was sent into the reports a client must receive,
//!   computed here independently of the driver (the scaling, the change rules and the
//!   centring after silence).
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each record is logged
//!   with the time its first byte left. [`WandaSim::mute`] makes it silent (records made
//!   meanwhile are neither sent nor logged), [`WandaSim::inject`] puts bytes on the line.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{encode, INIT_MESSAGE, RECORD_LEN, YELLOW_DOWN};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `wanda`.
pub static SIMULATOR: Simulator = Simulator {
    name: "wanda",
    about: "Wanda: sends its init message, then known ball and button records (7 data bits)",
    baud: 1200,
    line: "vrpn_Wanda Wanda0 {PATH} {BAUD} 60.0",
    make: |_| Box::new(WandaSim::new(SimConfig::new())),
};

/// How the simulated Wanda behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between records while the ball is pushed.
    pub period: Duration,
    /// Records per burst.
    pub burst: u64,
    /// Silence between bursts.
    pub pause: Duration,
    /// Log every record sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A Wanda at 1200 baud: bursts of 20 records 50 ms apart, 400 ms pauses, no log.
    pub fn new() -> SimConfig {
        SimConfig {
            baud: 1200,
            period: Duration::from_millis(50),
            burst: 20,
            pause: Duration::from_millis(400),
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

/// The contents of one record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// Raw ball X and Y.
    pub x: i8,
    /// Raw ball Y.
    pub y: i8,
    /// Blue, yellow, red.
    pub buttons: [bool; 3],
}

/// Record `k`'s values: X steps by one each record (so the channels change with every
/// record) and sweeps past the clamp; each button has its own rhythm.
pub fn sample(k: u64) -> Sample {
    Sample {
        x: ((k % 91) as i16 - 45) as i8,
        y: (((k * 13) % 101) as i16 - 50) as i8,
        buttons: [(k / 3) % 2 == 1, (k / 5) % 3 == 1, (k / 7) % 2 == 1],
    }
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentRecord {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// Its values.
    pub sample: Sample,
    /// The yellow byte it carried, if any (pressed or released).
    pub yellow: Option<bool>,
}

/// A report a client must receive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Report {
    /// Button `i` changed.
    Button(usize, bool),
    /// Both channels.
    Analog([f64; 2]),
}

/// A report and the record (index in the log) it comes from; `None` for the centring after
/// silence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expected {
    /// The report.
    pub report: Report,
    /// Its record.
    pub record: Option<usize>,
}

/// The channels a client must receive for a record: −X / 34 and Y / 34, within −1..1.
pub fn expected_channels(s: Sample) -> [f64; 2] {
    let scale = |v: i8| (f64::from(v) / 34.0).clamp(-1.0, 1.0);
    [-scale(s.x), scale(s.y)]
}

/// Everything a client connected from the start must receive for the records in `log`, in
/// order, up to `now`: per record, blue and red changes, the channels if they changed, the
/// yellow change its fourth byte makes; the channels set to zero when 0.2 s passed after a
/// record without another one.
pub fn expected(log: &[SentRecord], now: Instant) -> Vec<Expected> {
    let centre = Duration::from_millis(200);
    let mut out = Vec::new();
    let mut buttons = [false; 3];
    let mut chans = [0.0, 0.0];
    let mut last: Option<Instant> = None;
    let centre_if_quiet = |chans: &mut [f64; 2], until: Instant, last: Option<Instant>| {
        if last.is_some_and(|t| until >= t + centre) && *chans != [0.0, 0.0] {
            *chans = [0.0, 0.0];
            Some(Expected {
                report: Report::Analog([0.0, 0.0]),
                record: None,
            })
        } else {
            None
        }
    };
    for (i, r) in log.iter().enumerate() {
        out.extend(centre_if_quiet(&mut chans, r.first_byte, last));
        for b in [0, 2] {
            if r.sample.buttons[b] != buttons[b] {
                buttons[b] = r.sample.buttons[b];
                out.push(Expected {
                    report: Report::Button(b, buttons[b]),
                    record: Some(i),
                });
            }
        }
        let c = expected_channels(r.sample);
        if c != chans {
            chans = c;
            out.push(Expected {
                report: Report::Analog(c),
                record: Some(i),
            });
        }
        if let Some(y) = r.yellow.filter(|&y| y != buttons[1]) {
            buttons[1] = y;
            out.push(Expected {
                report: Report::Button(1, y),
                record: Some(i),
            });
        }
        last = Some(r.first_byte);
    }
    out.extend(centre_if_quiet(&mut chans, now, last));
    out
}

/// The simulated Wanda. See the module documentation.
pub struct WandaSim {
    cfg: SimConfig,
    started: bool,
    rts: bool,
    next_record: Option<Instant>,
    /// Records made so far (the next record is `sample(count)`).
    count: u64,
    yellow_was_down: bool,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    /// Sends nothing while true; records made meanwhile are lost and not logged.
    pub mute: bool,
    sent: Vec<SentRecord>,
    init_messages: u64,
}

impl WandaSim {
    /// A Wanda behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> WandaSim {
        WandaSim {
            cfg,
            started: false,
            rts: true,
            next_record: None,
            count: 0,
            yellow_was_down: false,
            out: VecDeque::new(),
            line_free: None,
            mute: false,
            sent: Vec::new(),
            init_messages: 0,
        }
    }

    /// Records sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentRecord] {
        &self.sent
    }

    /// Init messages sent.
    pub fn init_messages(&self) -> u64 {
        self.init_messages
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

    fn power_up(&mut self, at: Instant) {
        if !self.mute {
            self.queue(&INIT_MESSAGE, at);
            self.init_messages += 1;
        }
    }

    fn make_record(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        let s = sample(k);
        let yellow_down = s.buttons[1];
        let yellow = (yellow_down || self.yellow_was_down).then_some(yellow_down);
        self.yellow_was_down = yellow_down;
        if self.mute {
            return;
        }
        let mut bytes = [0u8; RECORD_LEN + 1];
        bytes[..RECORD_LEN].copy_from_slice(&encode(s.x, s.y, s.buttons[0], s.buttons[2]));
        let len = match yellow {
            Some(down) => {
                bytes[RECORD_LEN] = if down { YELLOW_DOWN } else { 0 };
                RECORD_LEN + 1
            }
            None => RECORD_LEN,
        };
        let first = self.queue(&bytes[..len], at);
        if self.cfg.keep_log {
            self.sent.push(SentRecord {
                first_byte: first,
                sample: s,
                yellow,
            });
        }
    }
}

impl DeviceModel for WandaSim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn set_rts(&mut self, on: bool, now: Now) {
        if on && !self.rts {
            self.power_up(now.mono);
        }
        self.rts = on;
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if !self.started {
            self.started = true;
            self.power_up(now.mono);
            self.next_record = Some(now.mono + self.cfg.period);
        }
        while let Some(t) = self.next_record.filter(|&t| t <= now.mono) {
            self.make_record(t);
            let gap = if self.count % self.cfg.burst.max(1) == 0 {
                self.cfg.pause
            } else {
                self.cfg.period
            };
            // A simulator that was not stepped for a while (unplugged) does not catch up.
            self.next_record = Some((t + gap).max(now.mono));
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
        [self.out.front().map(|&(t, _)| t), self.next_record]
            .into_iter()
            .flatten()
            .min()
    }
}
