//! A simulated Pinch Glove system: the device end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * `T0` switches time stamps off and is answered `0x82 '0' 0x8F`; `T1` switches them on
//!   (answered `0x82 '1' 0x8F`), after [`SimConfig::reply_delay`]. Every byte received is kept
//!   ([`PinchSim::heard`]).
//! * A touch message every [`SimConfig::period`] (a real glove sends one when a contact
//!   changes; these change every time): message `k` (counted over the simulator's life)
//!   holds the pairs of [`pairs(k)`](pairs), with time stamps if they are on (two bytes
//!   before the end byte, not logged).
//! * [`states`] gives the ten buttons a client must see after each logged message, computed
//!   here independently of the driver.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each message without
//!   time stamps is logged with the time its first byte left. [`PinchSim::mute`] makes it
//!   silent (it hears, answers nothing, and its messages are lost and not logged).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::message::{END, TEXT, TOUCH, TOUCH_TIMED};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `pinchglove`.
pub static SIMULATOR: Simulator = Simulator {
    name: "pinchglove",
    about: "Fakespace Pinch Glove: answers the time-stamp command, then sends known touch messages",
    baud: 9600,
    line: "vrpn_Button_PinchGlove PinchGlove0 {PATH} {BAUD}",
    make: |baud| Box::new(PinchSim::new(SimConfig::new(baud))),
};

/// How the simulated glove behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between touch messages.
    pub period: Duration,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// Time stamps on at power-up (an earlier program switched them on).
    pub time_stamps_at_start: bool,
    /// Log every message sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A glove at `baud`: a touch message every 80 ms, answers after 3 ms, time stamps off.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(80),
            reply_delay: Duration::from_millis(3),
            time_stamps_at_start: false,
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The pairs of message `k` (left-hand byte, right-hand byte): every eighth message says
/// nothing touches, every third has two groups of fingers; the hands' masks change with every
/// message.
pub fn pairs(k: u64) -> Vec<(u8, u8)> {
    let left = ((k * 7) % 32) as u8;
    let right = ((k * 11 + 3) % 32) as u8;
    if k % 8 == 0 {
        Vec::new()
    } else if k % 3 == 0 {
        vec![(left & 0x0F, right & 0x0F), (left & 0x10, right & 0x10)]
    } else {
        vec![(left, right)]
    }
}

/// A touch message put on the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SentTouch {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// Its number.
    pub k: u64,
    /// Its pairs.
    pub pairs: Vec<(u8, u8)>,
}

/// The buttons a client must see after `m`: button *j* is the right hand's finger *j*
/// (thumb first, mask 0x10 >> *j*) touching, button 5 + *j* the left hand's.
pub fn buttons_after(m: &SentTouch) -> [bool; 10] {
    let (mut left, mut right) = (0u8, 0u8);
    for &(l, r) in &m.pairs {
        left |= l;
        right |= r;
    }
    let mut out = [false; 10];
    for (j, mask) in [0x10u8, 0x08, 0x04, 0x02, 0x01].into_iter().enumerate() {
        out[j] = right & mask != 0;
        out[5 + j] = left & mask != 0;
    }
    out
}

/// The button states after each message of `log`.
pub fn states(log: &[SentTouch]) -> Vec<[bool; 10]> {
    log.iter().map(buttons_after).collect()
}

/// The changes a client connected from the start must receive, in order: (message index in
/// `log`, button, pressed).
pub fn expected_changes(log: &[SentTouch]) -> Vec<(usize, usize, bool)> {
    let mut state = [false; 10];
    let mut out = Vec::new();
    for (i, m) in log.iter().enumerate() {
        let next = buttons_after(m);
        for b in 0..10 {
            if next[b] != state[b] {
                out.push((i, b, next[b]));
            }
        }
        state = next;
    }
    out
}

/// The simulated glove. See the module documentation.
pub struct PinchSim {
    cfg: SimConfig,
    time_stamps: bool,
    next_message: Option<Instant>,
    count: u64,
    last_heard: Option<u8>,
    pending: Vec<(Instant, u8)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    /// Silent while true: answers nothing, and its messages are lost and not logged.
    pub mute: bool,
    sent: Vec<SentTouch>,
    heard: Vec<u8>,
}

impl PinchSim {
    /// A glove behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> PinchSim {
        PinchSim {
            time_stamps: cfg.time_stamps_at_start,
            cfg,
            next_message: None,
            count: 0,
            last_heard: None,
            pending: Vec::new(),
            out: VecDeque::new(),
            line_free: None,
            mute: false,
            sent: Vec::new(),
            heard: Vec::new(),
        }
    }

    /// Touch messages sent without time stamps (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentTouch] {
        &self.sent
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// True while time stamps are on.
    pub fn time_stamps(&self) -> bool {
        self.time_stamps
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

    fn make_message(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        if self.mute {
            return;
        }
        let pairs = pairs(k);
        let mut bytes = vec![if self.time_stamps { TOUCH_TIMED } else { TOUCH }];
        for &(l, r) in &pairs {
            bytes.extend([l, r]);
        }
        if self.time_stamps {
            bytes.extend([(k % 128) as u8, ((k / 128) % 128) as u8]);
        }
        bytes.push(END);
        let first = self.queue(&bytes, at);
        if self.cfg.keep_log && !self.time_stamps {
            self.sent.push(SentTouch {
                first_byte: first,
                k,
                pairs,
            });
        }
    }
}

impl DeviceModel for PinchSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        for &b in bytes {
            if self.last_heard == Some(b'T') && (b == b'0' || b == b'1') {
                self.time_stamps = b == b'1';
                if !self.mute {
                    let at = now.mono + self.cfg.reply_delay;
                    self.pending.extend([(at, TEXT), (at, b), (at, END)]);
                }
            }
            self.last_heard = Some(b);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.next_message.is_none() {
            self.next_message = Some(now.mono + self.cfg.period);
        }
        if self.pending.first().is_some_and(|&(t, _)| t <= now.mono) {
            let at = self.pending[0].0;
            let answer: Vec<u8> = self.pending.drain(..).map(|(_, b)| b).collect();
            self.queue(&answer, at);
        }
        while let Some(t) = self.next_message.filter(|&t| t <= now.mono) {
            self.make_message(t);
            // A simulator that was not stepped for a while (unplugged) does not catch up.
            self.next_message = Some((t + self.cfg.period).max(now.mono));
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
            self.next_message,
            self.pending.first().map(|&(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
