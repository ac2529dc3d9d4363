//! One streamed record: the eight slots the reset asks for, in order, big-endian.
//!
//! | Bytes | Slot (command) | Value |
//! |---|---|---|
//! | 0–15 | `0x06` untared orientation | quaternion x, y, z, w |
//! | 16–31 | `0x00` tared orientation | quaternion x, y, z, w |
//! | 32–43 | `0x29` tared linear acceleration, gravity removed | x, y, z in g |
//! | 44–79 | `0x25` all corrected sensor data | gyro rad/s, accelerometer g, compass gauss (x, y, z each) |
//! | 80–83 | `0x2B` temperature | °C |
//! | 84–87 | `0x2D` confidence | 0 (moving) … 1 (still) |
//! | 88 | `0xFA` button state | bit *i* = button *i* |
//!
//! The wired unit sends records back to back with no header, so a record is recognised by
//! its values ([`decode`] refuses what a real unit cannot send: a non-unit quaternion, a
//! confidence outside 0…1, a value out of its sensor's range, a non-finite number).

/// Bytes in one record.
pub const RECORD_LEN: usize = 16 + 16 + 12 + 36 + 4 + 4 + 1;

/// Analog channels: the nine corrected sensor values, the temperature, the confidence.
pub const CHANNELS: usize = 11;

/// Buttons: the byte's eight bits.
pub const BUTTONS: usize = 8;

/// Standard gravity (m/s² per g), to turn the acceleration slot into m/s² (as C++ does).
pub const GRAVITY: f64 = 9.80665;

/// The streaming slots the reset asks for (command `0x50`), `0xFF` marking the free one.
pub const SLOTS: [u8; 8] = [0x06, 0x00, 0x29, 0x25, 0x2B, 0x2D, 0xFA, 0xFF];

/// A decoded record, each value as the unit sent it (f32, widened).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Untared orientation (x, y, z, w): tracker sensor 0.
    pub untared: [f64; 4],
    /// Tared orientation (x, y, z, w): tracker sensor 1.
    pub tared: [f64; 4],
    /// Tared linear acceleration with gravity removed, in g.
    pub accel_g: [f64; 3],
    /// The Analog channels: gyro x y z (rad/s), gravity x y z (g), compass x y z (gauss),
    /// temperature (°C), confidence.
    pub channels: [f64; CHANNELS],
    /// Button bits.
    pub buttons: u8,
}

/// Why bytes are not a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Invalid {
    /// A value is not a finite number.
    NotFinite,
    /// An orientation is not a unit quaternion.
    NotUnit,
    /// The confidence is outside 0…1 (C++'s own check).
    Confidence,
    /// A sensor value is beyond what the unit measures.
    OutOfRange,
}

impl std::fmt::Display for Invalid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Invalid::NotFinite => "a value that is not a number",
            Invalid::NotUnit => "an orientation that is not a unit quaternion",
            Invalid::Confidence => "a confidence outside 0..1",
            Invalid::OutOfRange => "a sensor value out of range",
        })
    }
}

fn f32_at(b: &[u8], i: usize) -> f64 {
    f64::from(f32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]))
}

fn quat_at(b: &[u8], i: usize) -> Result<[f64; 4], Invalid> {
    let q = [
        f32_at(b, i),
        f32_at(b, i + 4),
        f32_at(b, i + 8),
        f32_at(b, i + 12),
    ];
    if q.iter().any(|v| !v.is_finite()) {
        return Err(Invalid::NotFinite);
    }
    let n2: f64 = q.iter().map(|v| v * v).sum();
    if (n2 - 1.0).abs() > UNIT_TOLERANCE {
        return Err(Invalid::NotUnit);
    }
    Ok(q)
}

/// How far from 1 a quaternion's squared norm may be (the unit normalises them; f32
/// rounding stays far below this).
const UNIT_TOLERANCE: f64 = 1e-3;

/// Largest magnitude accepted per channel: gyro (rad/s), gravity (g), compass (gauss),
/// temperature (°C), confidence.
const LIMITS: [f64; CHANNELS] = [
    100.0, 100.0, 100.0, 50.0, 50.0, 50.0, 100.0, 100.0, 100.0, 300.0, 1.0,
];

/// Decodes and checks one record.
pub fn decode(b: &[u8; RECORD_LEN]) -> Result<Record, Invalid> {
    let untared = quat_at(b, 0)?;
    let tared = quat_at(b, 16)?;
    let accel_g = [f32_at(b, 32), f32_at(b, 36), f32_at(b, 40)];
    let mut channels = [0.0; CHANNELS];
    for (i, c) in channels.iter_mut().enumerate() {
        *c = f32_at(b, 44 + 4 * i);
    }
    if accel_g.iter().chain(&channels).any(|v| !v.is_finite()) {
        return Err(Invalid::NotFinite);
    }
    let confidence = channels[CHANNELS - 1];
    if !(0.0..=1.0).contains(&confidence) {
        return Err(Invalid::Confidence);
    }
    if accel_g.iter().any(|v| v.abs() > 50.0)
        || channels.iter().zip(LIMITS).any(|(v, l)| v.abs() > l)
    {
        return Err(Invalid::OutOfRange);
    }
    Ok(Record {
        untared,
        tared,
        accel_g,
        channels,
        buttons: b[RECORD_LEN - 1],
    })
}

/// The bytes a unit sends for `r` (its values rounded to f32): for the simulator and tests.
pub fn encode(r: &Record) -> [u8; RECORD_LEN] {
    let mut b = [0u8; RECORD_LEN];
    let values = r
        .untared
        .iter()
        .chain(&r.tared)
        .chain(&r.accel_g)
        .chain(&r.channels);
    for (i, v) in values.enumerate() {
        b[4 * i..4 * i + 4].copy_from_slice(&(*v as f32).to_be_bytes());
    }
    b[RECORD_LEN - 1] = r.buttons;
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Record {
        Record {
            untared: [0.0, 0.0, 0.6, 0.8],
            tared: [0.6, 0.0, 0.0, 0.8],
            accel_g: [0.25, -0.5, 0.125],
            channels: [0.5, -0.25, 1.5, 0.0, 0.0, 1.0, 0.25, 0.5, -0.5, 27.5, 0.75],
            buttons: 0b1000_0001,
        }
    }

    #[test]
    fn layout_matches_the_slots() {
        assert_eq!(RECORD_LEN, 89);
        let b = encode(&sample());
        assert_eq!(&b[12..16], &0.8f32.to_be_bytes());
        assert_eq!(&b[80..84], &27.5f32.to_be_bytes());
        assert_eq!(&b[84..88], &0.75f32.to_be_bytes());
        assert_eq!(b[88], 0x81);
        let r = decode(&b).unwrap();
        assert_eq!(r.channels, sample().channels);
        assert_eq!(r.buttons, 0x81);
        assert!((r.untared[3] - 0.8).abs() < 1e-7);
    }

    #[test]
    fn what_a_unit_cannot_send_is_refused() {
        let mut r = sample();
        r.channels[10] = 1.5;
        assert_eq!(decode(&encode(&r)), Err(Invalid::Confidence));
        let mut r = sample();
        r.tared = [0.0, 0.0, 0.0, 0.5];
        assert_eq!(decode(&encode(&r)), Err(Invalid::NotUnit));
        let mut r = sample();
        r.channels[9] = 1e6;
        assert_eq!(decode(&encode(&r)), Err(Invalid::OutOfRange));
        let mut b = encode(&sample());
        b[44..48].copy_from_slice(&f32::NAN.to_be_bytes());
        assert_eq!(decode(&b), Err(Invalid::NotFinite));
        // A record shifted by any number of bytes is not a record.
        let two = [encode(&sample()), encode(&sample())].concat();
        for shift in 1..RECORD_LEN {
            let w: [u8; RECORD_LEN] = two[shift..shift + RECORD_LEN].try_into().unwrap();
            assert!(decode(&w).is_err(), "shift {shift}");
        }
    }
}
