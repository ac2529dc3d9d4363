//! A simulated TNG-3: the device end of its serial line, for tests and for a simulator on a
//! pseudo-terminal.
//!
//! What it does:
//!
//! * It streams from the moment it is plugged in (it takes no commands): a record every
//!   [`SimConfig::period`], start bytes 0x55 and 0xAA in turn. Record `k` (counted over the
//!   simulator's life) carries [`inputs(k)`](inputs); its data bytes take every value, the
//!   start bytes' included.
//! * [`expected`] turns the log into the reports a client must receive, computed here
//!   independently of the driver.
//! * Bytes leave at 19200 baud; with [`SimConfig::keep_log`] every record is logged with the
//!   time its first byte left. [`Tng3Sim::mute`] makes it silent (records made meanwhile are
//!   lost and not logged); [`Tng3Sim::inject`] puts bytes on the line.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `tng3`.
pub static SIMULATOR: Simulator = Simulator {
    name: "tng3",
    about: "Mindtel TNG-3: streams known button and analog records",
    baud: 19200,
    line: "vrpn_Tng3 tng3name {PATH} 8 8",
    make: |_| Box::new(Tng3Sim::new(SimConfig::new())),
};

/// How the simulated box behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time between records' starts.
    pub period: Duration,
    /// Log every record sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A record every 20 ms (10 bytes take 5.2 ms at 19200 baud).
    pub fn new() -> SimConfig {
        SimConfig {
            period: Duration::from_millis(20),
            keep_log: false,
        }
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

/// Record `k`'s eight analog bytes and its digital byte (a Gray code: one input changes per
/// record).
pub fn inputs(k: u64) -> ([u8; 8], u8) {
    let mut a = [0u8; 8];
    for (i, v) in a.iter_mut().enumerate() {
        *v = ((k * (7 * i as u64 + 3) + 31 * i as u64) % 256) as u8;
    }
    (a, ((k ^ (k >> 1)) & 0xFF) as u8)
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sent {
    /// When its first byte left the box.
    pub first_byte: Instant,
    /// Its number.
    pub k: u64,
}

/// A report a client must receive.
#[derive(Clone, Debug, PartialEq)]
pub enum Report {
    /// Button `i` changed.
    Button(usize, bool),
    /// Every channel read.
    Analog(Vec<f64>),
}

/// The reports a client reading `analogs` channels and `buttons` buttons must receive for
/// `log`, from the state `initial` (channels 0, buttons released) on: the channels (byte
/// values) if one changed, then each changed button (pressed while its bit is clear); each
/// with the index of its record.
pub fn expected(log: &[Sent], analogs: usize, buttons: usize) -> Vec<(Report, usize)> {
    let mut out = Vec::new();
    let mut chans = vec![0.0; analogs];
    let mut pressed = vec![false; buttons];
    for (i, s) in log.iter().enumerate() {
        let (a, d) = inputs(s.k);
        let now: Vec<f64> = a[..analogs].iter().map(|&v| f64::from(v)).collect();
        if now != chans {
            chans = now;
            out.push((Report::Analog(chans.clone()), i));
        }
        for (b, p) in pressed.iter_mut().enumerate() {
            let down = d >> b & 1 == 0;
            if down != *p {
                *p = down;
                out.push((Report::Button(b, down), i));
            }
        }
    }
    out
}

/// The simulated box. See the module documentation.
pub struct Tng3Sim {
    cfg: SimConfig,
    next_record: Option<Instant>,
    count: u64,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    /// Silent while true: records made meanwhile are lost and not logged.
    pub mute: bool,
    sent: Vec<Sent>,
}

impl Tng3Sim {
    /// A box behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> Tng3Sim {
        Tng3Sim {
            cfg,
            next_record: None,
            count: 0,
            out: VecDeque::new(),
            line_free: None,
            mute: false,
            sent: Vec::new(),
        }
    }

    /// Records sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// Puts `bytes` on the line at `now`, after what is already queued.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue(bytes, now);
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            // Ten bit times a byte at 19200 baud.
            self.out
                .push_back((start + Duration::from_micros(521 * i as u64), b));
        }
        self.line_free = Some(start + Duration::from_micros(521 * bytes.len() as u64));
        start
    }

    fn make_record(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        if self.mute {
            return;
        }
        let (a, d) = inputs(k);
        let mut r = [0u8; 10];
        r[0] = if k % 2 == 0 { 0x55 } else { 0xAA };
        r[1..9].copy_from_slice(&a);
        r[9] = d;
        let first = self.queue(&r, at);
        if self.cfg.keep_log {
            self.sent.push(Sent {
                first_byte: first,
                k,
            });
        }
    }
}

impl DeviceModel for Tng3Sim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.next_record.is_none() {
            self.next_record = Some(now.mono);
        }
        while let Some(t) = self.next_record.filter(|&t| t <= now.mono) {
            self.make_record(t);
            // A simulator that was not stepped for a while (unplugged) does not catch up.
            self.next_record = Some((t + self.cfg.period).max(now.mono));
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
