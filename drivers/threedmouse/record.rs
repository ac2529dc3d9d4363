//! The 3D mouse's 16-byte Euler record: finding it in the byte stream ([`Framer`]) and
//! decoding it ([`Record`]). Pure code: no I/O, no clock.
//!
//! ```text
//! byte 0      1 F O S U L M R    flag (always 1), fringe, out of range, then the buttons:
//!                                stand, suspend, left, middle, right
//! bytes 1–3   0 x x x x x x x    x, 21 bits two's complement (bit 6 of byte 1 is the sign),
//! bytes 4–6                      y  } in 1/1000 inch, 7 bits a byte, high byte first
//! bytes 7–9                      z  }
//! bytes 10–11 0 p p p p p p p    pitch, 14 bits, in 1/40 degree
//! bytes 12–13                    yaw
//! bytes 14–15                    roll
//! ```
//!
//! Only the first byte has its top bit set, which is how a record is found after garbage (the
//! device sends no checksum, so bytes that happen to look like a record cannot be told from
//! one).

use crate::time::Now;

/// Bytes in a record.
pub const RECORD_LEN: usize = 16;
/// The top bit: set in a record's first byte, clear in every other.
pub const FLAG: u8 = 0x80;
/// The mouse is near the edge of the tracked space.
pub const FRINGE: u8 = 0x40;
/// The mouse is out of the tracked space: the position and angles mean nothing.
pub const OUT_OF_RANGE: u8 = 0x20;
/// The buttons' bits in the first byte, in VRPN button order: 0 the mouse stand's button,
/// 1 suspend, 2 left, 3 middle, 4 right.
pub const BUTTON_BITS: [u8; BUTTONS] = [0x10, 0x08, 0x04, 0x02, 0x01];
/// Buttons served.
pub const BUTTONS: usize = 5;

/// One decoded record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// The first byte's flags and buttons (without the top bit).
    pub status: u8,
    /// x, y, z in the device's units (1/1000 inch), as sent.
    pub counts: [i32; 3],
    /// Pitch, yaw, roll in the device's units (1/40 degree), as sent.
    pub angles: [u16; 3],
}

impl Record {
    /// Decodes the 16 bytes of a record (the first byte's flag is not checked here: the
    /// framer found it).
    pub fn decode(b: &[u8; RECORD_LEN]) -> Record {
        let count = |i: usize| {
            let v = (i32::from(b[i] & 0x7F) << 14)
                | (i32::from(b[i + 1] & 0x7F) << 7)
                | i32::from(b[i + 2] & 0x7F);
            if b[i] & 0x40 != 0 {
                v | !0x1F_FFFF
            } else {
                v
            }
        };
        let angle = |i: usize| (u16::from(b[i] & 0x7F) << 7) | u16::from(b[i + 1] & 0x7F);
        Record {
            status: b[0] & !FLAG,
            counts: [count(1), count(4), count(7)],
            angles: [angle(10), angle(12), angle(14)],
        }
    }

    /// The record's bytes (what the device sends for these values; counts are cut to 21
    /// bits, angles to 14).
    pub fn encode(&self) -> [u8; RECORD_LEN] {
        let mut b = [0u8; RECORD_LEN];
        b[0] = self.status | FLAG;
        for (j, &c) in self.counts.iter().enumerate() {
            let v = (c as u32) & 0x1F_FFFF;
            b[1 + 3 * j] = (v >> 14) as u8 & 0x7F;
            b[2 + 3 * j] = (v >> 7) as u8 & 0x7F;
            b[3 + 3 * j] = v as u8 & 0x7F;
        }
        for (j, &a) in self.angles.iter().enumerate() {
            b[10 + 2 * j] = (a >> 7) as u8 & 0x7F;
            b[11 + 2 * j] = a as u8 & 0x7F;
        }
        b
    }

    /// Whether the mouse is out of the tracked space (no pose).
    pub fn out_of_range(&self) -> bool {
        self.status & OUT_OF_RANGE != 0
    }

    /// The buttons, pressed or not, in VRPN order.
    pub fn buttons(&self) -> [bool; BUTTONS] {
        BUTTON_BITS.map(|bit| self.status & bit != 0)
    }

    /// The position in metres, VRPN axes: x = the device's x, y = − its z, z = its y. Each
    /// is rounded to single precision as C++ VRPN rounds it, so both servers send the same
    /// numbers.
    pub fn position(&self) -> [f64; 3] {
        let [x, y, z] = self.counts;
        let x = (f64::from(x) / 100_000.0 * 2.54) as f32;
        let y = (f64::from(y) / 100_000.0 * 2.54) as f32;
        let z = (f64::from(z as f32 / 100_000.0f32) * 2.54) as f32;
        [f64::from(x), f64::from(-z), f64::from(y)]
    }

    /// The orientation as a quaternion (x, y, z, w): pitch about x, roll about y (turned
    /// round: 360° − roll, the device's z being VRPN's −y), yaw about z, composed as
    /// yaw · roll · pitch.
    pub fn orientation(&self) -> [f64; 4] {
        let deg = |a: u16| f64::from(a) / 40.0;
        let [p, y, r] = self.angles;
        let half = |d: f64| (d.to_radians() / 2.0).sin_cos();
        let (sp, cp) = half(deg(p));
        let (sy, cy) = half(deg(y));
        let (sr, cr) = half(360.0 - deg(r));
        [
            sp * cr * cy - cp * sr * sy,
            cp * sr * cy + sp * cr * sy,
            cp * cr * sy - sp * sr * cy,
            cp * cr * cy + sp * sr * sy,
        ]
    }
}

/// A record found in the stream, with the arrival of its first byte and the garbage dropped
/// before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// The record.
    pub record: Record,
    /// When the poll woke for its first byte.
    pub first_byte: Now,
    /// Bytes dropped since the previous record.
    pub skipped: u32,
}

/// Finds records byte by byte: a byte with the top bit set starts one (dropping a record
/// being collected), fifteen bytes without it complete it, a byte without it outside a record
/// is dropped.
#[derive(Debug, Default)]
pub struct Framer {
    buf: [u8; RECORD_LEN],
    len: usize,
    first: Option<Now>,
    skipped: u32,
    total_skipped: u64,
}

impl Framer {
    /// A framer waiting for a record's first byte.
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Takes one byte that arrived at `now`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, now: Now) -> Option<Framed> {
        if b & FLAG != 0 {
            self.drop_partial();
            self.buf[0] = b;
            self.len = 1;
            self.first = Some(now);
            return None;
        }
        if self.len == 0 {
            self.skip(1);
            return None;
        }
        self.buf[self.len] = b;
        self.len += 1;
        if self.len < RECORD_LEN {
            return None;
        }
        self.len = 0;
        let f = Framed {
            record: Record::decode(&self.buf),
            first_byte: self.first.take().unwrap_or(now),
            skipped: self.skipped,
        };
        self.skipped = 0;
        Some(f)
    }

    /// True while part of a record is held.
    pub fn is_partial(&self) -> bool {
        self.len > 0
    }

    /// Forgets a partial record (without counting it as skipped: the stream stopped).
    pub fn clear(&mut self) {
        self.len = 0;
        self.first = None;
        self.skipped = 0;
    }

    /// Bytes dropped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn drop_partial(&mut self) {
        let n = self.len as u32;
        self.len = 0;
        self.skip(n);
    }

    fn skip(&mut self, n: u32) {
        self.skipped += n;
        self.total_skipped += u64::from(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeVal;
    use nalgebra::{UnitQuaternion, Vector3};
    use std::time::{Duration, Instant};

    fn at(ms: u64) -> Now {
        let t0 = Instant::now();
        Now {
            mono: t0 + Duration::from_millis(ms),
            wall: TimeVal::new(1_700_000_000, 0).plus_secs(ms as f64 / 1e3),
        }
    }

    #[test]
    fn a_record_decodes_as_the_device_defines_it() {
        // x = -1 (all 21 bits set), y = 1000 (1 inch), z = -1000, angles 90°, 0°, 359.975°.
        let mut b = [0u8; RECORD_LEN];
        b[0] = FLAG | 0x04 | 0x01;
        b[1..4].copy_from_slice(&[0x7F, 0x7F, 0x7F]);
        b[4..7].copy_from_slice(&[0x00, (1000 >> 7) as u8, (1000 & 0x7F) as u8]);
        let m = (-1000i32 as u32) & 0x1F_FFFF;
        b[7..10].copy_from_slice(&[(m >> 14) as u8, (m >> 7) as u8 & 0x7F, m as u8 & 0x7F]);
        b[10..12].copy_from_slice(&[(3600 >> 7) as u8, (3600 & 0x7F) as u8]);
        b[14..16].copy_from_slice(&[(14399 >> 7) as u8, (14399 & 0x7F) as u8]);
        let r = Record::decode(&b);
        assert_eq!(r.counts, [-1, 1000, -1000]);
        assert_eq!(r.angles, [3600, 0, 14399]);
        assert_eq!(r.buttons(), [false, false, true, false, true]);
        assert!(!r.out_of_range());
        assert_eq!(r.encode(), b);
        let lowest = Record {
            status: 0,
            counts: [-(1 << 20), 0, 0],
            angles: [0, 0, 0],
        };
        assert_eq!(Record::decode(&lowest.encode()).counts[0], -(1 << 20));
        let p = r.position();
        assert!((p[0] + 0.0000254).abs() < 1e-9);
        assert!((p[1] - 0.0254).abs() < 1e-7, "{p:?}");
        assert!((p[2] - 0.0254).abs() < 1e-7, "{p:?}");
        // The extremes of 21 bits.
        for c in [-(1 << 20) + 1, (1 << 20) - 1, 0, 5, -5] {
            let r = Record {
                status: 0,
                counts: [c, -c, c],
                angles: [0, 0, 0],
            };
            assert_eq!(Record::decode(&r.encode()).counts, [c, -c, c]);
        }
    }

    #[test]
    fn the_orientation_is_yaw_then_roll_then_pitch() {
        for (p, y, r) in [(3600, 0, 0), (0, 1800, 0), (0, 0, 900), (1234, 5678, 9012)] {
            let rec = Record {
                status: 0,
                counts: [0; 3],
                angles: [p, y, r],
            };
            let q = rec.orientation();
            let d = |a: u16| (f64::from(a) / 40.0).to_radians();
            let want = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), d(y))
                * UnitQuaternion::from_axis_angle(
                    &Vector3::y_axis(),
                    2.0 * std::f64::consts::PI - d(r),
                )
                * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), d(p));
            let w = want.into_inner();
            let n = (q.iter().map(|v| v * v).sum::<f64>()).sqrt();
            assert!((n - 1.0).abs() < 1e-12, "{q:?}");
            // The same rotation (q and -q are one).
            let dot = q[0] * w.i + q[1] * w.j + q[2] * w.k + q[3] * w.w;
            assert!((dot.abs() - 1.0).abs() < 1e-12, "{q:?} {w:?}");
        }
    }

    #[test]
    fn garbage_costs_no_record_and_stamps_are_first_bytes() {
        let rec = Record {
            status: 0x12,
            counts: [7, -8, 9],
            angles: [1, 2, 3],
        };
        let bytes = rec.encode();
        let mut f = Framer::new();
        let mut got = Vec::new();
        let mut stream: Vec<(u8, u64)> = Vec::new();
        stream.extend([(0x01, 0), (0x7F, 0)]); // data bytes outside a record
        stream.extend(bytes.iter().map(|&b| (b, 1)));
        stream.extend(bytes[..5].iter().map(|&b| (b, 2))); // cut short by the next record
        stream.extend(bytes.iter().enumerate().map(|(i, &b)| (b, 3 + i as u64)));
        for (b, ms) in stream {
            if let Some(r) = f.push(b, at(ms)) {
                got.push((r.record, r.first_byte.wall, r.skipped));
            }
        }
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].0, rec);
        assert_eq!(got[0].2, 2);
        assert_eq!(got[1].0, rec);
        assert_eq!(got[1].2, 5);
        assert_eq!(got[1].1, at(3).wall);
        assert_eq!(f.total_skipped(), 7);
        assert!(!f.is_partial());
    }
}
