//! The Crossbow RGA300CA data packet: 24 bytes, big-endian, found byte by byte
//! ([`Framer`]) and decoded into C++ VRPN's report values ([`Packet::report`]). Pure.
//!
//! | bytes | field |
//! |---|---|
//! | 0–1 | header `AA 55` |
//! | 2–3, 4–5 | roll, pitch angle (i16, × 180° / 2¹⁵) |
//! | 6–7 | yaw rate (i16, × 1.5 × angular range / 2¹⁵, °/s) |
//! | 8–13 | acceleration x, y, z (i16, × 1.5 × G range / 2¹⁵, g) |
//! | 14–15, 16–17, 18–19, 20–21 | timer, temperature voltage, part number, status |
//! | 22–23 | checksum: the sum of bytes 2 to 21 (u16) |

use crate::time::Now;

/// Bytes of a packet.
pub const PACKET_LEN: usize = 24;
/// Its first two bytes.
pub const HEADER: [u8; 2] = [0xAA, 0x55];
/// Metres per second² per g (C++'s constant).
pub const MPSS_PER_G: f64 = 9.80665;

/// A packet's fields.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Packet {
    /// Roll angle, raw.
    pub roll: i16,
    /// Pitch angle, raw.
    pub pitch: i16,
    /// Yaw rate, raw.
    pub yaw_rate: i16,
    /// Acceleration x, y, z, raw.
    pub accel: [i16; 3],
    /// Timer, temperature voltage, part number, status.
    pub rest: [u16; 4],
}

/// The sum the checksum holds.
pub fn checksum(bytes: &[u8]) -> u16 {
    bytes[2..22]
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)))
}

/// The values sent for a packet: orientation, angular velocity and linear acceleration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Report {
    /// Orientation from pitch and roll (no yaw), x, y, z, w.
    pub quat: [f64; 4],
    /// The rotation in one second at the yaw rate, x, y, z, w.
    pub vel_quat: [f64; 4],
    /// m/s².
    pub acc: [f64; 3],
}

/// C++'s scaling, in single precision as C++ computes it.
fn scaled(v: i16, scale: f32) -> f32 {
    f32::from(v) * scale / 32768.0
}

impl Packet {
    /// Decodes a packet whose header and checksum were checked.
    pub fn decode(b: &[u8; PACKET_LEN]) -> Packet {
        let i = |k: usize| i16::from_be_bytes([b[k], b[k + 1]]);
        let u = |k: usize| u16::from_be_bytes([b[k], b[k + 1]]);
        Packet {
            roll: i(2),
            pitch: i(4),
            yaw_rate: i(6),
            accel: [i(8), i(10), i(12)],
            rest: [u(14), u(16), u(18), u(20)],
        }
    }

    /// Encodes it with header and checksum (for the simulator and tests).
    pub fn encode(&self) -> [u8; PACKET_LEN] {
        let mut b = [0u8; PACKET_LEN];
        b[..2].copy_from_slice(&HEADER);
        let words = [
            self.roll as u16,
            self.pitch as u16,
            self.yaw_rate as u16,
            self.accel[0] as u16,
            self.accel[1] as u16,
            self.accel[2] as u16,
            self.rest[0],
            self.rest[1],
            self.rest[2],
            self.rest[3],
        ];
        for (k, w) in words.iter().enumerate() {
            b[2 + 2 * k..4 + 2 * k].copy_from_slice(&w.to_be_bytes());
        }
        let sum = checksum(&b);
        b[22..].copy_from_slice(&sum.to_be_bytes());
        b
    }

    /// What C++ VRPN reports for it, with the line's G range and angular range.
    pub fn report(&self, g_range: f32, ar_range: f32) -> Report {
        let rad = std::f64::consts::PI / 180.0;
        let pitch = f64::from(scaled(self.pitch, 180.0)) * rad;
        let roll = f64::from(scaled(self.roll, 180.0)) * rad;
        let (sp, cp) = (pitch / 2.0).sin_cos();
        let (sr, cr) = (roll / 2.0).sin_cos();
        let yaw = f64::from(scaled(self.yaw_rate, 1.5 * ar_range)) * rad;
        let (sy, cy) = (yaw / 2.0).sin_cos();
        Report {
            quat: [sp * cr, cp * sr, -sp * sr, cp * cr],
            vel_quat: [0.0, 0.0, sy, cy],
            acc: self
                .accel
                .map(|a| f64::from(scaled(a, 1.5 * g_range)) * MPSS_PER_G),
        }
    }
}

/// A packet found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// Its fields.
    pub packet: Packet,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped since the previous packet.
    pub skipped: u32,
}

/// Finds packets byte by byte: a candidate whose checksum fails gives up only its first
/// byte, and the bytes after it are searched again (C++ VRPN flushes its input instead).
pub struct Framer {
    buf: [u8; PACKET_LEN],
    times: [Option<Now>; PACKET_LEN],
    len: usize,
    skipped: u32,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer {
            buf: [0; PACKET_LEN],
            times: [None; PACKET_LEN],
            len: 0,
            skipped: 0,
        }
    }

    /// Forgets a partial packet.
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
    }

    fn valid_prefix(&self) -> bool {
        match self.len {
            0 => true,
            1 => self.buf[0] == HEADER[0],
            _ => self.buf[..2] == HEADER,
        }
    }

    fn give_up_first(&mut self) {
        let next = (1..self.len)
            .find(|&i| self.buf[i] == HEADER[0])
            .unwrap_or(self.len);
        self.skipped += next as u32;
        self.buf.copy_within(next..self.len, 0);
        self.times.copy_within(next..self.len, 0);
        self.len -= next;
    }

    /// Takes one byte that arrived at `arrived`; returns a packet when this byte completes
    /// one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        loop {
            if !self.valid_prefix() {
                self.give_up_first();
                continue;
            }
            if self.len < PACKET_LEN {
                return None;
            }
            let sum = u16::from_be_bytes([self.buf[22], self.buf[23]]);
            if sum != checksum(&self.buf) {
                self.give_up_first();
                continue;
            }
            self.len = 0;
            return Some(Framed {
                packet: Packet::decode(&self.buf),
                first_byte: self.times[0].unwrap_or(arrived),
                skipped: std::mem::take(&mut self.skipped),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    #[test]
    fn packets_round_trip_and_are_found_after_garbage() {
        let p = Packet {
            roll: -16384,
            pitch: 8192,
            yaw_rate: 1000,
            accel: [100, -200, 21845],
            rest: [1, 2, 3, 4],
        };
        let bytes = p.encode();
        assert_eq!(Packet::decode(&bytes), p);
        let base = Instant::now();
        let at = |ms: u64| Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(1, 0).plus(Duration::from_millis(ms)),
        };
        let mut f = Framer::new();
        let mut got = Vec::new();
        let mut broken = bytes;
        broken[23] ^= 1;
        for (chunk, ms) in [
            (&[0xAA, 0xAA, 0x01][..], 0),
            (&broken[..], 1),
            (&bytes[..], 2),
        ] {
            for &b in chunk {
                got.extend(f.push(b, at(ms)));
            }
        }
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].packet, p);
        assert_eq!(got[0].first_byte, at(2));
        assert_eq!(got[0].skipped, 3 + 24);
        // Roll -90°, pitch 45°; acceleration in m/s² at ±2 g, yaw rate at 100 °/s.
        let r = p.report(2.0, 100.0);
        let (sp, cp) = (std::f64::consts::PI / 8.0).sin_cos();
        let (sr, cr) = (-std::f64::consts::PI / 4.0).sin_cos();
        let want = [sp * cr, cp * sr, -sp * sr, cp * cr];
        assert!(r.quat.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
        assert_eq!(r.acc[2], f64::from(21845.0f32 * 3.0 / 32768.0) * MPSS_PER_G);
    }
}
