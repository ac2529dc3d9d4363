//! The Polhemus Liberty / Patriot binary record (`F1`), with the output list the driver sets
//! (`O<station>,2,7,8[,10],0`: position, quaternion, time stamp, \[stylus\], space).
//!
//! | Bytes | Field |
//! |---|---|
//! | 0-1 | `LY` (Liberty), `PA` (Patriot) or `LU` (Liberty Latus) |
//! | 2 | station, binary, 1 for the first (VRPN sensor 0) |
//! | 3 | the command that started the output (ignored) |
//! | 4 | error indicator (ignored, as C++) |
//! | 5 | reserved |
//! | 6-7 | response size (ignored, as C++) |
//! | 8-19 | position x, y, z: little-endian `f32`, inches |
//! | 20-35 | quaternion w, x, y, z: little-endian `f32` |
//! | 36-39 | time stamp: little-endian `u32`, milliseconds |
//! | 40-43 | stylus switch: little-endian `u32`, nonzero pressed (only with a stylus) |
//! | last | an ASCII space |

/// Bytes in the record header.
pub const HEADER_LEN: usize = 8;
/// Bytes in a record without a stylus field.
pub const RECORD_LEN: usize = HEADER_LEN + 12 + 16 + 4 + 1;
/// Bytes in a record with a stylus field.
pub const STYLUS_RECORD_LEN: usize = RECORD_LEN + 4;
/// Metres per inch, as C++ VRPN writes it.
pub const METRES_PER_INCH: f64 = 2.54 / 100.0;
/// Stations the driver configures (C++'s fixed eight).
pub const STATIONS: usize = 8;

/// The two-byte starts a record may have.
pub const STARTS: [[u8; 2]; 3] = [*b"LY", *b"PA", *b"LU"];

/// Whether `b` can be the first byte of a record.
pub fn is_first(b: u8) -> bool {
    b == b'L' || b == b'P'
}

/// Whether `a`, `b` start a record.
pub fn is_start(a: u8, b: u8) -> bool {
    STARTS.contains(&[a, b])
}

/// A decoded record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// VRPN sensor (station − 1).
    pub sensor: usize,
    /// Position in metres.
    pub pos: [f64; 3],
    /// Orientation, VRPN's x, y, z, w order.
    pub quat: [f64; 4],
    /// The tracker's time stamp, in milliseconds.
    pub millis: u32,
    /// The stylus switch, for a station with a stylus field.
    pub stylus: Option<bool>,
}

fn f32_at(r: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([r[i], r[i + 1], r[i + 2], r[i + 3]])
}

fn u32_at(r: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([r[i], r[i + 1], r[i + 2], r[i + 3]])
}

/// Decodes a complete record (`r.len()` is [`RECORD_LEN`] or [`STYLUS_RECORD_LEN`]).
pub fn decode(r: &[u8]) -> Pose {
    let pos = [8, 12, 16].map(|i| f64::from(f32_at(r, i)) * METRES_PER_INCH);
    let [w, x, y, z] = [20, 24, 28, 32].map(|i| f64::from(f32_at(r, i)));
    Pose {
        sensor: usize::from(r[2]).saturating_sub(1),
        pos,
        quat: [x, y, z, w],
        millis: u32_at(r, 36),
        stylus: (r.len() == STYLUS_RECORD_LEN).then(|| u32_at(r, 40) != 0),
    }
}

/// The bytes of a record: `start`, `station` (1-based), position (inches), quaternion
/// (w, x, y, z), time stamp, optional stylus.
pub fn encode(
    start: [u8; 2],
    station: u8,
    pos: [f32; 3],
    wxyz: [f32; 4],
    millis: u32,
    stylus: Option<u32>,
    out: &mut Vec<u8>,
) {
    let len = if stylus.is_some() {
        STYLUS_RECORD_LEN
    } else {
        RECORD_LEN
    };
    out.extend_from_slice(&start);
    out.extend_from_slice(&[station, b'C', b' ', 0]);
    out.extend_from_slice(&((len - HEADER_LEN) as u16).to_le_bytes());
    for v in pos.iter().chain(&wxyz) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&millis.to_le_bytes());
    if let Some(s) = stylus {
        out.extend_from_slice(&s.to_le_bytes());
    }
    out.push(b' ');
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_and_decode_agree_on_every_field() {
        let mut r = Vec::new();
        encode(
            *b"PA",
            2,
            [1.0, -2.5, 40.0],
            [0.5, 0.5, -0.5, 0.5],
            123_456,
            Some(1),
            &mut r,
        );
        assert_eq!(r.len(), STYLUS_RECORD_LEN);
        assert_eq!(*r.last().unwrap(), b' ');
        let p = decode(&r);
        assert_eq!(p.sensor, 1);
        let m = METRES_PER_INCH;
        assert_eq!(p.pos, [m, -2.5 * m, 40.0 * m]);
        assert_eq!(p.quat, [0.5, -0.5, 0.5, 0.5]);
        assert_eq!((p.millis, p.stylus), (123_456, Some(true)));
        r.clear();
        encode(*b"LY", 8, [0.0; 3], [1.0, 0.0, 0.0, 0.0], 0, None, &mut r);
        assert_eq!(r.len(), RECORD_LEN);
        assert_eq!(decode(&r).stylus, None);
    }
}
