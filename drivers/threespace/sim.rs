//! A simulated Polhemus 3SPACE or ISOTRAK: the tracker's end of its serial line, for tests
//! and for a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * Single-byte commands: `c` stops continuous output, `C` starts it, `S` asks for the
//!   status (answered after [`SimConfig::reply_delay`]: 55 bytes for the 3SPACE, 21 for the
//!   ISOTRAK, starting with `2`), `f` binary records, `F` ASCII, `u` metric units; CR, `W`,
//!   `t`, `Y`, `P`, Ctrl-K are accepted and do nothing here. Ctrl-Y reinitialises the tracker:
//!   for [`SimConfig::reboot_time`] it hears nothing and sends nothing, then it is stopped, in
//!   ASCII mode. Any other letter starts a command line that ends with CR (`O2,11`, `x…`,
//!   `v…`, `R1`, `b1`, `H1,0,1,0`, …); every command is kept ([`ThreeSpaceSim::commands`]).
//! * Continuous output in binary mode sends one record every [`SimConfig::period`], cycling
//!   through [`SimConfig::stations`]; record `k` (counted over the simulator's life) holds
//!   [`sample(model, k, station)`](sample), and [`Sample::expected`] is what a VRPN client must
//!   receive for it, computed here from the record's definition, independently of the driver.
//!   In ASCII mode the output is a text line per record (which a binary reader must skip).
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each binary record is
//!   logged with the time its first byte was due and, once it has left, the step that handed
//!   it to the line ([`ThreeSpaceSim::sent`], [`SentRecord::written`]).
//! * Faults: [`ThreeSpaceSim::inject`] puts bytes on the line, [`SimConfig::status_reply`]
//!   breaks the status answer, [`SimConfig::ignores_stop`] keeps streaming through `c`.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{data, pack, Model, RECORD_LEN};
use super::reset::{status_len, CTRL_K, CTRL_Y};
use crate::sim::{DeviceModel, FirstByteLogged, FirstWrites, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `threespace`.
pub static SIMULATOR: Simulator = Simulator {
    name: "threespace",
    about: "Polhemus 3SPACE: answers the reset and status, then streams known binary records",
    baud: 19200,
    line: "vrpn_Tracker_3Space Tracker0 {PATH} {BAUD}",
    make: |baud| Box::new(ThreeSpaceSim::new(SimConfig::new(Model::ThreeSpace, baud))),
};

/// How the status request is answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusReply {
    /// As a working tracker.
    Good,
    /// Not at all.
    Silent,
    /// With a line that does not start with `2`.
    Garbage,
    /// With its first five bytes only.
    Short,
}

/// How the simulated tracker behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Which tracker.
    pub model: Model,
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between records in continuous output.
    pub period: Duration,
    /// The stations that send records (1-based), in turn.
    pub stations: Vec<u8>,
    /// Time from a command to its answer or to the first record.
    pub reply_delay: Duration,
    /// Time a Ctrl-Y takes.
    pub reboot_time: Duration,
    /// Streaming binary records when the port opens (an earlier program left it so).
    pub streaming_at_start: bool,
    /// How the status request is answered.
    pub status_reply: StatusReply,
    /// Log every binary record sent.
    pub keep_log: bool,
    /// Keeps streaming through the stop command.
    pub ignores_stop: bool,
}

impl SimConfig {
    /// A `model` tracker on a line at `baud`: one station, 60 records a second (fewer where
    /// the line is too slow for them), answers after 2 ms, 500 ms to reinitialise, streaming
    /// already, no log.
    pub fn new(model: Model, baud: u32) -> SimConfig {
        let record_time =
            Duration::from_micros(RECORD_LEN as u64 * 10_000_000 / u64::from(baud.max(1)));
        SimConfig {
            model,
            baud,
            period: Duration::from_micros(16_667).max(record_time * 2),
            stations: vec![1],
            reply_delay: Duration::from_millis(2),
            reboot_time: Duration::from_millis(500),
            streaming_at_start: true,
            status_reply: StatusReply::Good,
            keep_log: false,
            ignores_stop: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The contents of one record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// Which tracker sent it.
    pub model: Model,
    /// Station, 1-based.
    pub station: u8,
    /// Status byte (the ISOTRAK's stylus: `@` pressed, `*` released).
    pub status: u8,
    /// Position x, y, z, quaternion w, x, y, z, as sent.
    pub values: [i16; 7],
}

impl Sample {
    /// The record as it goes on the line.
    pub fn bytes(&self) -> [u8; RECORD_LEN] {
        pack(&data(self.station, self.status, self.values))
    }

    /// What a client must receive: sensor, position in metres, quaternion (x, y, z, w).
    ///
    /// 3SPACE: position = value × 65.48 in × 0.0254 m/in / 32768; quaternion normalised.
    /// ISOTRAK: position = value × 1.6632 m / 32767; each quaternion component = value ×
    /// (1/32767) in single precision, not normalised (as C++ VRPN computes it).
    pub fn expected(&self) -> (usize, [f64; 3], [f64; 4]) {
        let v = self.values;
        let sensor = usize::from(self.station) - 1;
        match self.model {
            Model::ThreeSpace => {
                let m = 65.48 * 2.54 / 100.0 / 32768.0;
                let (w, x, y, z) = (
                    f64::from(v[3]),
                    f64::from(v[4]),
                    f64::from(v[5]),
                    f64::from(v[6]),
                );
                let n = (x * x + y * y + z * z + w * w).sqrt();
                (
                    sensor,
                    [
                        f64::from(v[0]) * m,
                        f64::from(v[1]) * m,
                        f64::from(v[2]) * m,
                    ],
                    [x / n, y / n, z / n, w / n],
                )
            }
            Model::Isotrak => {
                let m = 1.6632 / 32767.0;
                let q = |c: i16| f64::from(f32::from(c) * (1.0f32 / 32767.0f32));
                (
                    sensor,
                    [
                        f64::from(v[0]) * m,
                        f64::from(v[1]) * m,
                        f64::from(v[2]) * m,
                    ],
                    [q(v[4]), q(v[5]), q(v[6]), q(v[3])],
                )
            }
        }
    }

    /// The stylus switch this record shows, if it shows one (`@` or `*`).
    pub fn stylus(&self) -> Option<bool> {
        match self.status {
            b'@' => Some(true),
            b'*' => Some(false),
            _ => None,
        }
    }
}

/// Record `k`'s values, from `station`: positions over the whole range, a quaternion that is
/// never zero, and (ISOTRAK) the stylus pressed for 7 records out of 14.
pub fn sample(model: Model, k: u64, station: u8) -> Sample {
    let c = |mul: u64, add: u64| ((k * mul + add) % 65_536) as u16 as i16;
    let status = match model {
        Model::Isotrak => {
            if (k / 7) % 2 == 1 {
                b'@'
            } else {
                b'*'
            }
        }
        Model::ThreeSpace => b' ',
    };
    Sample {
        model,
        station,
        status,
        values: [
            c(4099, 11),
            c(8191, 30_000),
            c(127, 65_000),
            // w never 0.
            ((k * 37) % 30_000) as i16 + 100,
            c(1021, 7),
            c(7919, 123),
            -(((k * 17) % 20_000) as i16),
        ],
    }
}

/// A binary record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentRecord {
    /// When its first byte was due to leave the tracker (the line's pacing).
    pub first_byte: Instant,
    /// The `now` of the step that handed its first byte to the line (on a pseudo-terminal:
    /// the time just before the write), once it has left.
    pub written: Option<Now>,
    /// Its values.
    pub sample: Sample,
    offset: u64,
}

impl FirstByteLogged for SentRecord {
    fn first_offset(&self) -> u64 {
        self.offset
    }
    fn set_written(&mut self, at: Now) {
        self.written = Some(at);
    }
}

/// The simulated tracker. See the module documentation.
pub struct ThreeSpaceSim {
    cfg: SimConfig,
    continuous: bool,
    binary: bool,
    next_record: Option<Instant>,
    started: bool,
    count: u64,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    writes: FirstWrites,
    pending_status: Option<Instant>,
    rebooting_until: Option<Instant>,
    line: Vec<u8>,
    in_line: bool,
    commands: Vec<String>,
    heard: Vec<u8>,
    sent: Vec<SentRecord>,
    /// Sends nothing while true.
    pub mute: bool,
}

impl ThreeSpaceSim {
    /// A tracker behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> ThreeSpaceSim {
        ThreeSpaceSim {
            continuous: cfg.streaming_at_start,
            binary: cfg.streaming_at_start,
            cfg,
            next_record: None,
            started: false,
            count: 0,
            out: VecDeque::new(),
            line_free: None,
            writes: FirstWrites::new(),
            pending_status: None,
            rebooting_until: None,
            line: Vec::new(),
            in_line: false,
            commands: Vec::new(),
            heard: Vec::new(),
            sent: Vec::new(),
            mute: false,
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

    /// Binary records sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentRecord] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
        self.writes.log_cleared();
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// Every command heard, in order: single bytes as themselves (control bytes as `^Y`,
    /// `^K`, CR as `\r`), command lines without their CR.
    pub fn commands(&self) -> &[String] {
        &self.commands
    }

    /// Forgets the commands heard.
    pub fn clear_commands(&mut self) {
        self.commands.clear();
    }

    /// True while continuous output is on.
    pub fn is_streaming(&self) -> bool {
        self.continuous
    }

    /// True while records are binary.
    pub fn is_binary(&self) -> bool {
        self.binary
    }

    /// Puts `bytes` on the line at `now`, after what is already queued.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue(bytes, now);
    }

    /// Queues `bytes` to leave from `at` on (after what is queued already); returns when the
    /// first is due and its offset in the output stream.
    fn queue(&mut self, bytes: &[u8], at: Instant) -> (Instant, u64) {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + self.cfg.byte_offset(i), b));
        }
        self.line_free = Some(start + self.cfg.byte_offset(bytes.len()));
        (start, self.writes.queue(bytes.len()))
    }

    fn make_record(&mut self, at: Instant) {
        let stations = &self.cfg.stations;
        let station = stations[(self.count % stations.len() as u64) as usize];
        let s = sample(self.cfg.model, self.count, station);
        self.count += 1;
        if self.mute {
            return;
        }
        if !self.binary {
            let text = format!(
                "0{station}  {:6} {:6} {:6}\r\n",
                s.values[0], s.values[1], s.values[2]
            );
            self.queue(text.as_bytes(), at);
            return;
        }
        let (first, offset) = self.queue(&s.bytes(), at);
        if self.cfg.keep_log {
            self.sent.push(SentRecord {
                first_byte: first,
                written: None,
                sample: s,
                offset,
            });
        }
    }

    fn answer_status(&mut self, at: Instant) {
        if self.mute {
            return;
        }
        let len = status_len(self.cfg.model);
        let mut answer = vec![b' '; len];
        answer[..3].copy_from_slice(b"21S");
        answer[3..7].copy_from_slice(b"3SPC");
        answer[len - 2] = b'\r';
        answer[len - 1] = b'\n';
        match self.cfg.status_reply {
            StatusReply::Good => {
                self.queue(&answer, at);
            }
            StatusReply::Silent => {}
            StatusReply::Garbage => {
                answer[0] = b'X';
                self.queue(&answer, at);
            }
            StatusReply::Short => {
                self.queue(&answer[..5], at);
            }
        }
    }

    fn command(&mut self, b: u8, now: Instant) {
        if self.in_line {
            if b == b'\r' {
                self.in_line = false;
                let text = String::from_utf8_lossy(&self.line).into_owned();
                self.commands.push(text);
                self.line.clear();
            } else {
                self.line.push(b);
            }
            return;
        }
        let name = match b {
            CTRL_Y => "^Y".to_owned(),
            CTRL_K => "^K".to_owned(),
            b'\r' => "\\r".to_owned(),
            _ => (b as char).to_string(),
        };
        match b {
            b'c' if !self.cfg.ignores_stop => {
                self.continuous = false;
                self.next_record = None;
            }
            b'C' => {
                if !self.continuous {
                    self.next_record = Some(now + self.cfg.reply_delay);
                }
                self.continuous = true;
            }
            b'S' => self.pending_status = Some(now + self.cfg.reply_delay),
            b'f' => self.binary = true,
            b'F' => self.binary = false,
            CTRL_Y => {
                self.rebooting_until = Some(now + self.cfg.reboot_time);
                self.continuous = false;
                self.binary = false;
                self.next_record = None;
                self.pending_status = None;
            }
            b'c' | b'u' | b'\r' | b'W' | b't' | b'Y' | b'P' | CTRL_K => {}
            b if b.is_ascii_alphabetic() => {
                self.in_line = true;
                self.line.push(b);
                return;
            }
            _ => {}
        }
        self.commands.push(name);
    }
}

impl DeviceModel for ThreeSpaceSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        if self.rebooting_until.is_some_and(|t| now.mono < t) {
            return;
        }
        for &b in bytes {
            self.command(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if !self.started {
            self.started = true;
            if self.continuous {
                self.next_record = Some(now.mono);
            }
        }
        if self.rebooting_until.is_some_and(|t| t <= now.mono) {
            self.rebooting_until = None;
        }
        if let Some(t) = self.pending_status.filter(|&t| t <= now.mono) {
            self.pending_status = None;
            self.answer_status(t);
        }
        while let Some(t) = self.next_record.filter(|&t| t <= now.mono) {
            self.make_record(t);
            self.next_record = Some(t + self.cfg.period);
        }
        let mut left = 0;
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            left += 1;
            if !self.mute {
                out.push(b);
            }
        }
        let handed = (!self.mute).then_some(now);
        self.writes.hand(left, handed, &mut self.sent);
    }

    fn next_deadline(&self) -> Option<Instant> {
        [
            self.out.front().map(|&(t, _)| t),
            self.next_record,
            self.pending_status,
            self.rebooting_until,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
