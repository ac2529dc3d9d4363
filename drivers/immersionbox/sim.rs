//! A simulated Immersion Interface Box: the device end of its serial line, for tests and for
//! a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * Waiting for a session, it echoes `IMMC` (after [`SimConfig::reply_delay`]); then answers
//!   `BEGIN` with `IBOX`; in a session it answers each identification command `C8`…`CE` with
//!   the command and a NUL-terminated text ([`IDENT`]), and the 25-byte configuration command
//!   with its first byte, `CF`, after which it streams records at the period the command
//!   asked for. `E` ends the session (and the stream). Everything received is kept
//!   ([`IboxSim::heard`]).
//! * Record `k` (counted over the simulator's life) carries the button byte
//!   [`buttons(k)`](buttons), a Gray code (one button changes per record), then analog and
//!   encoder bytes as long as the configuration asks.
//! * [`expected_changes`] gives the button changes a client must receive, computed here
//!   independently of the driver.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] every record is logged
//!   with the time its first byte left. [`IboxSim::mute`] cuts it off (it hears and answers
//!   nothing; records made meanwhile are lost and not logged).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `immersionbox`.
pub static SIMULATOR: Simulator = Simulator {
    name: "immersionbox",
    about: "Immersion Interface Box: answers the handshake and identification, then streams known button states",
    baud: 38400,
    line: "vrpn_ImmersionBox ibox {PATH} {BAUD} 4 0 0",
    make: |baud| Box::new(IboxSim::new(SimConfig::new(baud))),
};

/// The identification texts, for commands `C8` to `CE`.
pub const IDENT: [&str; 7] = [
    "IBOX-SIM",
    "1234",
    "IIB",
    "S/N 42",
    "simulated box",
    "default.prm",
    "1.07",
];

/// How the simulated box behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// Log every record sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A box at `baud`, answering after 1 ms.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            reply_delay: Duration::from_millis(1),
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// Record `k`'s button byte: the 7-bit Gray code of `k`, so each record changes one button.
pub fn buttons(k: u64) -> u8 {
    ((k ^ (k >> 1)) & 0x7F) as u8
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sent {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// Its number.
    pub k: u64,
    /// Its button byte.
    pub buttons: u8,
}

/// The button changes (record index in `log`, button, pressed) a client reading `n` buttons
/// must receive, from button byte `initial` on: bit *i* of a record's button byte is button
/// *i*.
pub fn expected_changes(log: &[Sent], n: usize, initial: u8) -> Vec<(usize, usize, bool)> {
    let mut state = initial;
    let mut out = Vec::new();
    for (i, s) in log.iter().enumerate() {
        for b in 0..n {
            let now = s.buttons >> b & 1 == 1;
            if now != (state >> b & 1 == 1) {
                out.push((i, b, now));
            }
        }
        state = s.buttons;
    }
    out
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Waiting,
    Synced,
    Session,
    Streaming,
}

/// The simulated box. See the module documentation.
pub struct IboxSim {
    cfg: SimConfig,
    mode: Mode,
    matched: usize,
    command: Vec<u8>,
    config: u8,
    period: Duration,
    next_record: Option<Instant>,
    count: u64,
    pending: VecDeque<(Instant, Vec<u8>)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    /// Cut off while true: hears nothing, answers nothing; records made meanwhile are lost
    /// and not logged.
    pub mute: bool,
    sent: Vec<Sent>,
    heard: Vec<u8>,
}

impl IboxSim {
    /// A box waiting for a session.
    pub fn new(cfg: SimConfig) -> IboxSim {
        IboxSim {
            cfg,
            mode: Mode::Waiting,
            matched: 0,
            command: Vec::new(),
            config: 0,
            period: Duration::from_millis(10),
            next_record: None,
            count: 0,
            pending: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            mute: false,
            sent: Vec::new(),
            heard: Vec::new(),
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

    /// Everything the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// True while records stream.
    pub fn is_streaming(&self) -> bool {
        self.mode == Mode::Streaming
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

    fn answer(&mut self, bytes: Vec<u8>, now: Instant) {
        if !self.mute {
            self.pending.push_back((now + self.cfg.reply_delay, bytes));
        }
    }

    fn record_len(&self) -> usize {
        let analog = [0, 3, 5, 9][usize::from((self.config >> 2) & 3)];
        let encoders = [0, 4, 8, 12][usize::from(self.config & 3)];
        2 + analog + encoders
    }

    fn make_record(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        if self.mute {
            return;
        }
        let mut bytes = vec![0u8; self.record_len()];
        bytes[0] = self.config | 0x80;
        bytes[1] = buttons(k);
        for (i, b) in bytes.iter_mut().enumerate().skip(2) {
            *b = ((k + i as u64) % 128) as u8;
        }
        let first = self.queue(&bytes, at);
        if self.cfg.keep_log {
            self.sent.push(Sent {
                first_byte: first,
                k,
                buttons: bytes[1],
            });
        }
    }

    fn byte(&mut self, b: u8, now: Instant) {
        let in_session = matches!(self.mode, Mode::Session | Mode::Streaming);
        if b == b'E' && in_session && self.command.is_empty() {
            self.mode = Mode::Waiting;
            self.next_record = None;
            self.matched = 0;
            return;
        }
        match self.mode {
            Mode::Waiting | Mode::Synced => {
                let want: &[u8] = if self.mode == Mode::Waiting {
                    b"IMMC"
                } else {
                    b"BEGIN"
                };
                if b == want[self.matched] {
                    self.matched += 1;
                } else {
                    self.matched = usize::from(b == want[0]);
                }
                if self.matched == want.len() {
                    self.matched = 0;
                    if self.mode == Mode::Waiting {
                        self.mode = Mode::Synced;
                        self.answer(b"IMMC".to_vec(), now);
                    } else {
                        self.mode = Mode::Session;
                        self.answer(b"IBOX".to_vec(), now);
                    }
                }
            }
            Mode::Session | Mode::Streaming => {
                if !self.command.is_empty() || b == 0xCF {
                    self.command.push(b);
                    if self.command.len() == 25 {
                        self.config = self.command[3];
                        self.period = Duration::from_millis(u64::from(self.command[2]).max(1));
                        self.command.clear();
                        self.answer(vec![0xCF], now);
                        if !self.mute {
                            self.mode = Mode::Streaming;
                            self.next_record = Some(now + self.cfg.reply_delay + self.period);
                        }
                    }
                } else if (0xC8..=0xCE).contains(&b) {
                    let mut a = vec![b];
                    a.extend_from_slice(IDENT[usize::from(b - 0xC8)].as_bytes());
                    a.push(0);
                    self.answer(a, now);
                }
            }
        }
    }
}

impl DeviceModel for IboxSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        if self.mute {
            // Cut off: the box hears nothing either.
            return;
        }
        for &b in bytes {
            self.byte(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while self.pending.front().is_some_and(|(t, _)| *t <= now.mono) {
            if let Some((t, bytes)) = self.pending.pop_front() {
                self.queue(&bytes, t);
            }
        }
        while let Some(t) = self.next_record.filter(|&t| t <= now.mono) {
            self.make_record(t);
            // A simulator that was not stepped for a while (unplugged) does not catch up, and a
            // record too long for the period delays the next.
            let free = self.line_free.unwrap_or(t);
            self.next_record = Some((t + self.period).max(now.mono).max(free));
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
            self.next_record,
            self.pending.front().map(|(t, _)| *t),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
