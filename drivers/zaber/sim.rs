//! A simulated chain of Zaber positioners: the device end of the serial line, for tests and
//! for a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * Renumbering (`[0, 2, …]`): device `i` answers `[i, 2, i, 0, 0, 0]`, one after another.
//! * Position (23), mode (40), speed (41) and acceleration (42) to device `i` are answered at
//!   once (23 with the position, the others echoed); a move (20) is answered with the target
//!   when the move is done, after [`SimConfig::move_time`] plus one millisecond per 1000
//!   microsteps. Commands to devices that are not in the chain get no answer.
//! * Every byte received is kept ([`ZaberSim::heard`]); bytes leave at the line's baud rate.
//! * With [`SimConfig::keep_log`], each move answer that changes what the host knows of the
//!   positions is logged with the time its first byte left and every device's position
//!   ([`ZaberSim::sent`]), computed here independently of the driver.
//! * Faults: [`ZaberSim::inject`] puts bytes on the line, [`ZaberSim::mute`] silences the chain
//!   (it still moves).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `zaber`.
pub static SIMULATOR: Simulator = Simulator {
    name: "zaber",
    about: "Two Zaber linear stages: answer renumbering and position requests, and move when told",
    baud: 9600,
    line: "vrpn_Zaber Zaber0 {PATH}",
    make: |_| Box::new(ZaberSim::new(SimConfig::new(2))),
};

/// How the simulated chain behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Devices in the chain.
    pub devices: usize,
    /// Each device's position at power-on.
    pub start: Vec<i32>,
    /// Shortest move.
    pub move_time: Duration,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// Log every move answer.
    pub keep_log: bool,
}

impl SimConfig {
    /// `devices` devices at positions 1000, 2000, …; moves take 20 ms or more; answers after
    /// 1 ms; no log.
    pub fn new(devices: usize) -> SimConfig {
        SimConfig {
            devices,
            start: (1..=devices as i32).map(|i| i * 1000).collect(),
            move_time: Duration::from_millis(20),
            reply_delay: Duration::from_millis(1),
            keep_log: false,
        }
    }
}

/// The line speed.
const BAUD: u32 = super::config::BAUD;

fn byte_offset(i: usize) -> Duration {
    Duration::from_micros((i as f64 * 10e6 / f64::from(BAUD)).round() as u64)
}

/// A move answer put on the line.
#[derive(Clone, Debug, PartialEq)]
pub struct SentMove {
    /// When its first byte left the chain.
    pub first_byte: Instant,
    /// The channels a client must receive: every device's position as the host knows it.
    pub channels: Vec<f64>,
}

/// The simulated chain. See the module documentation.
pub struct ZaberSim {
    cfg: SimConfig,
    positions: Vec<i32>,
    /// What the host was told last of each position.
    told: Vec<i32>,
    moves: Vec<Option<(Instant, i32)>>,
    command: Vec<u8>,
    answers: VecDeque<(Instant, [u8; 6])>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentMove>,
    heard: Vec<u8>,
    /// Sends nothing while true.
    pub mute: bool,
}

impl ZaberSim {
    /// A chain behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> ZaberSim {
        let n = cfg.devices;
        let mut positions = cfg.start.clone();
        positions.resize(n, 0);
        ZaberSim {
            cfg,
            positions,
            told: vec![0; n],
            moves: vec![None; n],
            command: Vec::new(),
            answers: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            heard: Vec::new(),
            mute: false,
        }
    }

    /// Move answers logged (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentMove] {
        &self.sent
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// Each device's position.
    pub fn positions(&self) -> &[i32] {
        &self.positions
    }

    /// Puts `bytes` on the line at `now`, after what is queued.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue(bytes, now);
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + byte_offset(i), b));
        }
        self.line_free = Some(start + byte_offset(bytes.len()));
        start
    }

    fn answer(&mut self, at: Instant, device: u8, cmd: u8, data: i32) {
        let d = data.to_le_bytes();
        self.answers
            .push_back((at, [device, cmd, d[0], d[1], d[2], d[3]]));
    }

    fn command(&mut self, c: [u8; 6], now: Instant) {
        let data = i32::from_le_bytes([c[2], c[3], c[4], c[5]]);
        let at = now + self.cfg.reply_delay;
        if c[0] == 0 && c[1] == 2 {
            for i in 1..=self.cfg.devices {
                self.answer(at + self.cfg.reply_delay * i as u32, i as u8, 2, i as i32);
            }
            return;
        }
        let Some(i) = usize::from(c[0])
            .checked_sub(1)
            .filter(|&i| i < self.cfg.devices)
        else {
            return;
        };
        match c[1] {
            23 => self.answer(at, c[0], 23, self.positions[i]),
            40..=42 => self.answer(at, c[0], c[1], data),
            20 => {
                let steps = (i64::from(data) - i64::from(self.positions[i])).unsigned_abs();
                let t = now + self.cfg.move_time + Duration::from_micros(steps);
                self.moves[i] = Some((t, data));
            }
            _ => {}
        }
    }
}

impl DeviceModel for ZaberSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        for &b in bytes {
            self.command.push(b);
            if self.command.len() == 6 {
                let c = [
                    self.command[0],
                    self.command[1],
                    self.command[2],
                    self.command[3],
                    self.command[4],
                    self.command[5],
                ];
                self.command.clear();
                self.command(c, now.mono);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        for i in 0..self.cfg.devices {
            if let Some((t, target)) = self.moves[i].filter(|&(t, _)| t <= now.mono) {
                self.moves[i] = None;
                self.positions[i] = target;
                self.answer(t, i as u8 + 1, 20, target);
            }
        }
        let (mut due, rest): (Vec<_>, Vec<_>) =
            self.answers.drain(..).partition(|&(t, _)| t <= now.mono);
        self.answers.extend(rest);
        due.sort_by_key(|&(t, _)| t);
        for (t, a) in due {
            let first = self.queue(&a, t);
            if self.mute || !matches!(a[1], 1 | 10 | 20 | 23) {
                continue;
            }
            let i = usize::from(a[0]) - 1;
            let pos = i32::from_le_bytes([a[2], a[3], a[4], a[5]]);
            let changed = self.told[i] != pos;
            self.told[i] = pos;
            if changed && a[1] == 20 && self.cfg.keep_log {
                let channels = self.told.iter().map(|&p| f64::from(p)).collect();
                self.sent.push(SentMove {
                    first_byte: first,
                    channels,
                });
            }
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
        let moves = self.moves.iter().flatten().map(|&(t, _)| t).min();
        let answers = self.answers.iter().map(|&(t, _)| t).min();
        [self.out.front().map(|&(t, _)| t), moves, answers]
            .into_iter()
            .flatten()
            .min()
    }
}
