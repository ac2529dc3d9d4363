//! A simulated GPS receiver: NMEA 0183 sentences on its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! Every [`SimConfig::period`] (longer where the line is too slow) it sends one epoch: an
//! RMC, a GGA and a GSA sentence, each with its checksum, at the line's baud rate. The GGA of
//! epoch `k` holds [`fix(k)`](fix) (or empty position fields where
//! [`SimConfig::no_fix_every`] says so). Each GGA with a fix is logged ([`GpsSim::sent`])
//! with the values a client must receive, read back from the digits sent, and the time its
//! `$` left. It hears nothing (a receiver has no commands here); RTS is recorded.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `gps`.
pub static SIMULATOR: Simulator = Simulator {
    name: "gps",
    about: "NMEA GPS receiver: RMC, GGA and GSA sentences with known fixes",
    baud: 4800,
    line: "vrpn_Tracker_GPS Gps0 {PATH} {BAUD}",
    make: |baud| Box::new(GpsSim::new(SimConfig::new(baud))),
};

/// How the simulated receiver behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Time between epochs.
    pub period: Duration,
    /// Epoch `k` has no fix when `k % n == n - 1`.
    pub no_fix_every: Option<u64>,
    /// Altitude in feet instead of metres.
    pub feet: bool,
    /// Log every fix sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A receiver at `baud`: 10 epochs a second (fewer where the line is too slow), always a
    /// fix, metres, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(100),
            no_fix_every: None,
            feet: false,
            keep_log: false,
        }
    }

    fn byte_time(&self) -> Duration {
        Duration::from_micros(
            (10_000_000 + u64::from(self.baud.max(1)) / 2) / u64::from(self.baud.max(1)),
        )
    }
}

/// Epoch `k`'s position as sent: latitude `DDMM.MMMM` and hemisphere, longitude
/// `DDDMM.MMMM` and hemisphere, altitude (tenths).
pub fn fix(k: u64) -> (String, char, String, char, String) {
    let lat_min = (k * 1_237) % 600_000;
    let lon_min = (k * 7_919 + 12_345) % 600_000;
    (
        format!(
            "{:02}{:02}.{:04}",
            35 + k % 20,
            lat_min / 10_000,
            lat_min % 10_000
        ),
        if k % 3 == 0 { 'S' } else { 'N' },
        format!(
            "{:03}{:02}.{:04}",
            100 + k % 70,
            lon_min / 10_000,
            lon_min % 10_000
        ),
        if k % 4 == 1 { 'W' } else { 'E' },
        format!("{}.{}", (k * 13) % 4_000, k % 10),
    )
}

/// What a client must receive for a fix as sent: (latitude, longitude, altitude in metres)
/// by NMEA's definition (`DDMM.MMMM` is degrees × 100 plus minutes).
pub fn expected(lat: &str, ns: char, lon: &str, ew: char, alt: &str, feet: bool) -> [f64; 3] {
    let deg = |s: &str| {
        let v: f64 = s.parse().unwrap();
        let whole = (v / 100.0).trunc();
        whole + (v - whole * 100.0) / 60.0
    };
    let sign = |neg: bool| if neg { -1.0 } else { 1.0 };
    let alt: f64 = alt.parse().unwrap();
    [
        sign(ns == 'S') * deg(lat),
        sign(ew == 'W') * deg(lon),
        if feet { alt / 3.280839895013 } else { alt },
    ]
}

/// A fix put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentFix {
    /// When its `$` left the receiver.
    pub first_byte: Instant,
    /// Latitude, longitude (degrees), altitude (metres).
    pub values: [f64; 3],
}

fn sentence(body: &str) -> Vec<u8> {
    let x = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("${body}*{x:02X}\r\n").into_bytes()
}

/// The simulated receiver. See the module documentation.
pub struct GpsSim {
    cfg: SimConfig,
    epoch: u64,
    next: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentFix>,
    rts: Vec<bool>,
}

impl GpsSim {
    /// A receiver behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> GpsSim {
        GpsSim {
            cfg,
            epoch: 0,
            next: None,
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            rts: Vec::new(),
        }
    }

    /// Fixes sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentFix] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// The RTS levels the host set, in order.
    pub fn rts(&self) -> &[bool] {
        &self.rts
    }

    fn queue_at(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let step = self.cfg.byte_time();
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + step * i as u32, b));
        }
        self.line_free = Some(start + step * bytes.len() as u32);
        start
    }

    fn send_epoch(&mut self, at: Instant) {
        let k = self.epoch;
        self.epoch += 1;
        let time = format!("{:02}{:02}{:02}.00", (k / 3600) % 24, (k / 60) % 60, k % 60);
        let has_fix = self.cfg.no_fix_every.map_or(true, |n| k % n != n - 1);
        let (lat, ns, lon, ew, alt) = fix(k);
        let rmc = if has_fix {
            format!("GPRMC,{time},A,{lat},{ns},{lon},{ew},000.5,054.7,191194,020.3,E")
        } else {
            format!("GPRMC,{time},V,,,,,,,191194,,")
        };
        self.queue_at(&sentence(&rmc), at);
        let unit = if self.cfg.feet { 'F' } else { 'M' };
        let gga = if has_fix {
            format!("GPGGA,{time},{lat},{ns},{lon},{ew},1,08,0.9,{alt},{unit},46.9,M,,")
        } else {
            format!("GPGGA,{time},,,,,0,00,,,M,,M,,")
        };
        let first = self.queue_at(&sentence(&gga), at);
        if has_fix && self.cfg.keep_log {
            self.sent.push(SentFix {
                first_byte: first,
                values: expected(&lat, ns, &lon, ew, &alt, self.cfg.feet),
            });
        }
        self.queue_at(&sentence("GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1"), at);
    }

    fn epoch_period(&self) -> Duration {
        // Three sentences of at most 82 bytes, and room to spare.
        self.cfg.period.max(self.cfg.byte_time() * 300)
    }
}

impl DeviceModel for GpsSim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn set_rts(&mut self, on: bool, _now: Now) {
        self.rts.push(on);
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let period = self.epoch_period();
        let next = *self.next.get_or_insert(now.mono);
        if next <= now.mono {
            self.send_epoch(next);
            self.next = Some(next + period);
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
        [self.out.front().map(|&(t, _)| t), self.next]
            .into_iter()
            .flatten()
            .min()
    }
}
