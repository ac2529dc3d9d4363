//! The binary record of the Polhemus 3SPACE and ISOTRAK (output list `O2,11`, binary mode
//! `f`): 20 bytes on the line carrying 17 bytes of data.
//!
//! Only the first byte on the line has its high bit set (the sync bit); every other byte
//! carries seven data bits. The eighth bit of each data byte travels in a separate byte: the
//! data come in groups of up to seven bytes, each group followed by one byte whose bit *j*
//! is the high bit of the group's byte *j*. Twenty bytes on the line are two groups of seven
//! (with their high-bit bytes) and one group of three: 7 + 7 + 3 = 17 data bytes.
//!
//! The 17 data bytes: the record type (`'0'`), the station as an ASCII digit (`'1'` is
//! station 1, VRPN sensor 0), a status byte (the ISOTRAK's stylus switch: `'@'` pressed,
//! `'*'` released), then seven little-endian signed 16-bit values: position x, y, z and the
//! quaternion w, x, y, z.

/// Bytes of a record on the line.
pub const RECORD_LEN: usize = 20;
/// Data bytes in a record.
pub const DATA_LEN: usize = 17;

/// The sync bit: set on a record's first byte only.
pub const SYNC: u8 = 0x80;

/// Scale of the original 3SPACE's positions: full scale (32768) is 65.48 inches.
pub const THREESPACE_METRES_PER_COUNT: f64 = 65.48 * 2.54 / 100.0 / 32768.0;
/// Scale of the ISOTRAK's positions in metric mode (`u`): full scale (32767) is 166.32 cm.
pub const ISOTRAK_METRES_PER_COUNT: f64 = 1.6632 / 32767.0;
/// Scale of the ISOTRAK's quaternion components (full scale 32767 is 1), in single precision
/// as C++ VRPN computes them.
pub const ISOTRAK_QUAT_PER_COUNT: f32 = 1.0 / 32767.0;

/// Which tracker a record comes from: the two scale their values differently.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Model {
    /// The original 3SPACE tracker (`vrpn_Tracker_3Space`): four stations, positions over
    /// ±65.48 inches, quaternions normalised.
    ThreeSpace,
    /// The 3SPACE ISOTRAK (`vrpn_Tracker_Isotrak`): two stations, metric positions over
    /// ±166.32 cm, quaternion components scaled by 1/32767 as they are.
    Isotrak,
}

impl Model {
    /// Stations the tracker has (and sensors the VRPN tracker serves).
    pub const fn stations(self) -> usize {
        match self {
            Model::ThreeSpace => 4,
            Model::Isotrak => 2,
        }
    }

    /// What the tracker is called in texts.
    pub const fn label(self) -> &'static str {
        match self {
            Model::ThreeSpace => "3Space",
            Model::Isotrak => "Isotrak",
        }
    }
}

/// The stylus switch as the ISOTRAK's status byte gives it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stylus {
    /// `'@'`: pressed.
    Pressed,
    /// `'*'`: released.
    Released,
    /// Anything else: no news.
    Unknown,
}

impl Stylus {
    /// The switch as the status byte `b` gives it.
    pub fn from_status(b: u8) -> Stylus {
        match b {
            b'@' => Stylus::Pressed,
            b'*' => Stylus::Released,
            _ => Stylus::Unknown,
        }
    }
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
    /// The status byte, as a stylus switch.
    pub stylus: Stylus,
}

/// Why 20 bytes are not a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Invalid {
    /// The station is not one the tracker has (the byte as received).
    Station(u8),
    /// All four quaternion components are zero (a 3SPACE quaternion cannot be normalised).
    ZeroQuaternion,
}

/// The 17 data bytes of a record on the line (whose first byte has the sync bit).
pub fn unpack(wire: &[u8; RECORD_LEN]) -> [u8; DATA_LEN] {
    let mut data = [0u8; DATA_LEN];
    let mut d = 0;
    // Groups of (data bytes, then the byte with their high bits): 7, 7 and 3.
    for (start, n) in [(0usize, 7usize), (8, 7), (16, 3)] {
        let high = wire[start + n];
        for j in 0..n {
            data[d] = (wire[start + j] & 0x7F) | (((high >> j) & 1) << 7);
            d += 1;
        }
    }
    data
}

/// The 20 bytes a tracker sends for `data` (the inverse of [`unpack`]).
pub fn pack(data: &[u8; DATA_LEN]) -> [u8; RECORD_LEN] {
    let mut wire = [0u8; RECORD_LEN];
    let mut d = 0;
    for (start, n) in [(0usize, 7usize), (8, 7), (16, 3)] {
        let mut high = 0u8;
        for j in 0..n {
            wire[start + j] = data[d] & 0x7F;
            high |= (data[d] >> 7) << j;
            d += 1;
        }
        wire[start + n] = high;
    }
    wire[0] |= SYNC;
    wire
}

/// The seven 16-bit values of a record's data: position x, y, z, quaternion w, x, y, z.
pub fn values(data: &[u8; DATA_LEN]) -> [i16; 7] {
    let mut v = [0i16; 7];
    for (i, v) in v.iter_mut().enumerate() {
        *v = i16::from_le_bytes([data[3 + 2 * i], data[4 + 2 * i]]);
    }
    v
}

/// The data bytes of a record: type `'0'`, `station` (1-based), `status`, the values.
pub fn data(station: u8, status: u8, values: [i16; 7]) -> [u8; DATA_LEN] {
    let mut d = [0u8; DATA_LEN];
    d[0] = b'0';
    d[1] = b'0' + station;
    d[2] = status;
    for (i, v) in values.iter().enumerate() {
        d[3 + 2 * i..5 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    d
}

/// The position in metres and the quaternion (x, y, z, w) the `model` reports for `values`,
/// as C++ VRPN computes them.
pub fn scaled(model: Model, v: [i16; 7]) -> Option<([f64; 3], [f64; 4])> {
    match model {
        Model::ThreeSpace => {
            let pos = [v[0], v[1], v[2]].map(|c| f64::from(c) * THREESPACE_METRES_PER_COUNT);
            let [w, x, y, z] = [v[3], v[4], v[5], v[6]].map(f64::from);
            let norm = (x * x + y * y + z * z + w * w).sqrt();
            if norm == 0.0 {
                return None;
            }
            Some((pos, [x / norm, y / norm, z / norm, w / norm]))
        }
        Model::Isotrak => {
            let pos = [v[0], v[1], v[2]].map(|c| f64::from(c) * ISOTRAK_METRES_PER_COUNT);
            let q = |c: i16| f64::from(f32::from(c) * ISOTRAK_QUAT_PER_COUNT);
            Some((pos, [q(v[4]), q(v[5]), q(v[6]), q(v[3])]))
        }
    }
}

/// Decodes a record of `model` (20 bytes as received, sync byte first).
pub fn decode(model: Model, wire: &[u8; RECORD_LEN]) -> Result<Pose, Invalid> {
    let data = unpack(wire);
    let station = data[1];
    let sensor = usize::from(station.wrapping_sub(b'1'));
    if sensor >= model.stations() {
        return Err(Invalid::Station(station));
    }
    let (pos, quat) = scaled(model, values(&data)).ok_or(Invalid::ZeroQuaternion)?;
    Ok(Pose {
        sensor,
        pos,
        quat,
        stylus: Stylus::from_status(data[2]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_round_trips_and_only_the_first_byte_has_the_sync_bit() {
        let v = [-32768, 32767, -1, 0x7F80, -0x0081, 1, 0x00FF];
        let d = data(2, b'@', v);
        let wire = pack(&d);
        assert!(wire[0] & SYNC != 0);
        assert!(wire[1..].iter().all(|b| b & SYNC == 0), "{wire:02X?}");
        let back = unpack(&wire);
        assert_eq!(back[1..], d[1..]);
        assert_eq!(values(&back), v);
    }

    #[test]
    fn the_group_layout_is_c_plus_plus_s() {
        // Data byte 3 (first byte of x) = 0xFF: low bits in wire[3], high bit in wire[7] bit 3.
        // Data bytes 14 and 16 open and close the last group (wire 16..19, high bits in 19).
        let mut d = [0u8; DATA_LEN];
        d[3] = 0xFF;
        d[14] = 0x80;
        d[16] = 0x81;
        let w = pack(&d);
        assert_eq!(w[3], 0x7F);
        assert_eq!(w[7], 1 << 3);
        assert_eq!(w[15], 0);
        assert_eq!(w[16], 0x00);
        assert_eq!(w[18], 0x01);
        assert_eq!(w[19], 0b101);
    }

    #[test]
    fn values_scale_as_c_plus_plus_scales_them() {
        let v = [16384, -32768, 100, 32767, 0, 0, 0];
        let wire = pack(&data(1, b' ', v));
        let p = decode(Model::Isotrak, &wire).unwrap();
        assert_eq!(p.sensor, 0);
        assert_eq!(p.pos[0], 16384.0 * 1.6632 / 32767.0);
        assert_eq!(
            p.quat,
            [0.0, 0.0, 0.0, f64::from(32767.0f32 * (1.0f32 / 32767.0))]
        );
        let p = decode(Model::ThreeSpace, &pack(&data(4, b' ', v))).unwrap();
        assert_eq!(p.sensor, 3);
        assert_eq!(p.pos[1], -65.48 * 2.54 / 100.0);
        assert_eq!(p.quat, [0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn bad_stations_and_zero_quaternions_are_not_records() {
        let v = [0, 0, 0, 0, 0, 0, 0];
        assert_eq!(
            decode(Model::Isotrak, &pack(&data(3, b' ', [0, 0, 0, 1, 0, 0, 0]))),
            Err(Invalid::Station(b'3'))
        );
        assert_eq!(
            decode(Model::ThreeSpace, &pack(&data(1, b' ', v))),
            Err(Invalid::ZeroQuaternion)
        );
        assert_eq!(
            decode(
                Model::ThreeSpace,
                &pack(&data(0, b' ', [0, 0, 0, 1, 0, 0, 0]))
            ),
            Err(Invalid::Station(b'0'))
        );
    }
}
