//! A simulated DynaSight: the device end of its serial line, for tests and for a simulator on
//! a pseudo-terminal.
//!
//! What it does:
//!
//! * Ctrl-C (`0x03`) stops output (a record already on the line finishes); `'4'` selects
//!   polling mode; `0x11` asks for one record (the status answer), sent after
//!   [`SimConfig::reply_delay`]; `'0'` or `'V'` starts continuous output, one record every
//!   [`SimConfig::period`]. Everything else is ignored. Every byte received is kept
//!   ([`DynaSim::heard`]).
//! * Records carry known values: record `k` (counted over the simulator's life) holds
//!   [`sample(k)`](sample), and [`Sample::expected_position_m`] is what a VRPN client must
//!   receive for it, computed here independently of the driver.
//! * Bytes leave at the line's baud rate (ten bit times each), so a record's first and last
//!   bytes arrive at different times; with [`SimConfig::keep_log`] each record is logged
//!   with the time its first byte left ([`DynaSim::sent`]).
//! * Faults: [`DynaSim::inject`] puts bytes on the line, [`DynaSim::mute`] makes the device
//!   silent (it hears but sends nothing), [`SimConfig::status_reply`] breaks the status
//!   answer, [`SimConfig::streaming_at_start`] leaves it streaming from an earlier program.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{encode, RECORD_LEN};
use super::reset::STATUS_REQUEST;
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim dyna PATH`: a DynaSight streaming 60 records a second.
pub static SIMULATOR: Simulator = Simulator {
    name: "dyna",
    about: "Origin Instruments DynaSight: 60 records/s of known positions",
    baud: 19200,
    line: "vrpn_Tracker_Dyna Dyna0 1 {PATH} {BAUD}",
    make: |baud| Box::new(DynaSim::new(SimConfig::new(baud))),
};

/// How the status request is answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusReply {
    /// With a record, as a working DynaSight.
    Record,
    /// Not at all.
    Silent,
    /// With eight bytes that are not a record.
    Garbage,
    /// With the first three bytes of a record only.
    Short,
}

/// How the simulated DynaSight behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between records in continuous output.
    pub period: Duration,
    /// Time from a command to the first byte of its answer or output.
    pub reply_delay: Duration,
    /// Streaming when the port opens (an earlier program left it so).
    pub streaming_at_start: bool,
    /// How the status request is answered.
    pub status_reply: StatusReply,
    /// Log every record sent.
    pub keep_log: bool,
    /// Keeps streaming through the stop command (as a device at another baud rate would
    /// seem to).
    pub ignores_stop: bool,
}

impl SimConfig {
    /// A DynaSight on a line at `baud`: 60 records a second, answers after 5 ms, streaming
    /// already, working status answer, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_micros(16_667),
            reply_delay: Duration::from_millis(5),
            streaming_at_start: true,
            status_reply: StatusReply::Record,
            keep_log: false,
            ignores_stop: false,
        }
    }

    /// Time on the line of byte `i` of a burst, on whole microseconds.
    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The contents of one record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// Exponent code (0..=3).
    pub exponent: u8,
    /// Tracking status (0 tracking, 1 caution).
    pub status: u8,
    /// Raw coordinates.
    pub xyz: [i16; 3],
}

impl Sample {
    /// The record's bytes (target 0).
    pub fn bytes(&self) -> [u8; RECORD_LEN] {
        encode(0, self.exponent, self.status, self.xyz)
    }

    /// What a client must receive: each coordinate × 2^shift × 0.05 mm, in metres, where the
    /// exponent codes 0, 1, 2, 3 stand for shifts 0, 1, 4, 5.
    pub fn expected_position_m(&self) -> [f64; 3] {
        let factor = [1.0, 2.0, 16.0, 32.0][usize::from(self.exponent & 3)];
        self.xyz.map(|v| f64::from(v) * factor * 0.000_05)
    }
}

/// Record `k`'s values: every exponent code and both statuses occur, coordinates stay within
/// ±10000 so no coordinate byte pair looks like a header.
pub fn sample(k: u64) -> Sample {
    let coord = |mul: u64, add: u64| ((k * mul + add) % 20_001) as i16 - 10_000;
    Sample {
        exponent: ((k / 3) % 4) as u8,
        status: ((k / 5) % 2) as u8,
        xyz: [coord(37, 11), coord(101, 5_000), coord(7_919, 17)],
    }
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentRecord {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// Its values.
    pub sample: Sample,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Stopped,
    Continuous,
}

/// The simulated DynaSight. See the module documentation.
pub struct DynaSim {
    cfg: SimConfig,
    mode: Mode,
    next_record: Option<Instant>,
    started: bool,
    /// Records made so far (the next record is `sample(count)`).
    count: u64,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    pending_status: Option<Instant>,
    /// Sends nothing while true (the device hears commands and keeps its clock).
    pub mute: bool,
    sent: Vec<SentRecord>,
    heard: Vec<u8>,
}

impl DynaSim {
    /// A DynaSight behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> DynaSim {
        DynaSim {
            mode: if cfg.streaming_at_start {
                Mode::Continuous
            } else {
                Mode::Stopped
            },
            cfg,
            next_record: None,
            started: false,
            count: 0,
            out: VecDeque::new(),
            line_free: None,
            pending_status: None,
            mute: false,
            sent: Vec::new(),
            heard: Vec::new(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// Changes how later status requests are answered.
    pub fn set_status_reply(&mut self, reply: StatusReply) {
        self.cfg.status_reply = reply;
    }

    /// Records sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentRecord] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// True while continuous output is on.
    pub fn is_streaming(&self) -> bool {
        self.mode == Mode::Continuous
    }

    /// Puts `bytes` on the line at `now` (line noise), after what is already queued.
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
        if self.mute {
            return;
        }
        let first = self.queue(&s.bytes(), at);
        if self.cfg.keep_log {
            self.sent.push(SentRecord {
                first_byte: first,
                sample: s,
            });
        }
    }

    fn answer_status(&mut self, at: Instant) {
        if self.mute {
            return;
        }
        match self.cfg.status_reply {
            StatusReply::Record => self.make_record(at),
            StatusReply::Silent => {}
            StatusReply::Garbage => {
                self.queue(&[0x41, 0x42, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48], at);
            }
            StatusReply::Short => {
                let b = sample(self.count).bytes();
                self.queue(&b[..3], at);
            }
        }
    }
}

impl DeviceModel for DynaSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        for &b in bytes {
            match b {
                0x03 | b'4' if !self.cfg.ignores_stop => {
                    self.mode = Mode::Stopped;
                    self.next_record = None;
                }
                STATUS_REQUEST => self.pending_status = Some(now.mono + self.cfg.reply_delay),
                b'0' | b'V' if self.mode == Mode::Stopped => {
                    self.mode = Mode::Continuous;
                    self.next_record = Some(now.mono + self.cfg.reply_delay);
                }
                _ => {}
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if !self.started {
            self.started = true;
            if self.mode == Mode::Continuous {
                self.next_record = Some(now.mono);
            }
        }
        if let Some(t) = self.pending_status.filter(|&t| t <= now.mono) {
            self.pending_status = None;
            self.answer_status(t);
        }
        while let Some(t) = self.next_record.filter(|&t| t <= now.mono) {
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
            self.next_record,
            self.pending_status,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
