//! A simulated 5DT Data Glove 16: the device end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * It streams from power-on and hears nothing: an information packet (`<I`, hardware 2.01,
//!   right hand, wired) first and then every [`SimConfig::info_every`] data packets, and a data
//!   packet (`<D`) every [`SimConfig::period`].
//! * Data packet `k` (counted over the glove's life) holds [`sample(k)`](sample), sixteen
//!   12-bit sensor values; [`expected`] is what a client must receive, computed here
//!   independently of the driver.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each data packet is
//!   logged with the time its first byte left ([`Glove16Sim::sent`]).
//! * Faults: [`Glove16Sim::inject`] puts bytes on the line, [`Glove16Sim::mute`] silences it.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::packet::{CHANNELS, SENSORS};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `glove5dt16`.
pub static SIMULATOR: Simulator = Simulator {
    name: "glove5dt16",
    about: "5DT Data Glove 16: streams known sensor values",
    baud: 19200,
    line: "vrpn_5dt16 Glove16 {PATH} {BAUD}",
    make: |baud| Box::new(Glove16Sim::new(SimConfig::new(baud))),
};

/// How the simulated glove behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between data packets (a 36-byte packet takes 19 ms at 19200 baud).
    pub period: Duration,
    /// An information packet after every this many data packets (0: only at power-on).
    pub info_every: u64,
    /// Log every data packet sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A glove at `baud`: a data packet every 25 ms, information every 20, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(25),
            info_every: 20,
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// Data packet `k`'s sixteen sensor values (0..4096).
pub fn sample(k: u64) -> [u16; SENSORS] {
    let mut v = [0u16; SENSORS];
    for (i, x) in v.iter_mut().enumerate() {
        *x = ((k * (37 + 6 * i as u64) + 257 * i as u64) % 4096) as u16;
    }
    v
}

/// The channels a client must receive for `sample`: the raw values, then a 0.
pub fn expected(s: [u16; SENSORS]) -> [f64; CHANNELS] {
    let mut c = [0.0; CHANNELS];
    for (d, &v) in c.iter_mut().zip(&s) {
        *d = f64::from(v);
    }
    c
}

/// A data packet put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentPacket {
    /// When its first byte left the glove.
    pub first_byte: Instant,
    /// The channels a client must receive for it.
    pub channels: [f64; CHANNELS],
}

/// The simulated glove. See the module documentation.
pub struct Glove16Sim {
    cfg: SimConfig,
    next: Option<Instant>,
    count: u64,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentPacket>,
    /// Sends nothing while true (and logs nothing).
    pub mute: bool,
}

impl Glove16Sim {
    /// A glove behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> Glove16Sim {
        Glove16Sim {
            cfg,
            next: None,
            count: 0,
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            mute: false,
        }
    }

    /// Data packets logged (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentPacket] {
        &self.sent
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

    fn make_packets(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        if k == 0 || (self.cfg.info_every > 0 && k % self.cfg.info_every == 0) {
            self.queue(b"<I\x02\x01\x01\x01>", at);
        }
        let s = sample(k);
        let mut p = vec![b'<', b'D'];
        for v in s {
            p.extend_from_slice(&v.to_be_bytes());
        }
        let sum = p.iter().map(|&b| u32::from(b)).sum::<u32>();
        p.extend_from_slice(&[sum as u8, b'>']);
        let first = self.queue(&p, at);
        if self.cfg.keep_log && !self.mute {
            self.sent.push(SentPacket {
                first_byte: first,
                channels: expected(s),
            });
        }
    }
}

impl DeviceModel for Glove16Sim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.next.is_none() {
            self.next = Some(now.mono);
        }
        while let Some(t) = self.next.filter(|&t| t <= now.mono) {
            self.make_packets(t);
            self.next = Some(t + self.cfg.period);
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
        [self.out.front().map(|&(t, _)| t), self.next]
            .into_iter()
            .flatten()
            .min()
    }
}
