//! A simulated Tektronix 4662 plotter: the device's end of its serial line, for tests and for
//! a simulator on a pseudo-terminal.
//!
//! It executes what the host sends, in order: NULs are ignored, `ESC A E` turns the plotter
//! on (until then it ignores everything else), `ESC A N` forgets commands not yet carried
//! out, [`GS`](super::gin::GS) and a five-byte address move the pen there at
//! [`SimConfig::speed`], and `ESC A M` (GIN) is answered 1 ms after the moves before it are
//! done, with the pen's position in seven bytes. With [`SimConfig::wander`] the joystick
//! moves the pen before each answer to a place computed from the answer's number
//! ([`wander_position`]); `vrpn_device_sim` lets it wander until the host first moves the
//! pen. With [`SimConfig::keep_log`] it logs every answer ([`PlotterSim::sent`])
//! with the position in counts, the metres a client must receive, and the time the answer's
//! first byte left.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator for `vrpn_device_sim`.
pub static SIMULATOR: Simulator = Simulator {
    name: "tek4662",
    about: "Tektronix 4662 plotter: answers position requests, its joystick wanders until \
            the host moves the pen",
    baud: 1200,
    line: "vrpn_Tek4662 Tek4662 {PATH} {BAUD}",
    make: |baud| {
        let mut cfg = SimConfig::new(baud);
        cfg.wander = true;
        cfg.wander_until_moved = true;
        Box::new(PlotterSim::new(cfg))
    },
};

/// How the simulated plotter behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// The pen at power-on, in counts.
    pub start: (u16, u16),
    /// Pen speed in metres per second.
    pub speed: f64,
    /// The joystick moves the pen before each answer ([`wander_position`]).
    pub wander: bool,
    /// The joystick stops wandering when the host first moves the pen (so that a client can
    /// take the pen over from `vrpn_device_sim`).
    pub wander_until_moved: bool,
    /// Log every answer.
    pub keep_log: bool,
}

impl SimConfig {
    /// A plotter at `baud`, its pen at (1000, 500), moving at 570 mm/s, no wandering, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            start: (1000, 500),
            speed: 0.57,
            wander: false,
            wander_until_moved: false,
            keep_log: false,
        }
    }
}

/// Where the joystick puts the pen before answer `k` when wandering: every count of both
/// axes is visited in time (coprime steps).
pub fn wander_position(k: u64) -> (u16, u16) {
    ((k * 389 % 4096) as u16, (k * 151 % 2731) as u16)
}

/// A position the plotter told, and when the answer's first byte left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sent {
    /// The pen in counts.
    pub counts: (u16, u16),
    /// The position a client must receive, in metres: counts over 4095 per 15 inches, in
    /// single precision.
    pub metres: [f64; 3],
    /// When the answer's first byte left.
    pub at: Instant,
}

/// The metres a count stands for, as the plotter's documentation defines its units (4095
/// counts per 15 inches) and C++ VRPN rounds them (single precision).
pub fn count_metres(c: u16) -> f64 {
    let per_metre = 1.0 / ((15.0 / 4095.0) * 0.0254);
    f64::from((f64::from(c) / per_metre) as f32)
}

/// A command being parsed.
#[derive(Clone, Copy, Debug)]
enum Parse {
    Idle,
    Esc,
    EscA,
    Address { bytes: [u8; 5], len: usize },
}

/// A command waiting to be carried out, with when it arrived.
#[derive(Clone, Copy, Debug)]
enum Command {
    Move(u16, u16),
    Gin,
}

/// The simulated plotter. See the module documentation.
pub struct PlotterSim {
    cfg: SimConfig,
    on: bool,
    parse: Parse,
    pen: (u16, u16),
    pen_down: bool,
    queue: VecDeque<(Instant, Command)>,
    /// The plotter is busy (moving, answering) until then.
    busy_until: Option<Instant>,
    /// A move under way: when it ends and where.
    moving: Option<(Instant, (u16, u16))>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    answers: u64,
    moves: u64,
    resets: u64,
    heard: Vec<u8>,
    sent: Vec<Sent>,
}

impl PlotterSim {
    /// A plotter behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> PlotterSim {
        PlotterSim {
            pen: cfg.start,
            cfg,
            on: false,
            parse: Parse::Idle,
            pen_down: false,
            queue: VecDeque::new(),
            busy_until: None,
            moving: None,
            out: VecDeque::new(),
            line_free: None,
            answers: 0,
            moves: 0,
            resets: 0,
            heard: Vec::new(),
            sent: Vec::new(),
        }
    }

    /// Every answer, in order (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// The pen now, in counts.
    pub fn pen(&self) -> (u16, u16) {
        self.pen
    }

    /// Answers sent.
    pub fn answers(&self) -> u64 {
        self.answers
    }

    /// Moves carried out or under way.
    pub fn moves(&self) -> u64 {
        self.moves
    }

    /// `ESC A N` heard.
    pub fn resets(&self) -> u64 {
        self.resets
    }

    /// Every byte heard (with [`SimConfig::keep_log`]).
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// Moves the pen with the joystick.
    pub fn joystick(&mut self, to: (u16, u16)) {
        self.pen = to;
    }

    /// Turns wandering on or off.
    pub fn set_wander(&mut self, on: bool) {
        self.cfg.wander = on;
    }

    fn byte_time(&self) -> Duration {
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    fn byte(&mut self, b: u8, now: Instant) {
        self.parse = match (self.parse, b) {
            (Parse::Idle, 27) => Parse::Esc,
            (Parse::Idle, 29) => Parse::Address {
                bytes: [0; 5],
                len: 0,
            },
            (Parse::Idle, _) => Parse::Idle,
            (Parse::Esc, b'A') => Parse::EscA,
            (Parse::Esc | Parse::EscA, 27) => Parse::Esc,
            (Parse::Esc, _) => Parse::Idle,
            (Parse::EscA, c) => {
                match c {
                    b'E' => self.on = true,
                    b'N' => {
                        self.resets += 1;
                        self.queue.clear();
                    }
                    b'M' if self.on => self.queue.push_back((now, Command::Gin)),
                    _ => {}
                }
                Parse::Idle
            }
            (Parse::Address { mut bytes, len }, c) => {
                bytes[len] = c;
                if len + 1 < 5 {
                    Parse::Address {
                        bytes,
                        len: len + 1,
                    }
                } else {
                    if self.on {
                        let y = (u16::from(bytes[0] & 31) << 7)
                            | (u16::from(bytes[2] & 31) << 2)
                            | (u16::from(bytes[1] >> 2) & 3);
                        let x = (u16::from(bytes[3] & 31) << 7)
                            | (u16::from(bytes[4] & 31) << 2)
                            | u16::from(bytes[1] & 3);
                        self.queue.push_back((now, Command::Move(x, y)));
                    }
                    Parse::Idle
                }
            }
        };
    }

    /// The seven bytes telling the pen's position; bits the host ignores vary with `k`.
    fn answer_bytes(&self, k: u64) -> [u8; 7] {
        let (x, y) = self.pen;
        let k = k as u8;
        [
            0x20 | (x >> 7) as u8,
            0x20 | (y >> 7) as u8,
            0x20 | ((x >> 2) & 31) as u8,
            0x20 | ((y >> 2) & 31) as u8,
            0x20 | ((x & 3) << 3) as u8 | (k & 7),
            0x20 | ((y & 3) << 3) as u8 | ((k >> 3) & 7),
            0x40 | if self.pen_down { 4 } else { 0 } | (k & 0x1b),
        ]
    }

    fn queue_out(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let mut t = start;
        for &b in bytes {
            self.out.push_back((t, b));
            t += self.byte_time();
        }
        self.line_free = Some(t);
        start
    }

    /// Carries out the commands whose turn has come by `now`.
    fn execute(&mut self, now: Instant) {
        loop {
            if let Some((end, to)) = self.moving {
                if end > now {
                    return;
                }
                self.moving = None;
                self.pen = to;
            }
            let Some(&(arrived, cmd)) = self.queue.front() else {
                return;
            };
            let start = self.busy_until.map_or(arrived, |b| b.max(arrived));
            if start > now {
                return;
            }
            self.queue.pop_front();
            match cmd {
                Command::Move(x, y) => {
                    self.moves += 1;
                    if self.cfg.wander_until_moved {
                        self.cfg.wander = false;
                    }
                    let dx = f64::from(x) - f64::from(self.pen.0);
                    let dy = f64::from(y) - f64::from(self.pen.1);
                    let metres = dx.hypot(dy) * 0.381 / 4095.0;
                    let end = start
                        + Duration::from_millis(2)
                        + Duration::from_secs_f64(metres / self.cfg.speed.max(1e-3));
                    self.moving = Some((end, (x, y)));
                    self.busy_until = Some(end);
                }
                Command::Gin => {
                    let k = self.answers;
                    self.answers += 1;
                    if self.cfg.wander {
                        self.pen = wander_position(k);
                        self.pen_down = k % 3 == 0;
                    }
                    let bytes = self.answer_bytes(k);
                    let at = self.queue_out(&bytes, start + Duration::from_millis(1));
                    self.busy_until = Some(at);
                    if self.cfg.keep_log {
                        let (x, y) = self.pen;
                        self.sent.push(Sent {
                            counts: self.pen,
                            metres: [count_metres(x), count_metres(y), 0.0],
                            at,
                        });
                    }
                }
            }
        }
    }
}

impl DeviceModel for PlotterSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        if self.cfg.keep_log {
            self.heard.extend_from_slice(bytes);
        }
        for &b in bytes {
            self.byte(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        self.execute(now.mono);
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let next_command = self
            .queue
            .front()
            .map(|&(arrived, _)| self.busy_until.map_or(arrived, |b| b.max(arrived)));
        [
            self.out.front().map(|&(t, _)| t),
            self.moving.map(|m| m.0),
            next_command,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
