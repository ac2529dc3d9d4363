//! A simulated NDI Polaris: the tracker's end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * It talks at 9600 baud until `COMM` moves it (it answers `OKAY` at the old rate, then
//!   switches); bytes the host sends at another speed than its own are lost on it (garbled).
//!   An RTS pulse (where the line carries RTS: the virtual line, not a pseudo-terminal)
//!   resets it to 9600 baud, untracked, and it says `RESET`.
//! * Commands end with CR; every reply carries NDI's CRC. `INIT` forgets the tools and stops
//!   tracking; `PHRQ` gives port handles `0A`, `0B`, …; `PVWR` stores a tool's image (kept:
//!   [`PolarisSim::roms`]); `PINIT` needs an image (or answers `ERROR`); `PENA` enables;
//!   `TSTART` starts tracking with the frame counter at 0; `TX` answers with the latest
//!   frame of every enabled handle after [`SimConfig::reply_delay`]. Every command is kept
//!   ([`PolarisSim::commands`]).
//! * Frames come every [`SimConfig::period`]; tool `t` in frame `k` holds
//!   [`sample(k, t)`](sample), or is missing when [`SimConfig::missing_every`] says so. A
//!   `TX` reply's pose of a tool whose frame is new since the last reply is logged
//!   ([`PolarisSim::sent`]) with the values a client must receive, computed from the digits
//!   independently of the driver, the time the reply's first byte was due and, once it has
//!   left, the step that handed it to the line ([`SentPose::written`]).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::reply::with_crc;
use crate::sim::{DeviceModel, FirstByteLogged, FirstWrites};
use crate::time::Now;

/// How the simulated tracker behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time between measurement frames.
    pub period: Duration,
    /// Time from a command to its reply.
    pub reply_delay: Duration,
    /// Tool `t` is missing in frame `k` when `(k / 8 + t) % n == 0` (`None`: always seen).
    pub missing_every: Option<u64>,
    /// Answers `PINIT` with `ERROR` for these tools (0-based, in `PHRQ` order).
    pub refuse_tools: Vec<usize>,
    /// Tracking already (as left by an earlier server) at this speed when the line opens.
    pub tracking_at: Option<u32>,
    /// Restarts on an RTS pulse (false: an adapter that does not carry RTS).
    pub hears_rts: bool,
    /// Log every new pose sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// 60 frames a second, replies after 3 ms, every tool seen, in reset, no log.
    pub fn new() -> SimConfig {
        SimConfig {
            period: Duration::from_micros(16_667),
            reply_delay: Duration::from_millis(3),
            missing_every: None,
            refuse_tools: Vec::new(),
            tracking_at: None,
            hears_rts: true,
            keep_log: false,
        }
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

/// Tool `t`'s values in frame `k`, as the tracker's integers: q0 qx qy qz (×10⁻⁴), tx ty tz
/// (×10⁻² mm).
pub fn sample(k: u64, t: usize) -> ([i32; 4], [i32; 3]) {
    let a = ((k + t as u64 * 100) % 628) as f64 / 100.0;
    let f = |mul: u64, add: u64| ((k * mul + add + t as u64 * 1_000) % 200_001) as i32 - 100_000;
    (
        [
            ((a / 2.0).cos() * 10_000.0).round() as i32,
            ((k * 7) % 2_000) as i32 - 1_000,
            ((a / 2.0).sin() * 10_000.0).round() as i32,
            t as i32 * 100,
        ],
        [f(37, 11), f(101, 50_000), f(7_919, 17)],
    )
}

/// What a client must receive for those integers: sensor `t`, position in millimetres,
/// quaternion x, y, z, w.
pub fn expected(t: usize, q: [i32; 4], p: [i32; 3]) -> (usize, [f64; 3], [f64; 4]) {
    let q = q.map(|v| f64::from(v) / 10_000.0);
    (t, p.map(|v| f64::from(v) / 100.0), [q[1], q[2], q[3], q[0]])
}

/// A pose put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentPose {
    /// When the first byte of its reply was due to leave the tracker (the line's pacing).
    pub first_byte: Instant,
    /// The `now` of the step that handed its reply's first byte to the line (on a
    /// pseudo-terminal: the time just before the write), once it has left.
    pub written: Option<Now>,
    /// Sensor, position (mm), quaternion (x, y, z, w).
    pub values: (usize, [f64; 3], [f64; 4]),
    /// Its frame number.
    pub frame: u64,
    offset: u64,
}

impl FirstByteLogged for SentPose {
    fn first_offset(&self) -> u64 {
        self.offset
    }
    fn set_written(&mut self, at: Now) {
        self.written = Some(at);
    }
}

#[derive(Clone, Debug, Default)]
struct Handle {
    rom: Vec<u8>,
    initialized: bool,
    enabled: bool,
    last_sent: Option<u64>,
}

/// A reply waiting for its time, with the poses it carries.
type Pending = (Instant, Vec<u8>, Vec<(usize, [i32; 4], [i32; 3], u64)>);

/// The simulated tracker. See the module documentation.
pub struct PolarisSim {
    cfg: SimConfig,
    device_baud: u32,
    host_baud: u32,
    rts: bool,
    handles: Vec<Handle>,
    tracking_since: Option<Instant>,
    line: Vec<u8>,
    pending: Vec<Pending>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    writes: FirstWrites,
    commands: Vec<String>,
    sent: Vec<SentPose>,
    started: bool,
}

impl PolarisSim {
    /// A tracker behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> PolarisSim {
        PolarisSim {
            device_baud: cfg.tracking_at.unwrap_or(9600),
            cfg,
            host_baud: 9600,
            rts: false,
            handles: Vec::new(),
            tracking_since: None,
            line: Vec::new(),
            pending: Vec::new(),
            out: VecDeque::new(),
            line_free: None,
            writes: FirstWrites::new(),
            commands: Vec::new(),
            sent: Vec::new(),
            started: false,
        }
    }

    /// Every command heard, in order (without CR).
    pub fn commands(&self) -> &[String] {
        &self.commands
    }

    /// Poses sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentPose] {
        &self.sent
    }

    /// The image stored for each handle (`0A` first).
    pub fn roms(&self) -> Vec<Vec<u8>> {
        self.handles.iter().map(|h| h.rom.clone()).collect()
    }

    /// The speed it talks at.
    pub fn baud(&self) -> u32 {
        self.device_baud
    }

    /// True while tracking.
    pub fn is_tracking(&self) -> bool {
        self.tracking_since.is_some()
    }

    fn byte_time(&self) -> Duration {
        Duration::from_micros(
            (10_000_000 + u64::from(self.device_baud) / 2) / u64::from(self.device_baud),
        )
    }

    /// Queues `bytes` to leave from `at` on (after what is queued already); returns when the
    /// first is due and its offset in the output stream.
    fn queue_at(&mut self, bytes: &[u8], at: Instant) -> (Instant, u64) {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let step = self.byte_time();
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + step * i as u32, b));
        }
        self.line_free = Some(start + step * bytes.len() as u32);
        (start, self.writes.queue(bytes.len()))
    }

    fn reply(&mut self, body: &[u8], at: Instant) {
        let mut v = Vec::new();
        with_crc(body, &mut v);
        self.pending.push((at, v, Vec::new()));
    }

    fn error(&mut self, code: u8, at: Instant) {
        self.reply(format!("ERROR{code:02X}").as_bytes(), at);
    }

    fn handle(&self, hex: &str) -> Option<usize> {
        let h = u8::from_str_radix(hex.get(..2)?, 16).ok()?;
        let i = usize::from(h.checked_sub(0x0A)?);
        (i < self.handles.len()).then_some(i)
    }

    fn tx(&mut self, now: Instant) {
        let Some(since) = self.tracking_since else {
            return self.error(0x0C, now + self.cfg.reply_delay);
        };
        let at = now + self.cfg.reply_delay;
        let k = (at.saturating_duration_since(since).as_nanos() / self.cfg.period.as_nanos().max(1))
            as u64;
        let enabled: Vec<usize> = (0..self.handles.len())
            .filter(|&i| self.handles[i].enabled)
            .collect();
        let mut body = format!("{:02X}", enabled.len());
        let mut poses = Vec::new();
        for &t in &enabled {
            let missing = self
                .cfg
                .missing_every
                .is_some_and(|n| (k / 8 + t as u64) % n.max(1) == 0);
            body.push_str(&format!("{:02X}", 0x0A + t));
            if missing {
                body.push_str(&format!("MISSING{:08X}{k:08X}\n", 0x31));
                continue;
            }
            let (q, p) = sample(k, t);
            for v in q {
                body.push_str(&format!("{}{:05}", if v < 0 { '-' } else { '+' }, v.abs()));
            }
            for v in p {
                body.push_str(&format!("{}{:06}", if v < 0 { '-' } else { '+' }, v.abs()));
            }
            body.push_str(&format!("+00012{:08X}{k:08X}\n", 0x31));
            if self.handles[t].last_sent != Some(k) {
                self.handles[t].last_sent = Some(k);
                poses.push((t, q, p, k));
            }
        }
        body.push_str("0000");
        let mut v = Vec::new();
        with_crc(body.as_bytes(), &mut v);
        self.pending.push((at, v, poses));
    }

    fn command(&mut self, now: Instant) {
        let text = String::from_utf8_lossy(&self.line).into_owned();
        self.line.clear();
        let text = text.trim_end_matches(' ').to_owned();
        let at = now + self.cfg.reply_delay;
        let (word, arg) = text.split_once(' ').unwrap_or((&text, ""));
        match word {
            "COMM" => {
                let rate = match arg.as_bytes().first() {
                    Some(b'0') => 9600,
                    Some(b'1') => 14_400,
                    Some(b'2') => 19_200,
                    Some(b'3') => 38_400,
                    Some(b'4') => 57_600,
                    Some(b'5') => 115_200,
                    Some(b'6') => 921_600,
                    Some(b'7') => 1_228_739,
                    _ => 0,
                };
                if rate == 0 {
                    self.error(0x04, at);
                } else {
                    // The reply goes out at the old rate; the switch follows it.
                    self.reply(b"OKAY", at);
                    let due: Vec<Pending> = std::mem::take(&mut self.pending);
                    for (t, b, _) in due {
                        self.queue_at(&b, t);
                    }
                    self.device_baud = rate;
                }
            }
            "INIT" => {
                self.handles.clear();
                self.tracking_since = None;
                self.reply(b"OKAY", at);
            }
            "IRATE" => self.reply(b"OKAY", at),
            "PHRQ" => {
                self.handles.push(Handle::default());
                let body = format!("{:02X}", 0x0A + self.handles.len() - 1);
                self.reply(body.as_bytes(), at);
            }
            "PVWR" => match (self.handle(arg), arg.get(2..6), arg.get(6..)) {
                (Some(i), Some(addr), Some(data)) if data.len() == 128 => {
                    let addr = usize::from_str_radix(addr, 16).unwrap_or(usize::MAX);
                    let bytes: Option<Vec<u8>> = (0..64)
                        .map(|j| u8::from_str_radix(&data[j * 2..j * 2 + 2], 16).ok())
                        .collect();
                    match bytes {
                        Some(b) if addr % 64 == 0 && addr < 1024 => {
                            let rom = &mut self.handles[i].rom;
                            if rom.len() < addr + 64 {
                                rom.resize(addr + 64, 0);
                            }
                            rom[addr..addr + 64].copy_from_slice(&b);
                            self.reply(b"OKAY", at);
                        }
                        _ => self.error(0x03, at),
                    }
                }
                _ => self.error(0x03, at),
            },
            "PINIT" => match self.handle(arg) {
                Some(i)
                    if !self.handles[i].rom.is_empty() && !self.cfg.refuse_tools.contains(&i) =>
                {
                    self.handles[i].initialized = true;
                    self.reply(b"OKAY", at);
                }
                _ => self.error(0x0C, at),
            },
            "PENA" => match self.handle(arg) {
                Some(i) if self.handles[i].initialized && arg.get(2..) == Some("D") => {
                    self.handles[i].enabled = true;
                    self.reply(b"OKAY", at);
                }
                _ => self.error(0x0C, at),
            },
            "TSTART" => {
                self.tracking_since = Some(now);
                self.handles.iter_mut().for_each(|h| h.last_sent = None);
                self.reply(b"OKAY", at);
            }
            "TSTOP" => {
                self.tracking_since = None;
                self.reply(b"OKAY", at);
            }
            "TX" => self.tx(now),
            "" => {}
            _ => self.error(0x01, at),
        }
        if !text.is_empty() {
            self.commands.push(text);
        }
    }

    /// The tracker restarts (an RTS pulse): 9600 baud, nothing tracked, `RESET` said.
    fn restart(&mut self, now: Instant) {
        self.device_baud = 9600;
        self.handles.clear();
        self.tracking_since = None;
        self.pending.clear();
        self.line.clear();
        self.commands.push("<RTS reset>".into());
        let mut v = Vec::new();
        with_crc(b"RESET", &mut v);
        self.pending
            .push((now + Duration::from_millis(50), v, Vec::new()));
    }
}

impl DeviceModel for PolarisSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        if self.host_baud != self.device_baud {
            return;
        }
        for &b in bytes {
            if b == b'\r' {
                self.command(now.mono);
            } else if self.line.len() < 512 {
                self.line.push(b);
            }
        }
    }

    fn set_rts(&mut self, on: bool, now: Now) {
        if self.rts && !on && self.cfg.hears_rts {
            self.restart(now.mono);
        }
        self.rts = on;
    }

    fn set_baud(&mut self, baud: u32, _now: Now) {
        self.host_baud = baud;
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if !self.started {
            self.started = true;
            if self.cfg.tracking_at.is_some() {
                // Left tracking by an earlier session, with tool 0 enabled.
                self.handles.push(Handle {
                    rom: vec![0; 64],
                    initialized: true,
                    enabled: true,
                    last_sent: None,
                });
                self.tracking_since = Some(now.mono);
            }
        }
        self.pending.sort_by_key(|p| p.0);
        while self.pending.first().is_some_and(|p| p.0 <= now.mono) {
            let (t, bytes, poses) = self.pending.remove(0);
            let (first, offset) = self.queue_at(&bytes, t);
            if self.cfg.keep_log {
                for (tool, q, p, frame) in poses {
                    self.sent.push(SentPose {
                        first_byte: first,
                        written: None,
                        values: expected(tool, q, p),
                        frame,
                        offset,
                    });
                }
            }
        }
        let before = out.len();
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            // Bytes sent at a speed the host is not listening at arrive garbled.
            out.push(if self.host_baud == self.device_baud {
                b
            } else {
                b ^ 0x5A
            });
        }
        self.writes
            .hand(out.len() - before, Some(now), &mut self.sent);
    }

    fn next_deadline(&self) -> Option<Instant> {
        [
            self.out.front().map(|&(t, _)| t),
            self.pending.iter().map(|p| p.0).min(),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
