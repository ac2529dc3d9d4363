//! A simulated Polhemus Liberty, Patriot or Liberty Latus: the tracker's end of its serial
//! line, for tests and for a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * Commands end with CR, but for `P` (one ASCII record, which ends continuous output), `C`
//!   (continuous output), Ctrl-V (WhoAmI: [`SimConfig::whoami_len`] bytes starting with `0`,
//!   after [`SimConfig::reply_delay`]) and Ctrl-Y (reinitialise: for
//!   [`SimConfig::reboot_time`] it hears and sends nothing, then it is stopped, in ASCII
//!   mode), which act at once. `F1` / `F0` select binary / ASCII records, `O<s>,…` sets
//!   station *s*'s output list (a list with `10` adds the stylus field; a Patriot answers
//!   an error line for a station above 2), `Q0` zeroes the time stamp clock. Every command is
//!   kept ([`LibertySim::commands`]).
//! * Continuous binary output sends, every [`SimConfig::period`], one record per station of
//!   [`SimConfig::stations`]; record `k` (counted over the simulator's life) holds
//!   [`sample(k, station)`](sample), and [`Sample::expected`] is what a client must receive
//!   for it, computed from the record's definition independently of the driver.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each binary record is
//!   logged with the time its first byte was due and, once it has left, the step that handed
//!   it to the line ([`SentRecord::written`]: a station's own, not its frame's).
//! * Faults: [`LibertySim::inject`], [`SimConfig::whoami`] (a silent or wrong WhoAmI),
//!   [`SimConfig::ignores_stop`].

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{encode, METRES_PER_INCH, RECORD_LEN};
use super::reset::{CTRL_V, CTRL_Y, DEFAULT_WHOAMI_LEN};
use crate::sim::{DeviceModel, FirstByteLogged, FirstWrites, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `liberty`.
pub static SIMULATOR: Simulator = Simulator {
    name: "liberty",
    about: "Polhemus Liberty: answers the reset and WhoAmI, then streams known binary records",
    baud: 115200,
    line: "vrpn_Tracker_Liberty Liberty {PATH} {BAUD}",
    make: |baud| Box::new(LibertySim::new(SimConfig::new(Kind::Liberty, baud))),
};

/// Which tracker.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Liberty: records start `LY`, up to 8 stations here.
    Liberty,
    /// Patriot: records start `PA`, 2 stations.
    Patriot,
    /// Liberty Latus: records start `LU`.
    Latus,
}

impl Kind {
    /// The first two bytes of its records.
    pub fn start(self) -> [u8; 2] {
        match self {
            Kind::Liberty => *b"LY",
            Kind::Patriot => *b"PA",
            Kind::Latus => *b"LU",
        }
    }
}

/// How WhoAmI is answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WhoAmI {
    /// As a working tracker.
    Good,
    /// Not at all.
    Silent,
    /// With text that does not start with `0`.
    Wrong,
}

/// How the simulated tracker behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Which tracker.
    pub kind: Kind,
    /// Line speed.
    pub baud: u32,
    /// Time between output frames (one record per station each).
    pub period: Duration,
    /// The stations that send records (1-based).
    pub stations: Vec<u8>,
    /// Bytes of the WhoAmI answer.
    pub whoami_len: usize,
    /// How WhoAmI is answered.
    pub whoami: WhoAmI,
    /// Time from a command to its answer or to the first frame.
    pub reply_delay: Duration,
    /// Time a Ctrl-Y takes.
    pub reboot_time: Duration,
    /// Streaming binary records when the port opens.
    pub streaming_at_start: bool,
    /// Log every binary record sent.
    pub keep_log: bool,
    /// Keeps streaming through `P`.
    pub ignores_stop: bool,
}

impl SimConfig {
    /// A `kind` tracker on a line at `baud`: station 1, 60 frames a second (fewer where the
    /// line is too slow), a 195-byte WhoAmI answer after 2 ms, streaming already, no log.
    pub fn new(kind: Kind, baud: u32) -> SimConfig {
        SimConfig {
            kind,
            baud,
            period: Duration::from_micros(16_667),
            stations: vec![1],
            whoami_len: DEFAULT_WHOAMI_LEN,
            whoami: WhoAmI::Good,
            reply_delay: Duration::from_millis(2),
            reboot_time: Duration::from_millis(500),
            streaming_at_start: true,
            keep_log: false,
            ignores_stop: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }

    /// The frame period the line can carry: [`period`](Self::period), or longer.
    fn frame_period(&self) -> Duration {
        let bytes = (RECORD_LEN + 4) * self.stations.len().max(1) * 3 / 2;
        self.period.max(self.byte_offset(bytes))
    }
}

/// The contents of one record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Station, 1-based.
    pub station: u8,
    /// Position, inches.
    pub pos: [f32; 3],
    /// Quaternion w, x, y, z.
    pub wxyz: [f32; 4],
    /// Time stamp, ms.
    pub millis: u32,
    /// Stylus field, if the station's output list has it.
    pub stylus: Option<u32>,
}

impl Sample {
    /// What a client must receive: sensor, position in metres (inches × 2.54 / 100, in double
    /// precision), quaternion (x, y, z, w) as sent.
    pub fn expected(&self) -> (usize, [f64; 3], [f64; 4]) {
        let [w, x, y, z] = self.wxyz.map(f64::from);
        (
            usize::from(self.station) - 1,
            self.pos.map(|v| f64::from(v) * METRES_PER_INCH),
            [x, y, z, w],
        )
    }
}

/// Record `k`'s values from `station` (the stylus, where there is one, pressed for 5 records
/// out of 10).
pub fn sample(k: u64, station: u8, millis: u32, stylus: bool) -> Sample {
    let f = |mul: u64, add: u64| ((k * mul + add) % 20_001) as f32 / 100.0 - 100.0;
    let a = (k % 628) as f32 / 100.0;
    Sample {
        station,
        pos: [f(37, 11), f(101, 5_000), f(7_919, 17)],
        wxyz: [(a / 2.0).cos(), 0.0, (a / 2.0).sin(), f(3, 1) / 1000.0],
        millis,
        stylus: stylus.then(|| u32::from((k / 5) % 2 == 1)),
    }
}

/// A binary record put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
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
pub struct LibertySim {
    cfg: SimConfig,
    continuous: bool,
    binary: bool,
    stylus: [bool; 17],
    next_frame: Option<Instant>,
    started: bool,
    count: u64,
    zero: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    writes: FirstWrites,
    pending: Vec<(Instant, Vec<u8>)>,
    rebooting_until: Option<Instant>,
    line: Vec<u8>,
    commands: Vec<String>,
    sent: Vec<SentRecord>,
    scratch: Vec<u8>,
}

impl LibertySim {
    /// A tracker behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> LibertySim {
        LibertySim {
            continuous: cfg.streaming_at_start,
            binary: cfg.streaming_at_start,
            cfg,
            stylus: [false; 17],
            next_frame: None,
            started: false,
            count: 0,
            zero: None,
            out: VecDeque::new(),
            line_free: None,
            writes: FirstWrites::new(),
            pending: Vec::new(),
            rebooting_until: None,
            line: Vec::new(),
            commands: Vec::new(),
            sent: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// Changes how later WhoAmI requests are answered.
    pub fn set_whoami(&mut self, w: WhoAmI) {
        self.cfg.whoami = w;
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

    /// Every command heard, in order (control bytes as `^V`, `^Y`; lines without CR).
    pub fn commands(&self) -> &[String] {
        &self.commands
    }

    /// True while continuous binary output is on.
    pub fn is_streaming_binary(&self) -> bool {
        self.continuous && self.binary
    }

    /// Puts `bytes` on the line at `now`.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue_at(bytes, now);
    }

    /// Queues `bytes` to leave from `at` on (after what is queued already); returns when the
    /// first is due and its offset in the output stream.
    fn queue_at(&mut self, bytes: &[u8], at: Instant) -> (Instant, u64) {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + self.cfg.byte_offset(i), b));
        }
        self.line_free = Some(start + self.cfg.byte_offset(bytes.len()));
        (start, self.writes.queue(bytes.len()))
    }

    fn max_station(&self) -> usize {
        match self.cfg.kind {
            Kind::Patriot => 2,
            _ => 16,
        }
    }

    fn frame(&mut self, at: Instant) {
        let millis = self
            .zero
            .map_or(0, |z| at.saturating_duration_since(z).as_millis() as u32);
        for i in 0..self.cfg.stations.len() {
            let station = self.cfg.stations[i];
            let s = sample(
                self.count,
                station,
                millis,
                self.stylus[usize::from(station)],
            );
            self.count += 1;
            if !self.binary {
                let text = format!(
                    "{station:2}P {:8.3} {:8.3} {:8.3}\r\n",
                    s.pos[0], s.pos[1], s.pos[2]
                );
                self.queue_at(text.as_bytes(), at);
                continue;
            }
            self.scratch.clear();
            let mut bytes = std::mem::take(&mut self.scratch);
            encode(
                self.cfg.kind.start(),
                station,
                s.pos,
                s.wxyz,
                s.millis,
                s.stylus,
                &mut bytes,
            );
            let (first, offset) = self.queue_at(&bytes, at);
            self.scratch = bytes;
            if self.cfg.keep_log {
                self.sent.push(SentRecord {
                    first_byte: first,
                    written: None,
                    sample: s,
                    offset,
                });
            }
        }
    }

    fn whoami(&mut self, at: Instant) {
        let len = self.cfg.whoami_len;
        let mut text = b"0  Polhemus Liberty simulator, 8 stations, firmware 1.0".to_vec();
        text.resize(len.max(4) - 2, b' ');
        text.extend_from_slice(b"\r\n");
        text.truncate(len);
        match self.cfg.whoami {
            WhoAmI::Good => self.pending.push((at, text)),
            WhoAmI::Silent => {}
            WhoAmI::Wrong => {
                text[0] = b'?';
                self.pending.push((at, text));
            }
        }
    }

    fn line_command(&mut self, now: Instant) {
        let text = String::from_utf8_lossy(&self.line).into_owned();
        self.line.clear();
        if text.is_empty() {
            return;
        }
        match text.as_bytes()[0] {
            b'F' => self.binary = text == "F1",
            b'Q' => self.zero = Some(now),
            b'O' => {
                let station: usize = text[1..]
                    .split(',')
                    .next()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(0);
                if station == 0 || station > self.max_station() {
                    let reply = format!("{station:2}O Station out of range\r\n");
                    self.pending
                        .push((now + self.cfg.reply_delay, reply.into_bytes()));
                } else {
                    self.stylus[station] = text.split(',').skip(1).any(|f| f == "10");
                }
            }
            _ => {}
        }
        self.commands.push(text);
    }

    fn byte(&mut self, b: u8, now: Instant) {
        match b {
            b'\r' => self.line_command(now),
            CTRL_V => {
                self.commands.push("^V".into());
                self.whoami(now + self.cfg.reply_delay);
            }
            CTRL_Y => {
                self.commands.push("^Y".into());
                self.line.clear();
                self.rebooting_until = Some(now + self.cfg.reboot_time);
                self.continuous = false;
                self.binary = false;
                self.next_frame = None;
                self.pending.clear();
            }
            b'P' if self.line.is_empty() => {
                self.commands.push("P".into());
                if !self.cfg.ignores_stop {
                    self.continuous = false;
                    self.next_frame = None;
                    let t = now + self.cfg.reply_delay;
                    self.frame(t);
                }
            }
            b'C' if self.line.is_empty() => {
                self.commands.push("C".into());
                if !self.continuous {
                    self.next_frame = Some(now + self.cfg.reply_delay);
                }
                self.continuous = true;
            }
            _ => self.line.push(b),
        }
    }
}

impl DeviceModel for LibertySim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        if self.rebooting_until.is_some_and(|t| now.mono < t) {
            return;
        }
        for &b in bytes {
            self.byte(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if !self.started {
            self.started = true;
            if self.continuous {
                self.next_frame = Some(now.mono);
            }
        }
        if self.rebooting_until.is_some_and(|t| t <= now.mono) {
            self.rebooting_until = None;
        }
        let mut due: Vec<(Instant, Vec<u8>)> = Vec::new();
        self.pending.retain(|(t, b)| {
            if *t <= now.mono {
                due.push((*t, b.clone()));
                false
            } else {
                true
            }
        });
        for (t, b) in due {
            self.queue_at(&b, t);
        }
        let period = self.cfg.frame_period();
        while let Some(t) = self.next_frame.filter(|&t| t <= now.mono) {
            self.frame(t);
            self.next_frame = Some(t + period);
        }
        let before = out.len();
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
        self.writes
            .hand(out.len() - before, Some(now), &mut self.sent);
    }

    fn next_deadline(&self) -> Option<Instant> {
        [
            self.out.front().map(|&(t, _)| t),
            self.next_frame,
            self.pending.iter().map(|(t, _)| *t).min(),
            self.rebooting_until,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
