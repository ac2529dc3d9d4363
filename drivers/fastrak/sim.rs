//! A simulated Fastrak / IS-900 in Fastrak-compatible mode: the device end of the serial line.
//!
//! It answers what the driver sends as the tracker does: single-letter commands act at once
//! (`c` / `C` stop / start continuous output, `f` / `F` binary / ASCII output, `S` status,
//! Ctrl-Y reinitialise; CR, `Y`, `t`, `W` are accepted and ignored), and other commands run
//! when their CR arrives (`O<station>,<items>` sets a station's output list, `MZ` zeroes the
//! clock, anything else is accepted and logged in [`FastrakSim::commands`]).
//!
//! In continuous binary mode it sends, every [`SimConfig::cycle`], one record per connected
//! station laid out as that station's output list says (items 0 space, 1 CR LF, 2 position,
//! 4 Euler angles, 11 quaternion, 16 Fastrak stylus, 21 timestamp, 22 IS-900 buttons,
//! 23 joystick). The values are known functions of the station and a per-station record count
//! ([`pose`], [`buttons`], [`stylus`], [`joystick`]) so a test can compute what a client
//! must receive, and every record sent is logged with the time its first byte left the line
//! ([`FastrakSim::log`]).
//!
//! Bytes leave at the configured baud rate in chunks of [`SimConfig::chunk`] bytes, the way a
//! UART FIFO or USB adapter hands them over, so records reach the host in several reads.
//! The model implements only [`DeviceModel`], so it runs on a virtual line or, through an
//! adapter, on a real pseudo-terminal.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::MAX_STATIONS;
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim fastrak PATH`: a Fastrak with four stations.
pub static SIMULATOR: Simulator = Simulator {
    name: "fastrak",
    about: "Polhemus Fastrak (or IS-900 in Fastrak mode): 4 stations of known poses",
    baud: 19200,
    line: "vrpn_Tracker_Fastrak Tracker0 {PATH} {BAUD}",
    make: |baud| Box::new(FastrakSim::new(SimConfig::new(baud))),
};

/// Ctrl-Y: reinitialise.
const CTRL_Y: u8 = 0x19;
/// Records kept in [`FastrakSim::log`].
pub const LOG_CAP: usize = 100_000;
/// Output list after power-on or Ctrl-Y: position, Euler angles, CR LF.
const DEFAULT_LIST: [u8; 3] = [2, 4, 1];
/// Most items in one output list.
const MAX_ITEMS: usize = 16;

/// How the simulated tracker behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Stations with a sensor plugged in (stations 1 to this stream), 1 to 8.
    pub stations: u8,
    /// Time between output cycles (one record per station each); longer when the line is
    /// too slow for it.
    pub cycle: Duration,
    /// Line speed: one byte takes 10 bits.
    pub baud: u32,
    /// Bytes handed to the host at once.
    pub chunk: usize,
    /// Length of the status answer: 55, or 54 for later IS-900 firmware.
    pub status_len: usize,
    /// Delay before a status answer starts.
    pub reply_delay: Duration,
    /// Time Ctrl-Y takes, during which the tracker neither reads nor sends.
    pub reboot_time: Duration,
    /// Status requests left unanswered before the tracker starts answering (to test reset
    /// escalation).
    pub ignore_status: u32,
    /// Status byte of each record (space, or a letter for a warning).
    pub status_byte: u8,
    /// Answer every command other than `O`, `MT`, `MZ`, `e`, `x`, `v` with a line
    /// `2 <command>` CR LF, as a tracker answers queries and reports errors.
    pub echo_commands: bool,
}

impl SimConfig {
    /// Four stations, 60 cycles a second, 8-byte chunks, 55-byte status, 5 ms replies.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            stations: 4,
            cycle: Duration::from_micros(16_667),
            baud,
            chunk: 8,
            status_len: 55,
            reply_delay: Duration::from_millis(5),
            reboot_time: Duration::from_millis(1500),
            ignore_status: 0,
            status_byte: b' ',
            echo_commands: false,
        }
    }
}

/// One record the simulator sent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentRecord {
    /// Station, 1-based.
    pub station: u8,
    /// Per-station record count, the argument of [`pose`] and friends.
    pub seq: u64,
    /// When the chunk holding its first byte left the line.
    pub first_byte_at: Instant,
    /// The timestamp it carried (milliseconds since the last `MZ`, or since power-on).
    pub device_ms: f32,
    /// Whether it was sent in binary mode.
    pub binary: bool,
}

/// Position (inches) and quaternion (w, x, y, z) of record `seq` of `station`: a rotation
/// about the axis (0.6, 0, 0.8) that advances with `seq`, exactly representable inputs aside.
pub fn pose(station: u8, seq: u64) -> ([f32; 3], [f32; 4]) {
    let a = (seq % 10_000) as f32 * 0.01 + f32::from(station);
    let pos = [
        f32::from(station) * 10.0 + a.sin(),
        a.cos() * 5.0,
        (seq % 100) as f32 * 0.25 - 12.0,
    ];
    let (s, c) = (a * 0.5).sin_cos();
    (pos, [c, 0.6 * s, 0.0, 0.8 * s])
}

/// IS-900 button bits (six buttons) of record `seq` of `station`.
pub fn buttons(station: u8, seq: u64) -> u8 {
    ((seq / 4 + u64::from(station)) & 0x3F) as u8
}

/// Fastrak stylus switch of record `seq` of `station`.
pub fn stylus(station: u8, seq: u64) -> bool {
    (seq / 3 + u64::from(station)) % 2 == 1
}

/// Joystick bytes (left/right, up/down) of record `seq` of `station`.
pub fn joystick(station: u8, seq: u64) -> [u8; 2] {
    [
        ((seq * 37 + u64::from(station)) % 256) as u8,
        ((seq * 11 + 64) % 256) as u8,
    ]
}

#[derive(Clone, Copy, Debug)]
struct OutputList {
    items: [u8; MAX_ITEMS],
    len: usize,
}

impl OutputList {
    fn new(items: &[u8]) -> OutputList {
        let mut list = OutputList {
            items: [0; MAX_ITEMS],
            len: items.len().min(MAX_ITEMS),
        };
        list.items[..list.len].copy_from_slice(&items[..list.len]);
        list
    }
}

#[derive(Clone, Copy, Debug)]
struct Mark {
    index: u64,
    station: u8,
    seq: u64,
    device_ms: f32,
    binary: bool,
}

/// The simulated tracker.
#[derive(Debug)]
pub struct FastrakSim {
    cfg: SimConfig,
    byte_time: Duration,
    power_on: Option<Instant>,
    continuous: bool,
    binary: bool,
    lists: [OutputList; MAX_STATIONS],
    rx_line: Vec<u8>,
    tx: VecDeque<u8>,
    /// When the transmitter finished the last chunk (or became busy again).
    tx_clock: Option<Instant>,
    enqueued: u64,
    emitted: u64,
    marks: VecDeque<Mark>,
    next_cycle: Option<Instant>,
    status_due: Option<Instant>,
    reboot_until: Option<Instant>,
    silent: bool,
    resume: bool,
    seq: [u64; MAX_STATIONS],
    clock_zero: Option<Instant>,
    status_requests: u32,
    reboots: u32,
    /// Every CR-terminated command received, in order, without its CR.
    pub commands: Vec<String>,
    /// Every record sent (the last [`LOG_CAP`]).
    pub log: VecDeque<SentRecord>,
    /// Device times sent instead of the clock's, one per record, in order (for tests of
    /// IS-900 timestamps that are not times: ±∞, NaN, ±3.4·10³⁸).
    pub hostile_times: VecDeque<f32>,
}

impl FastrakSim {
    /// A tracker just powered on: polled ASCII output, default output lists.
    pub fn new(cfg: SimConfig) -> FastrakSim {
        let byte_time =
            Duration::from_micros((10_000_000 + u64::from(cfg.baud) / 2) / u64::from(cfg.baud));
        FastrakSim {
            cfg,
            byte_time,
            power_on: None,
            continuous: false,
            binary: false,
            lists: [OutputList::new(&DEFAULT_LIST); MAX_STATIONS],
            rx_line: Vec::new(),
            tx: VecDeque::new(),
            tx_clock: None,
            enqueued: 0,
            emitted: 0,
            marks: VecDeque::new(),
            next_cycle: None,
            status_due: None,
            reboot_until: None,
            silent: false,
            resume: false,
            seq: [0; MAX_STATIONS],
            clock_zero: None,
            status_requests: 0,
            reboots: 0,
            commands: Vec::new(),
            log: VecDeque::new(),
            hostile_times: VecDeque::new(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// Makes the tracker hang (true): it neither reads nor sends, and what it would have sent
    /// is lost. When it wakes (false) it carries on in the mode it was in.
    pub fn set_silent(&mut self, silent: bool) {
        if self.silent && !silent {
            self.resume = true;
        }
        self.silent = silent;
    }

    /// True while hung.
    pub fn is_silent(&self) -> bool {
        self.silent
    }

    /// True in continuous binary mode: what the driver must leave it in.
    pub fn is_streaming(&self) -> bool {
        self.continuous && self.binary && self.reboot_until.is_none()
    }

    /// The output list of `station` (1-based) as item numbers.
    pub fn output_list(&self, station: u8) -> &[u8] {
        let l = &self.lists[usize::from(station - 1)];
        &l.items[..l.len]
    }

    /// Status requests received.
    pub fn status_requests(&self) -> u32 {
        self.status_requests
    }

    /// Times Ctrl-Y reinitialised the tracker.
    pub fn reboots(&self) -> u32 {
        self.reboots
    }

    /// When the clock was last zeroed with `MZ`.
    pub fn clock_zero(&self) -> Option<Instant> {
        self.clock_zero
    }

    fn reboot(&mut self, now: Instant) {
        self.reboots += 1;
        self.reboot_until = Some(now + self.cfg.reboot_time);
        self.continuous = false;
        self.binary = false;
        self.lists = [OutputList::new(&DEFAULT_LIST); MAX_STATIONS];
        self.drop_output();
        self.next_cycle = None;
        self.rx_line.clear();
        self.clock_zero = None;
        self.power_on = Some(now + self.cfg.reboot_time);
    }

    fn command_byte(&mut self, b: u8, now: Instant) {
        if !self.rx_line.is_empty() {
            if b == b'\r' {
                let line = std::mem::take(&mut self.rx_line);
                self.run_line(&line, now);
            } else {
                self.rx_line.push(b);
            }
            return;
        }
        match b {
            b'c' => {
                self.continuous = false;
                self.next_cycle = None;
            }
            b'C' => {
                if !self.continuous {
                    self.continuous = true;
                    self.next_cycle = Some(now + self.cfg.cycle);
                }
            }
            b'f' => self.binary = true,
            b'F' => self.binary = false,
            b'S' => {
                self.status_requests += 1;
                if self.status_requests > self.cfg.ignore_status {
                    self.status_due = Some(now + self.cfg.reply_delay);
                }
            }
            CTRL_Y => self.reboot(now),
            b'\r' | b'\n' | b'Y' | b't' | b'W' | 0x0B => {}
            _ => self.rx_line.push(b),
        }
    }

    fn run_line(&mut self, line: &[u8], now: Instant) {
        self.commands
            .push(String::from_utf8_lossy(line).into_owned());
        if line == b"MZ" {
            self.clock_zero = Some(now);
        } else if let Some(rest) = line.strip_prefix(b"O") {
            let text = String::from_utf8_lossy(rest);
            let mut fields = text.split(',').map(str::trim);
            let station = fields.next().and_then(|s| s.parse::<usize>().ok());
            let items: Option<Vec<u8>> = fields.map(|f| f.parse::<u8>().ok()).collect();
            if let (Some(s @ 1..=MAX_STATIONS), Some(items)) = (station, items) {
                self.lists[s - 1] = OutputList::new(&items);
            }
        } else if self.cfg.echo_commands
            && line != b"MT"
            && !matches!(line.first(), Some(b'e' | b'x' | b'v'))
        {
            let mut reply = b"2 ".to_vec();
            reply.extend_from_slice(line);
            reply.extend_from_slice(b"\r\n");
            self.enqueue(&reply, now + self.cfg.reply_delay);
        }
    }

    /// Loses everything not yet sent.
    fn drop_output(&mut self) {
        self.tx.clear();
        self.marks.clear();
        self.emitted = self.enqueued;
        self.status_due = None;
    }

    fn enqueue(&mut self, bytes: &[u8], at: Instant) {
        if self.tx.is_empty() {
            self.tx_clock = Some(self.tx_clock.map_or(at, |c| c.max(at)));
        }
        self.tx.extend(bytes.iter().copied());
        self.enqueued += bytes.len() as u64;
    }

    /// When everything queued will have left the line.
    fn tx_done(&self) -> Option<Instant> {
        let clock = self.tx_clock?;
        let queued = self.tx.len() as u32;
        (queued > 0).then(|| clock + self.byte_time * queued)
    }

    fn status_answer(&mut self, at: Instant) {
        let len = self.cfg.status_len.max(5);
        let mut s = b"21S".to_vec();
        let filler = b"  0.000 1 2 3 4 5 6 7 8 9 ";
        while s.len() < len - 2 {
            s.push(filler[s.len() % filler.len()]);
        }
        s.extend_from_slice(b"\r\n");
        self.enqueue(&s, at);
    }

    fn device_ms(&self, at: Instant) -> f32 {
        let zero = self.clock_zero.or(self.power_on).unwrap_or(at);
        (at.saturating_duration_since(zero).as_secs_f64() * 1000.0) as f32
    }

    fn cycle(&mut self, at: Instant) {
        let mut rec = Vec::with_capacity(64);
        for station in 1..=self.cfg.stations.min(MAX_STATIONS as u8) {
            let i = usize::from(station - 1);
            let seq = self.seq[i];
            self.seq[i] += 1;
            let device_ms = match self.hostile_times.front() {
                Some(_)
                    if self.binary && self.lists[i].items[..self.lists[i].len].contains(&21) =>
                {
                    self.hostile_times.pop_front().unwrap_or_default()
                }
                _ => self.device_ms(at),
            };
            rec.clear();
            rec.extend_from_slice(&[b'0', b'0' + station, self.cfg.status_byte]);
            let list = self.lists[i];
            let (pos, quat) = pose(station, seq);
            for &item in &list.items[..list.len] {
                if self.binary {
                    let mut floats = |v: &[f32]| {
                        for x in v {
                            rec.extend_from_slice(&x.to_le_bytes());
                        }
                    };
                    match item {
                        0 => rec.push(b' '),
                        1 => rec.extend_from_slice(b"\r\n"),
                        2 => floats(&pos),
                        4 => floats(&[0.0; 3]),
                        11 => floats(&quat),
                        16 => rec.extend_from_slice(&[b' ', b'0' + u8::from(stylus(station, seq))]),
                        21 => floats(&[device_ms]),
                        22 => rec.push(buttons(station, seq)),
                        23 => rec.extend_from_slice(&joystick(station, seq)),
                        _ => {}
                    }
                } else {
                    let text = match item {
                        0 => " ".to_owned(),
                        1 => "\r\n".to_owned(),
                        2 => format!("{:7.2}{:7.2}{:7.2}", pos[0], pos[1], pos[2]),
                        11 => format!(
                            "{:8.4}{:8.4}{:8.4}{:8.4}",
                            quat[0], quat[1], quat[2], quat[3]
                        ),
                        _ => format!("{:7.2}{:7.2}{:7.2}", 0.0, 0.0, 0.0),
                    };
                    rec.extend_from_slice(text.as_bytes());
                }
            }
            self.marks.push_back(Mark {
                index: self.enqueued,
                station,
                seq,
                device_ms,
                binary: self.binary,
            });
            self.enqueue(&rec, at);
        }
    }

    fn release(&mut self, now: Instant, out: &mut Vec<u8>) {
        while !self.tx.is_empty() {
            let n = self.cfg.chunk.max(1).min(self.tx.len());
            let clock = self.tx_clock.unwrap_or(now);
            let done = clock + self.byte_time * n as u32;
            if done > now {
                return;
            }
            out.extend(self.tx.drain(..n));
            self.emitted += n as u64;
            self.tx_clock = Some(done);
            while self.marks.front().is_some_and(|m| m.index < self.emitted) {
                let m = self.marks.pop_front().expect("checked");
                if self.log.len() == LOG_CAP {
                    self.log.pop_front();
                }
                self.log.push_back(SentRecord {
                    station: m.station,
                    seq: m.seq,
                    first_byte_at: done,
                    device_ms: m.device_ms,
                    binary: m.binary,
                });
            }
        }
    }
}

impl DeviceModel for FastrakSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.power_on.get_or_insert(now.mono);
        if self.silent || self.reboot_until.is_some_and(|t| now.mono < t) {
            return;
        }
        for &b in bytes {
            if self.reboot_until.is_some_and(|t| now.mono < t) {
                break;
            }
            self.command_byte(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let now = now.mono;
        self.power_on.get_or_insert(now);
        if self.silent {
            self.drop_output();
            return;
        }
        if let Some(t) = self.reboot_until {
            if now < t {
                return;
            }
            self.reboot_until = None;
        }
        if std::mem::take(&mut self.resume) && self.continuous {
            self.next_cycle = Some(now);
        }
        if let Some(t) = self.status_due.filter(|&t| t <= now) {
            self.status_due = None;
            self.status_answer(t);
        }
        while let Some(t) = self.next_cycle.filter(|&t| t <= now && self.continuous) {
            self.cycle(t);
            let busy = self.tx_done().unwrap_or(t);
            self.next_cycle = Some((t + self.cfg.cycle).max(busy));
        }
        self.release(now, out);
    }

    fn next_deadline(&self) -> Option<Instant> {
        if self.silent {
            return None;
        }
        if self.reboot_until.is_some() {
            return self.reboot_until;
        }
        let chunk = self
            .tx_clock
            .filter(|_| !self.tx.is_empty())
            .map(|c| c + self.byte_time * self.cfg.chunk.max(1).min(self.tx.len()) as u32);
        [
            self.next_cycle.filter(|_| self.continuous),
            self.status_due,
            chunk,
        ]
        .into_iter()
        .flatten()
        .min()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;

    fn now(base: Instant, us: u64) -> Now {
        Now {
            mono: base + Duration::from_micros(us),
            wall: TimeVal::new(0, us as i64),
        }
    }

    #[test]
    fn answers_status_and_streams_its_output_lists() {
        let base = Instant::now();
        let mut cfg = SimConfig::new(115_200);
        cfg.stations = 2;
        let mut sim = FastrakSim::new(cfg);
        sim.receive(b"S", now(base, 0));
        let mut out = Vec::new();
        sim.transmit(now(base, 100_000), &mut out);
        assert_eq!(out.len(), 55);
        assert!(out.starts_with(b"21S") && out.ends_with(b"\r\n"));
        out.clear();
        sim.receive(b"O1,2,11,22,0\rO2,2,11,0\rfC", now(base, 100_000));
        assert_eq!(sim.output_list(1), &[2, 11, 22, 0]);
        assert!(sim.is_streaming());
        sim.transmit(now(base, 130_000), &mut out);
        // One cycle at 116.667 ms: 33 + 32 bytes at 87 µs each, gone by 130 ms.
        assert_eq!(out.len(), 65);
        assert_eq!(&out[..3], b"01 ");
        assert_eq!(out[31], buttons(1, 0));
        assert_eq!(&out[33..36], b"02 ");
        assert_eq!(sim.log.len(), 2);
        assert_eq!(sim.commands, vec!["O1,2,11,22,0", "O2,2,11,0"]);
    }

    #[test]
    fn ctrl_y_reboots_into_polled_ascii_mode() {
        let base = Instant::now();
        let mut sim = FastrakSim::new(SimConfig::new(9600));
        sim.receive(b"fC\x19S", now(base, 0));
        assert!(!sim.is_streaming());
        assert_eq!(sim.reboots(), 1);
        // The S sent during the reboot is lost.
        assert_eq!(sim.status_requests(), 0);
        let mut out = Vec::new();
        sim.transmit(now(base, 2_000_000), &mut out);
        assert!(out.is_empty());
    }
}
