//! A simulated Crossbow RGA300CA: the device's end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! It answers `R` with `H`, `S` with `FF`, its serial number (4 bytes), their sum and `FF`,
//! `v` with its version text and `$`, and `G` with one packet after
//! [`SimConfig::reply_delay`]; `P` stops continuous output, `C` starts it (a packet every
//! [`SimConfig::period`]). Packet `k` (counted over its life) holds [`packet(k)`](packet);
//! with [`SimConfig::keep_log`] each is logged with the values a client must receive,
//! computed from C++ VRPN's formulas independently of the driver, and the time its first
//! byte left. Bytes leave at the line's baud rate. An RTS pulse is counted.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::packet::Packet;
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `crossbow`.
pub static SIMULATOR: Simulator = Simulator {
    name: "crossbow",
    about: "Crossbow RGA300CA: answers the ping, serial and version, then every poll with known angles and accelerations",
    baud: 38400,
    line: "vrpn_Tracker_Crossbow Tracker0 {PATH} {BAUD} 2.0 100",
    make: |baud| Box::new(CrossbowSim::new(SimConfig::new(baud))),
};

/// The serial number it reports.
pub const SERIAL: u32 = 0x0102_03F4;
/// Its version text.
pub const VERSION: &[u8] = b"RGA300CA-200 Rev C";

/// How the simulated device behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// Time between packets in continuous mode.
    pub period: Duration,
    /// In continuous mode when the line opens.
    pub continuous_at_start: bool,
    /// G and angular range the expected values are computed for.
    pub ranges: (f32, f32),
    /// Log every packet sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A device at `baud`, answering after 3 ms, polled, ranges 2 g and 100 °/s, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            reply_delay: Duration::from_millis(3),
            period: Duration::from_millis(10),
            continuous_at_start: false,
            ranges: (2.0, 100.0),
            keep_log: false,
        }
    }
}

/// Packet `k`'s fields.
pub fn packet(k: u64) -> Packet {
    let w = |mul: u64, add: u64| (((k * mul + add) % 65_536) as u16) as i16;
    Packet {
        roll: w(97, 1),
        pitch: w(389, 7_000),
        yaw_rate: w(1_201, 30_000),
        accel: [w(7, 3), w(13, 40_000), w(4_099, 9)],
        rest: [k as u16, 0x0800, 0x0123, 0],
    }
}

/// What a client must receive for `p`: orientation, acceleration (m/s²), rotation of one
/// second at the yaw rate.
pub fn expected(p: &Packet, g: f32, ar: f32) -> ([f64; 4], [f64; 3], [f64; 4]) {
    let deg = std::f64::consts::PI / 180.0;
    let f = |v: i16, scale: f32| f64::from(f32::from(v) * scale / 32768.0);
    let (pitch, roll) = (f(p.pitch, 180.0) * deg, f(p.roll, 180.0) * deg);
    let yaw = f(p.yaw_rate, 1.5 * ar) * deg;
    let quat = [
        (pitch / 2.0).sin() * (roll / 2.0).cos(),
        (pitch / 2.0).cos() * (roll / 2.0).sin(),
        -(pitch / 2.0).sin() * (roll / 2.0).sin(),
        (pitch / 2.0).cos() * (roll / 2.0).cos(),
    ];
    let acc = p.accel.map(|a| f(a, 1.5 * g) * 9.80665);
    (quat, acc, [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()])
}

/// A packet put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentPacket {
    /// When its first byte left.
    pub first_byte: Instant,
    /// Its fields.
    pub packet: Packet,
    /// Orientation, acceleration, velocity rotation a client must receive.
    pub values: ([f64; 4], [f64; 3], [f64; 4]),
}

/// The simulated device. See the module documentation.
pub struct CrossbowSim {
    cfg: SimConfig,
    continuous: bool,
    next_frame: Option<Instant>,
    count: u64,
    pending: Vec<(Instant, Vec<u8>)>,
    packets_due: Vec<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentPacket>,
    commands: Vec<u8>,
    rts_pulses: u32,
    rts: bool,
}

impl CrossbowSim {
    /// A device behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> CrossbowSim {
        CrossbowSim {
            continuous: cfg.continuous_at_start,
            cfg,
            next_frame: None,
            count: 0,
            pending: Vec::new(),
            packets_due: Vec::new(),
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            commands: Vec::new(),
            rts_pulses: 0,
            rts: false,
        }
    }

    /// Packets sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentPacket] {
        &self.sent
    }

    /// Every command byte heard, in order.
    pub fn commands(&self) -> &[u8] {
        &self.commands
    }

    /// RTS pulses seen.
    pub fn rts_pulses(&self) -> u32 {
        self.rts_pulses
    }

    fn byte_time(&self) -> Duration {
        Duration::from_micros(
            (10_000_000 + u64::from(self.cfg.baud.max(1)) / 2) / u64::from(self.cfg.baud.max(1)),
        )
    }

    fn queue_at(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let step = self.byte_time();
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + step * i as u32, b));
        }
        self.line_free = Some(start + step * bytes.len() as u32);
        start
    }

    fn send_packet(&mut self, at: Instant) {
        let p = packet(self.count);
        self.count += 1;
        let first = self.queue_at(&p.encode(), at);
        if self.cfg.keep_log {
            let (g, ar) = self.cfg.ranges;
            self.sent.push(SentPacket {
                first_byte: first,
                packet: p,
                values: expected(&p, g, ar),
            });
        }
    }
}

impl DeviceModel for CrossbowSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        let at = now.mono + self.cfg.reply_delay;
        for &b in bytes {
            self.commands.push(b);
            match b {
                b'R' => self.pending.push((at, b"H".to_vec())),
                b'S' => {
                    let s = SERIAL.to_be_bytes();
                    let sum = s.iter().fold(0u8, |a, &b| a.wrapping_add(b));
                    self.pending
                        .push((at, vec![0xFF, s[0], s[1], s[2], s[3], sum, 0xFF]));
                }
                b'v' => {
                    let mut v = VERSION.to_vec();
                    v.push(b'$');
                    self.pending.push((at, v));
                }
                b'G' => self.packets_due.push(at),
                b'P' => {
                    self.continuous = false;
                    self.next_frame = None;
                }
                b'C' => self.continuous = true,
                _ => {}
            }
        }
    }

    fn set_rts(&mut self, on: bool, _now: Now) {
        if self.rts && !on {
            self.rts_pulses += 1;
        }
        self.rts = on;
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.continuous && self.next_frame.is_none() {
            self.next_frame = Some(now.mono);
        }
        let period = self.cfg.period.max(self.byte_time() * 30);
        while let Some(t) = self
            .next_frame
            .filter(|&t| t <= now.mono && self.continuous)
        {
            self.send_packet(t);
            self.next_frame = Some(t + period);
        }
        let mut due: Vec<(Instant, Option<Vec<u8>>)> = Vec::new();
        self.pending.retain(|(t, b)| {
            let ready = *t <= now.mono;
            if ready {
                due.push((*t, Some(b.clone())));
            }
            !ready
        });
        self.packets_due.retain(|&t| {
            let ready = t <= now.mono;
            if ready {
                due.push((t, None));
            }
            !ready
        });
        due.sort_by_key(|d| d.0);
        for (t, bytes) in due {
            match bytes {
                Some(b) => {
                    self.queue_at(&b, t);
                }
                None => self.send_packet(t),
            }
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
            self.next_frame.filter(|_| self.continuous),
            self.pending.iter().map(|p| p.0).min(),
            self.packets_due.iter().copied().min(),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
