//! A simulated 5DT Data Glove 5: the device end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * A wired glove answers `A` with `U` (and stops streaming), `G` with its 32-byte
//!   information block (`BR`, version 2.1, hand, pitch and roll fitted, name "DG5 Glove"),
//!   `C` with one record, and starts streaming on `D`, each after
//!   [`SimConfig::reply_delay`]. A wireless glove hears nothing and streams from power-on.
//! * Record `k` (counted over the glove's life) holds [`sample(k)`](sample); the channels a
//!   client must receive are [`expected`], computed here independently of the driver.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each record is logged
//!   with the time its first byte left ([`GloveSim::sent`]).
//! * Faults: [`GloveSim::inject`] puts bytes on the line, [`GloveSim::mute`] makes the glove
//!   silent (it hears but sends nothing, and logs nothing), [`SimConfig::init_answer`]
//!   changes the answer to `A`.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{CHANNELS, HEADER, WIRELESS_LEFT, WIRELESS_RIGHT};
use super::{INFO, INFO_LEN, INIT, INIT_ANSWER, REQUEST, STREAM};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `glove5dt`.
pub static SIMULATOR: Simulator = Simulator {
    name: "glove5dt",
    about: "5DT Data Glove 5: answers the reset and information requests, then streams (or answers polls with) known finger values",
    baud: 19200,
    // C++'s documented wired line: polled, nine-byte records (what this simulator sends).
    line: "vrpn_5dt Glove0 {PATH} {BAUD} 1 0",
    make: |baud| Box::new(GloveSim::new(SimConfig::new(baud))),
};

/// How the simulated glove behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed (9600: a receive-only wireless glove, as the driver takes it).
    pub baud: u32,
    /// Records carry a tenth byte (always for a wireless glove).
    pub ten_bytes: bool,
    /// A right glove.
    pub right: bool,
    /// Time between streamed records.
    pub period: Duration,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// The answer to `A` (`None`: silence).
    pub init_answer: Option<u8>,
    /// Log every record sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A right glove at `baud`, nine-byte records, 100 records a second when streaming,
    /// answers after 2 ms, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            ten_bytes: false,
            right: true,
            period: Duration::from_millis(10),
            reply_delay: Duration::from_millis(2),
            init_answer: Some(INIT_ANSWER),
            keep_log: false,
        }
    }

    fn wireless(&self) -> bool {
        self.baud == 9600
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// Record `k`'s five fingers, pitch and roll: every value 0..=255 occurs except the header's.
pub fn sample(k: u64) -> [u8; 7] {
    let mul = [7u64, 11, 13, 17, 19, 23, 29];
    let mut v = [0u8; 7];
    for (i, x) in v.iter_mut().enumerate() {
        let raw = ((k * mul[i] + 31 * i as u64) % 256) as u8;
        *x = if raw == HEADER { HEADER + 1 } else { raw };
    }
    v
}

/// The eight channels a client must receive for `sample`: 0, the fingers / 255, pitch and
/// roll × 180 / 255.
pub fn expected(s: [u8; 7]) -> [f64; CHANNELS] {
    let mut c = [0.0; CHANNELS];
    for i in 0..5 {
        c[1 + i] = f64::from(s[i]) / 255.0;
    }
    c[6] = f64::from(s[5]) * 180.0 / 255.0;
    c[7] = f64::from(s[6]) * 180.0 / 255.0;
    c
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentRecord {
    /// When its first byte left the glove.
    pub first_byte: Instant,
    /// The channels a client must receive for it.
    pub channels: [f64; CHANNELS],
}

/// The simulated glove. See the module documentation.
pub struct GloveSim {
    cfg: SimConfig,
    streaming: bool,
    next_record: Option<Instant>,
    count: u64,
    pending: VecDeque<(Instant, u8)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentRecord>,
    heard: Vec<u8>,
    /// Sends nothing while true (the glove hears commands and keeps its clock).
    pub mute: bool,
}

impl GloveSim {
    /// A glove behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> GloveSim {
        GloveSim {
            streaming: cfg.wireless(),
            cfg,
            next_record: None,
            count: 0,
            pending: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            heard: Vec::new(),
            mute: false,
        }
    }

    /// Records logged (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentRecord] {
        &self.sent
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// Changes the answer to later `A` commands.
    pub fn set_init_answer(&mut self, answer: Option<u8>) {
        self.cfg.init_answer = answer;
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

    fn make_record(&mut self, at: Instant) {
        let s = sample(self.count);
        self.count += 1;
        let mut r = vec![HEADER];
        r.extend_from_slice(&s);
        r.push((s.iter().map(|&b| u32::from(b)).sum::<u32>() & 0x7F) as u8);
        if self.cfg.wireless() {
            r.push(if self.cfg.right {
                WIRELESS_RIGHT
            } else {
                WIRELESS_LEFT
            });
        } else if self.cfg.ten_bytes {
            r.push(0x55);
        }
        let first = self.queue(&r, at);
        if self.cfg.keep_log && !self.mute {
            self.sent.push(SentRecord {
                first_byte: first,
                channels: expected(s),
            });
        }
    }

    fn info(&self) -> [u8; INFO_LEN] {
        let mut i = [0u8; INFO_LEN];
        i[..4].copy_from_slice(&[b'B', b'R', 2, 1]);
        i[4] = u8::from(self.cfg.right);
        i[5] = 16;
        i[16..25].copy_from_slice(b"DG5 Glove");
        i
    }

    fn command(&mut self, c: u8, at: Instant) {
        match c {
            INIT => {
                self.streaming = false;
                self.next_record = None;
                if let Some(a) = self.cfg.init_answer {
                    self.queue(&[a], at);
                }
            }
            INFO => {
                let i = self.info();
                self.queue(&i, at);
            }
            REQUEST => self.make_record(at),
            STREAM => self.streaming = true,
            _ => {}
        }
    }
}

impl DeviceModel for GloveSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        if self.cfg.wireless() {
            return;
        }
        for &b in bytes {
            self.pending.push_back((now.mono + self.cfg.reply_delay, b));
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while let Some(&(t, c)) = self.pending.front() {
            if t > now.mono {
                break;
            }
            self.pending.pop_front();
            self.command(c, t);
        }
        if self.streaming && self.next_record.is_none() {
            self.next_record = Some(now.mono);
        }
        while let Some(t) = self
            .next_record
            .filter(|&t| t <= now.mono && self.streaming)
        {
            self.make_record(t);
            self.next_record = Some(t + self.cfg.period);
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
        [
            self.out.front().map(|&(t, _)| t),
            self.next_record.filter(|_| self.streaming),
            self.pending.front().map(|&(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
