//! A simulated Logitech 3D mouse control unit: the device's end of its serial line, for tests
//! and for a simulator on a pseudo-terminal.
//!
//! What it does:
//!
//! * `*R` restarts it: for [`SimConfig::reboot_time`] it hears nothing and sends nothing
//!   (what was queued is lost).
//! * `*` 05 is answered with the diagnostics [`SimConfig::diagnostics`] (`BF 3F`: every test
//!   passed) after [`SimConfig::reply_delay`].
//! * `2A 24 02 07 n` sets the filter count (kept: [`ThreeDMouseSim::filter_count`]).
//! * `*d` is answered with one record after [`SimConfig::reply_delay`] (each request is
//!   answered, in order); record `k` (counted over the simulator's life) holds
//!   [`sample(k)`](sample), and [`Sample::pose`] and [`Sample::buttons`] are what a VRPN
//!   client must receive for it, computed here from the record's definition, independently of
//!   the driver. With [`SimConfig::answers`] false, requests go unanswered.
//! * Bytes leave at the line's baud rate; with [`SimConfig::keep_log`] each record is logged
//!   with the time its first byte left ([`ThreeDMouseSim::sent`]).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{Record, BUTTONS, FRINGE, OUT_OF_RANGE, RECORD_LEN};
use super::reset::{ALL_PASSED, FILTER_PREFIX};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `threedmouse`.
pub static SIMULATOR: Simulator = Simulator {
    name: "threedmouse",
    about: "Logitech 3D mouse: answers the reset and diagnostics, then each request with a known record",
    baud: 19200,
    line: "vrpn_Tracker_3DMouse Tracker0 {PATH} {BAUD}",
    make: |baud| Box::new(ThreeDMouseSim::new(SimConfig::new(baud))),
};

/// How the simulated control unit behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time from a request to its answer.
    pub reply_delay: Duration,
    /// Time `*R` takes.
    pub reboot_time: Duration,
    /// The diagnostics answer.
    pub diagnostics: [u8; 2],
    /// Answers requests for records.
    pub answers: bool,
    /// Log every record sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A control unit at `baud`: answers after 3 ms, restarts in 50 ms, passes its tests,
    /// no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            reply_delay: Duration::from_millis(3),
            reboot_time: Duration::from_millis(50),
            diagnostics: ALL_PASSED,
            answers: true,
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The contents of one record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// The first byte's flags and buttons (without the top bit).
    pub status: u8,
    /// x, y, z in 1/1000 inch.
    pub counts: [i32; 3],
    /// Pitch, yaw, roll in 1/40 degree.
    pub angles: [u16; 3],
}

/// What a client must receive of a pose: sensor, position, quaternion (x, y, z, w).
pub type Pose = (usize, [f64; 3], [f64; 4]);

impl Sample {
    /// The record as it goes on the line.
    pub fn bytes(&self) -> [u8; RECORD_LEN] {
        Record {
            status: self.status,
            counts: self.counts,
            angles: self.angles,
        }
        .encode()
    }

    /// The pose a client must receive, none when out of range.
    ///
    /// Position: 1/1000 inch = 2.54e-5 m, rounded to single precision (as C++ VRPN does);
    /// VRPN's x, y, z are the device's x, −z, y. Orientation: the rotation by yaw about z,
    /// then by 360° − roll about y, then by pitch about x (angles in 1/40 degree).
    pub fn pose(&self) -> Option<Pose> {
        if self.status & OUT_OF_RANGE != 0 {
            return None;
        }
        let metres = |c: i32| f64::from((f64::from(c) / 100_000.0 * 2.54) as f32);
        let [x, y, z] = self.counts;
        let minus_z = -f64::from((f64::from(z as f32 / 100_000.0f32) * 2.54) as f32);
        let pos = [metres(x), minus_z, metres(y)];
        // Half-angle sines and cosines of pitch, yaw and of roll turned round.
        let half = |deg: f64| (deg.to_radians() / 2.0).sin_cos();
        let [p, y, r] = self.angles.map(|a| f64::from(a) / 40.0);
        let (sp, cp) = half(p);
        let (sy, cy) = half(y);
        let (sr, cr) = half(360.0 - r);
        // q = qz(yaw) · qy(roll) · qx(pitch), multiplied out.
        let q = [
            sp * cr * cy - cp * sr * sy,
            cp * sr * cy + sp * cr * sy,
            cp * cr * sy - sp * sr * cy,
            cp * cr * cy + sp * sr * sy,
        ];
        Some((0, pos, q))
    }

    /// The buttons a client must see, in VRPN order (stand, suspend, left, middle, right).
    pub fn buttons(&self) -> [bool; BUTTONS] {
        [0x10, 0x08, 0x04, 0x02, 0x01].map(|bit| self.status & bit != 0)
    }
}

/// Record `k`'s values: positions over the whole 21-bit range (both signs), angles over
/// 0–360°, one button changing every 6 records (a Gray code), the fringe flag now and then,
/// and every 17th record out of range.
pub fn sample(k: u64) -> Sample {
    let count = |mul: u64, add: u64| ((k * mul + add) % (1 << 21)) as i32 - (1 << 20);
    let angle = |mul: u64, add: u64| ((k * mul + add) % 14_400) as u16;
    let n = (k / 6) % 32;
    let mut status = (n ^ (n >> 1)) as u8;
    if k % 11 == 3 {
        status |= FRINGE;
    }
    if k % 17 == 16 {
        status |= OUT_OF_RANGE;
    }
    Sample {
        status,
        counts: [
            count(40_503, 11),
            count(7_919, 1_000_000),
            count(104_729, 5),
        ],
        angles: [angle(97, 0), angle(1_013, 7_000), angle(331, 14_399)],
    }
}

/// A record put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentRecord {
    /// When its first byte left the control unit.
    pub first_byte: Instant,
    /// Its values.
    pub sample: Sample,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Heard {
    /// Waiting for `*` (or the filter command's first byte).
    Start,
    /// After `*`.
    Star,
    /// Inside the filter command: this many of its bytes heard.
    Filter(usize),
}

/// The simulated control unit. See the module documentation.
pub struct ThreeDMouseSim {
    cfg: SimConfig,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    rebooting_until: Option<Instant>,
    parse: Heard,
    count: u64,
    filter: u8,
    resets: usize,
    requests: usize,
    diagnostics_asked: usize,
    heard: Vec<u8>,
    sent: Vec<SentRecord>,
}

impl ThreeDMouseSim {
    /// A control unit behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> ThreeDMouseSim {
        ThreeDMouseSim {
            cfg,
            out: VecDeque::new(),
            line_free: None,
            rebooting_until: None,
            parse: Heard::Start,
            count: 0,
            filter: 1,
            resets: 0,
            requests: 0,
            diagnostics_asked: 0,
            heard: Vec::new(),
            sent: Vec::new(),
        }
    }

    /// The configuration, to change it while running.
    pub fn config_mut(&mut self) -> &mut SimConfig {
        &mut self.cfg
    }

    /// Records sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentRecord] {
        &self.sent
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// `*R` heard.
    pub fn resets(&self) -> usize {
        self.resets
    }

    /// `*d` heard (answered or not).
    pub fn requests(&self) -> usize {
        self.requests
    }

    /// `*` 05 heard.
    pub fn diagnostics_asked(&self) -> usize {
        self.diagnostics_asked
    }

    /// True when nothing is queued to send (the line is idle until the next request).
    pub fn is_idle(&self) -> bool {
        self.out.is_empty()
    }

    /// The filter count set (1 until set).
    pub fn filter_count(&self) -> u8 {
        self.filter
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + self.cfg.byte_offset(i), b));
        }
        self.line_free = Some(start + self.cfg.byte_offset(bytes.len()));
        start
    }

    fn command(&mut self, b: u8, now: Instant) {
        let reply_at = now + self.cfg.reply_delay;
        self.parse = match (self.parse, b) {
            (Heard::Star, b'R') => {
                self.resets += 1;
                self.out.clear();
                self.line_free = None;
                self.rebooting_until = Some(now + self.cfg.reboot_time);
                self.filter = 1;
                Heard::Start
            }
            (Heard::Star, 0x05) => {
                self.diagnostics_asked += 1;
                let d = self.cfg.diagnostics;
                self.queue(&d, reply_at);
                Heard::Start
            }
            (Heard::Star, b'd') => {
                self.requests += 1;
                if self.cfg.answers {
                    let s = sample(self.count);
                    self.count += 1;
                    let first = self.queue(&s.bytes(), reply_at);
                    if self.cfg.keep_log {
                        self.sent.push(SentRecord {
                            first_byte: first,
                            sample: s,
                        });
                    }
                }
                Heard::Start
            }
            (Heard::Star, 0x24) => Heard::Filter(2),
            (Heard::Filter(i), b) if i < FILTER_PREFIX.len() => {
                if b == FILTER_PREFIX[i] {
                    Heard::Filter(i + 1)
                } else {
                    Heard::Start
                }
            }
            (Heard::Filter(_), n) => {
                self.filter = n;
                Heard::Start
            }
            (_, b'*') => Heard::Star,
            _ => Heard::Start,
        };
    }
}

impl DeviceModel for ThreeDMouseSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.heard.extend_from_slice(bytes);
        for &b in bytes {
            if self.rebooting_until.is_some_and(|t| now.mono < t) {
                continue;
            }
            self.command(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.rebooting_until.is_some_and(|t| t <= now.mono) {
            self.rebooting_until = None;
            self.parse = Heard::Start;
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
        [self.out.front().map(|&(t, _)| t), self.rebooting_until]
            .into_iter()
            .flatten()
            .min()
    }
}

#[cfg(test)]
mod tests {
    use super::super::record::FLAG;
    use super::*;

    #[test]
    fn samples_cover_the_ranges_and_flags() {
        let s: Vec<Sample> = (0..2000).map(sample).collect();
        assert!(s.iter().any(|x| x.counts[0] < -900_000));
        assert!(s.iter().any(|x| x.counts[2] > 900_000));
        assert!(s.iter().all(|x| x.angles.iter().all(|&a| a < 14_400)));
        assert!(s.iter().any(|x| x.status & OUT_OF_RANGE != 0));
        assert!(s.iter().all(|x| x.status & FLAG == 0));
        assert_eq!(s.iter().filter(|x| x.pose().is_none()).count(), 2000 / 17);
        // One button changes every 6 records.
        for w in s.windows(2) {
            let diff = (w[0].status ^ w[1].status) & 0x1F;
            assert!(diff.count_ones() <= 1);
        }
        assert!(s.iter().any(|x| x.buttons().iter().all(|&b| b)));
    }
}
