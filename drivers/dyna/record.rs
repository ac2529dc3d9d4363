//! One DynaSight record: eight bytes, checked and decoded as C++ VRPN does.
//!
//! | Byte | Content |
//! |---|---|
//! | 0 | `1000` (sync), target number (2 bits), exponent code (2 bits) |
//! | 1 | `1000`, two unused bits, tracking status (2 bits: 0 tracking, 1 caution) |
//! | 2, 3 | X, big-endian, signed |
//! | 4, 5 | Y |
//! | 6, 7 | Z |
//!
//! A coordinate is the signed 16-bit value shifted left by the exponent, in units of
//! 0.05 mm. The shift is `(code & 1) | ((code & 2) << 1)`, that is 0, 1, 4 or 5 — the formula
//! C++ VRPN applies, kept so a client sees the same numbers.

/// Bytes in a record.
pub const RECORD_LEN: usize = 8;
/// The high nibble of the two header bytes.
pub const SYNC: u8 = 0x80;
/// Metres per unit of a coordinate (0.05 mm).
pub const METRES_PER_UNIT: f64 = 0.000_05;

/// True for a byte that can start a record (high nibble `1000`).
pub fn is_sync(b: u8) -> bool {
    b & 0xF0 == SYNC
}

/// Why eight bytes starting at a sync byte are not a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Invalid {
    /// The second byte lacks the `1000` high nibble.
    SecondByte(u8),
    /// A coordinate's two bytes both look like header bytes: another record starts inside.
    HeaderInside,
    /// Not tracking, and the target number is not 0 (the passive target).
    Target(u8),
}

/// Checks the record C++ VRPN's way: both header nibbles, no header pair among the
/// coordinates, and when the tracker is not tracking (status 2 or 3) only target 0.
pub fn validate(r: &[u8; RECORD_LEN]) -> Result<(), Invalid> {
    if !is_sync(r[1]) {
        return Err(Invalid::SecondByte(r[1]));
    }
    if (2..RECORD_LEN)
        .step_by(2)
        .any(|i| is_sync(r[i]) && is_sync(r[i + 1]))
    {
        return Err(Invalid::HeaderInside);
    }
    let status = r[1] & 0x03;
    let target = (r[0] >> 2) & 0x03;
    if status > 1 && target != 0 {
        return Err(Invalid::Target(target));
    }
    Ok(())
}

/// The left shift the exponent code of byte 0 stands for (0, 1, 4 or 5).
pub fn shift(b0: u8) -> u32 {
    u32::from((b0 & 0x01) | ((b0 & 0x02) << 1))
}

/// Position in metres (x, y, z) of a valid record.
pub fn position_m(r: &[u8; RECORD_LEN]) -> [f64; 3] {
    let e = shift(r[0]);
    let coord = |i: usize| {
        let raw = i16::from_be_bytes([r[i], r[i + 1]]);
        (i64::from(raw) << e) as f64 * METRES_PER_UNIT
    };
    [coord(2), coord(4), coord(6)]
}

/// The orientation C++ reports for the single-target DynaSight: the identity (x, y, z, w).
pub const IDENTITY_XYZW: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// Builds a record (for the simulator and tests): `target` and `status` 0..=3, `exponent`
/// the 2-bit code, raw coordinates.
pub fn encode(target: u8, exponent: u8, status: u8, xyz: [i16; 3]) -> [u8; RECORD_LEN] {
    let mut r = [0u8; RECORD_LEN];
    r[0] = SYNC | ((target & 3) << 2) | (exponent & 3);
    r[1] = SYNC | (status & 3);
    for (k, v) in xyz.iter().enumerate() {
        r[2 + 2 * k..4 + 2 * k].copy_from_slice(&v.to_be_bytes());
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_codes_shift_by_0_1_4_5() {
        assert_eq!([0, 1, 2, 3].map(|c| shift(SYNC | c)), [0, 1, 4, 5]);
    }

    #[test]
    fn decodes_signed_coordinates_in_units_of_50_micrometres() {
        let r = encode(0, 0, 0, [1000, -1000, 0x0102]);
        let p = position_m(&r);
        assert_eq!(p, [0.05, -0.05, 258.0 * 0.000_05]);
        let r = encode(0, 3, 1, [-2, 3, 0]);
        assert_eq!(position_m(&r), [-64.0 * 0.000_05, 96.0 * 0.000_05, 0.0]);
        assert_eq!(validate(&r), Ok(()));
    }

    #[test]
    fn rejects_what_c_plus_plus_rejects() {
        let mut r = encode(0, 0, 0, [1, 2, 3]);
        r[1] = 0x12;
        assert_eq!(validate(&r), Err(Invalid::SecondByte(0x12)));
        // Y high and low both look like header bytes.
        let r = encode(0, 0, 0, [1, 0x8180u16 as i16, 3]);
        assert_eq!(validate(&r), Err(Invalid::HeaderInside));
        // Not tracking (status 2) with an active target.
        assert_eq!(validate(&encode(1, 0, 2, [0; 3])), Err(Invalid::Target(1)));
        // Not tracking with the passive target, or tracking any target: valid.
        assert_eq!(validate(&encode(0, 0, 3, [0; 3])), Ok(()));
        assert_eq!(validate(&encode(2, 0, 1, [0; 3])), Ok(()));
    }
}
