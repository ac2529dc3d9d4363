//! A simulated Radamec SPI: the device end of its serial line, for tests and for a simulator
//! on a pseudo-terminal.
//!
//! What it does:
//!
//! * It streams a data block of type [`SimConfig::kind`] every [`SimConfig::period`] from the
//!   moment it is plugged in, whatever it is told (as C++'s comments say the real one does).
//!   Block `k` (counted over the simulator's life) carries [`sample(k)`](sample).
//! * Command blocks (`A4 id what check`) are kept ([`RadamecSim::heard_commands`]); with
//!   [`SimConfig::echo_commands`] each is echoed with the camera's id.
//! * [`Sample::expected`] gives the channels a client must receive for a block, computed here
//!   independently of the driver.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] every block is logged
//!   with the time its first byte left. [`RadamecSim::mute`] makes it silent (its blocks are
//!   lost and not logged); [`RadamecSim::inject`] puts bytes on the line.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::check_byte;
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `radamec`.
pub static SIMULATOR: Simulator = Simulator {
    name: "radamec",
    about:
        "Radamec SPI camera head: answers the camera request, then streams known position blocks",
    baud: 38400,
    line: "vrpn_Radamec_SPI Analog0 {PATH} {BAUD}",
    make: |_| Box::new(RadamecSim::new(SimConfig::new())),
};

/// How the simulated device behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between blocks.
    pub period: Duration,
    /// The data block type streamed: 0xA0, 0xA1, 0xA2 or 0xA6.
    pub kind: u8,
    /// The camera's id.
    pub camera: u8,
    /// Echo command blocks.
    pub echo_commands: bool,
    /// Log every block sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A device at 38400 baud streaming 0xA2 blocks of camera 3 every 20 ms, no echoes.
    pub fn new() -> SimConfig {
        SimConfig {
            baud: 38400,
            period: Duration::from_millis(20),
            kind: 0xA2,
            camera: 3,
            echo_commands: false,
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig::new()
    }
}

/// The raw values of one block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// Pan, tilt, zoom, focus, height (24-bit counts).
    pub counts: [u32; 5],
    /// X and Y: millimetres and fractions (1/65536 mm).
    pub xy: [(u16, u16); 2],
    /// Orientation in hundredths of a degree.
    pub orientation: u16,
}

/// Block `k`'s values: pan within ±100°, tilt within ±50°, every field changing.
pub fn sample(k: u64) -> Sample {
    let c = |mul: u64, add: u64, modulus: u64| ((k * mul + add) % modulus) as u32;
    Sample {
        counts: [
            0x7FFFF + c(977, 0, 180_001) - 90_000,
            0x7FFFF + 45_000 - c(531, 7, 90_001),
            c(4099, 11, 0x100_0000),
            c(8191, 5, 0x100_0000),
            100_000 + c(1, 0, 5000),
        ],
        xy: [
            (1000 + c(7, 0, 3000) as u16, c(3001, 1, 65536) as u16),
            (2000 + c(11, 0, 3000) as u16, c(4001, 2, 65536) as u16),
        ],
        orientation: c(17, 0, 36000) as u16,
    }
}

impl Sample {
    /// The block of type `kind` for camera `camera`, check byte included.
    pub fn block(&self, kind: u8, camera: u8) -> Vec<u8> {
        let mut b = vec![kind, camera];
        let n = match kind {
            0xA0 => 4,
            _ => 5,
        };
        for v in &self.counts[..n] {
            b.extend_from_slice(&v.to_be_bytes()[1..]);
        }
        match kind {
            0xA2 => {
                for (mm, frac) in self.xy {
                    b.extend_from_slice(&frac.to_be_bytes());
                    b.extend_from_slice(&mm.to_be_bytes());
                }
                b.extend_from_slice(&self.orientation.to_be_bytes());
                b.extend_from_slice(&[0, 0]);
            }
            0xA6 => {
                for (mm, _) in self.xy {
                    b.extend_from_slice(&mm.to_be_bytes());
                }
                b.extend_from_slice(&self.orientation.to_be_bytes());
                b.extend_from_slice(&[0, 0]);
            }
            _ => {}
        }
        b.push(check_byte(&b));
        b
    }

    /// The channels a client must receive for a block of type `kind`: pan and tilt in
    /// degrees ((count − 0x7FFFF) / 900), zoom, focus and height as counts, X and Y in
    /// metres (the 0xA6 block has no fractions), orientation in degrees.
    pub fn expected(&self, kind: u8) -> Vec<f64> {
        let deg = |v: u32| (f64::from(v) - 524_287.0) / 900.0;
        let mut out = vec![
            deg(self.counts[0]),
            deg(self.counts[1]),
            f64::from(self.counts[2]),
            f64::from(self.counts[3]),
        ];
        if kind == 0xA0 {
            return out;
        }
        out.push(f64::from(self.counts[4]));
        if kind == 0xA1 {
            return out;
        }
        for (mm, frac) in self.xy {
            let frac = if kind == 0xA2 { frac } else { 0 };
            out.push(0.001 * (f64::from(mm) + f64::from(frac) / 65536.0));
        }
        out.push(0.01 * f64::from(self.orientation));
        out
    }
}

/// A block put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sent {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// Its type.
    pub kind: u8,
    /// Its values.
    pub sample: Sample,
}

impl Sent {
    /// The channels a client must receive for it.
    pub fn expected(&self) -> Vec<f64> {
        self.sample.expected(self.kind)
    }
}

/// The simulated device. See the module documentation.
pub struct RadamecSim {
    cfg: SimConfig,
    next_block: Option<Instant>,
    count: u64,
    command: Vec<u8>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    /// Silent while true: blocks made meanwhile are lost and not logged.
    pub mute: bool,
    sent: Vec<Sent>,
    commands: Vec<[u8; 4]>,
}

impl RadamecSim {
    /// A device behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> RadamecSim {
        RadamecSim {
            cfg,
            next_block: None,
            count: 0,
            command: Vec::new(),
            out: VecDeque::new(),
            line_free: None,
            mute: false,
            sent: Vec::new(),
            commands: Vec::new(),
        }
    }

    /// Blocks sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// The command blocks received (with a right check byte).
    pub fn heard_commands(&self) -> &[[u8; 4]] {
        &self.commands
    }

    /// Streams blocks of type `kind` from now on.
    pub fn set_kind(&mut self, kind: u8) {
        self.cfg.kind = kind;
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

    fn make_block(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        if self.mute {
            return;
        }
        let s = sample(k);
        let first = self.queue(&s.block(self.cfg.kind, self.cfg.camera), at);
        if self.cfg.keep_log {
            self.sent.push(Sent {
                first_byte: first,
                kind: self.cfg.kind,
                sample: s,
            });
        }
    }
}

impl DeviceModel for RadamecSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            if self.command.is_empty() && b != 0xA4 {
                continue;
            }
            self.command.push(b);
            if self.command.len() < 4 {
                continue;
            }
            let c = [
                self.command[0],
                self.command[1],
                self.command[2],
                self.command[3],
            ];
            self.command.clear();
            if c[3] != check_byte(&c[..3]) {
                continue;
            }
            self.commands.push(c);
            if self.cfg.echo_commands && !self.mute {
                let e = [0xA4, self.cfg.camera, c[2]];
                self.queue(&[e[0], e[1], e[2], check_byte(&e)], now.mono);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.next_block.is_none() {
            self.next_block = Some(now.mono + self.cfg.period);
        }
        while let Some(t) = self.next_block.filter(|&t| t <= now.mono) {
            self.make_block(t);
            // A simulator that was not stepped for a while (unplugged) does not catch up.
            self.next_block = Some((t + self.cfg.period).max(now.mono));
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
        [self.out.front().map(|&(t, _)| t), self.next_block]
            .into_iter()
            .flatten()
            .min()
    }
}
