//! The Flock's position/quaternion record and how its numbers become a VRPN pose.
//!
//! A record is seven data words, two bytes each, low byte first. Only the first byte of a
//! record has bit 7 set (the phasing bit); every other byte has it clear, which is how the
//! start of a record is found in a stream. Each byte carries 7 data bits, so a word holds a
//! 14-bit two's-complement number, which VRPN places in the top 14 bits of a signed 16-bit
//! value: `w16 = (high & 0x7F) << 9 | (low & 0x7F) << 2`.
//!
//! | Word | Meaning | VRPN value |
//! |---|---|---|
//! | 0, 1, 2 | X, Y, Z position | metres = `w16` × S × 0.0254, S = 144/32768 inch per unit with an extended-range transmitter, 36/32768 without |
//! | 3 | quaternion W | `w16` / 32768 |
//! | 4, 5, 6 | quaternion X, Y, Z | `w16` / 32768 |
//!
//! In group mode (several receivers on one line) an eighth byte follows: the bird's bus
//! address. Receivers are at addresses 1..N, or 2..N+1 when the extended-range controller
//! takes address 1; the VRPN sensor is the receiver's index from 0.

/// Data words in a position/quaternion record.
pub const WORDS: usize = 7;
/// Bytes of a record without the address byte (one receiver per line).
pub const RECORD_LEN: usize = 2 * WORDS;
/// Bytes of a record in group mode: the words, then the bird's address.
pub const GROUP_RECORD_LEN: usize = RECORD_LEN + 1;
/// Metres per inch: the Flock reports inches.
pub const METRES_PER_INCH: f64 = 0.0254;
/// The phasing bit: set in the first byte of a record only.
pub const PHASING_BIT: u8 = 0x80;

/// The transmitter the receivers measure against; it sets the position scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transmitter {
    /// The standard-range transmitter: ±36 inches full scale.
    Standard,
    /// An extended-range transmitter (with its controller at bus address 1): ±144 inches.
    ExtendedRange,
}

impl Transmitter {
    /// The transmitter for the configuration's `useERT` flag.
    pub fn from_ert(ert: bool) -> Transmitter {
        if ert {
            Transmitter::ExtendedRange
        } else {
            Transmitter::Standard
        }
    }

    /// True for the extended-range transmitter.
    pub fn is_extended(self) -> bool {
        self == Transmitter::ExtendedRange
    }

    /// Full scale of a position word, in inches.
    pub fn full_scale_inches(self) -> f64 {
        match self {
            Transmitter::Standard => 36.0,
            Transmitter::ExtendedRange => 144.0,
        }
    }

    /// Inches per unit of a 16-bit position value.
    pub fn inches_per_unit(self) -> f64 {
        self.full_scale_inches() / 32768.0
    }

    /// Bus address of the first receiver (the controller of an extended-range transmitter
    /// takes address 1).
    pub fn first_receiver_address(self) -> u8 {
        1 + u8::from(self.is_extended())
    }

    /// Units on the bus for `receivers` receivers: the receivers, plus the controller.
    pub fn units(self, receivers: u8) -> u8 {
        receivers + u8::from(self.is_extended())
    }
}

/// A data word as VRPN reads it: the 14-bit value in the top bits of an `i16`.
pub fn decode_word(low: u8, high: u8) -> i16 {
    ((u16::from(high & 0x7F) << 9) | (u16::from(low & 0x7F) << 2)) as i16
}

/// The seven words of one record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PosQuat {
    /// X, Y, Z, W, QX, QY, QZ as 16-bit values (see [`decode_word`]).
    pub words: [i16; WORDS],
}

impl PosQuat {
    /// Decodes the first [`RECORD_LEN`] bytes of `bytes` (the phasing bit is ignored).
    pub fn decode(bytes: &[u8]) -> PosQuat {
        let mut words = [0i16; WORDS];
        for (w, pair) in words.iter_mut().zip(bytes[..RECORD_LEN].chunks_exact(2)) {
            *w = decode_word(pair[0], pair[1]);
        }
        PosQuat { words }
    }

    /// Position in metres.
    pub fn position_m(&self, transmitter: Transmitter) -> [f64; 3] {
        let scale = transmitter.inches_per_unit();
        // Evaluated as (value × scale) × 0.0254, the order C++ uses, for identical bits.
        [0, 1, 2].map(|i| f64::from(self.words[i]) * scale * METRES_PER_INCH)
    }

    /// Orientation as VRPN sends it: x, y, z, w (the Flock sends w first).
    pub fn quat_xyzw(&self) -> [f64; 4] {
        let q = |i: usize| f64::from(self.words[i]) / 32768.0;
        [q(4), q(5), q(6), q(3)]
    }
}

/// The multiplicative inverse of a quaternion (x, y, z, w): its conjugate divided by its
/// squared length, computed as quatlib does (one reciprocal, then products) so the bits match
/// a C++ server started with the "invert quaternion" option.
pub fn invert_xyzw(q: [f64; 4]) -> [f64; 4] {
    let norm = 1.0 / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    [-q[0] * norm, -q[1] * norm, -q[2] * norm, q[3] * norm]
}

/// The VRPN sensor of the receiver at bus `address`, if it is one of the `receivers`.
pub fn sensor_for_address(address: u8, receivers: u8, transmitter: Transmitter) -> Option<i32> {
    let first = transmitter.first_receiver_address();
    (address >= first && address < first + receivers).then(|| i32::from(address - first))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Encodes a 14-bit value the way the Flock sends it (independent of the decoder).
    fn bytes_of(v14: i16, first: bool) -> [u8; 2] {
        let u = (v14 as u16) & 0x3FFF;
        let low = (u & 0x7F) as u8 | if first { 0x80 } else { 0 };
        [low, ((u >> 7) & 0x7F) as u8]
    }

    #[test]
    fn words_keep_sign_and_land_in_the_top_bits() {
        for (v14, w16) in [
            (0i16, 0i16),
            (1, 4),
            (-1, -4),
            (8191, 32764),
            (-8192, -32768),
            (0x1555, 0x1555 * 4),
        ] {
            let [low, high] = bytes_of(v14, false);
            assert_eq!(decode_word(low, high), w16, "v14 = {v14}");
            // The phasing bit never changes the value.
            assert_eq!(decode_word(low | 0x80, high), w16);
        }
    }

    #[test]
    fn record_scales_to_metres_and_reorders_the_quaternion() {
        let values: [i16; 7] = [2048, -4096, 8191, 4096, -2048, 0, -8192];
        let mut bytes = Vec::new();
        for (i, v) in values.iter().enumerate() {
            bytes.extend_from_slice(&bytes_of(*v, i == 0));
        }
        let r = PosQuat::decode(&bytes);
        // 2048 units of 14 bits are a quarter of full scale.
        assert_eq!(
            r.position_m(Transmitter::ExtendedRange)[0],
            8192.0 * (144.0 / 32768.0) * 0.0254
        );
        assert!((r.position_m(Transmitter::ExtendedRange)[0] - 36.0 * 0.0254).abs() < 1e-12);
        assert!((r.position_m(Transmitter::Standard)[1] + 18.0 * 0.0254).abs() < 1e-12);
        assert_eq!(r.quat_xyzw(), [-0.25, 0.0, -1.0, 0.5]);
    }

    #[test]
    fn inverse_of_a_unit_quaternion_is_its_conjugate() {
        assert_eq!(
            invert_xyzw([0.0, 0.6, 0.0, 0.8]),
            [-0.0, -0.6 / (0.36 + 0.64), -0.0, 0.8 / (0.36 + 0.64)]
        );
        let q = invert_xyzw([0.5, 0.0, 0.0, 0.5]);
        assert_eq!(q, [-1.0, -0.0, -0.0, 1.0]);
    }

    #[test]
    fn addresses_map_to_sensors() {
        let ert = Transmitter::ExtendedRange;
        assert_eq!(sensor_for_address(1, 3, ert), None);
        assert_eq!(sensor_for_address(2, 3, ert), Some(0));
        assert_eq!(sensor_for_address(4, 3, ert), Some(2));
        assert_eq!(sensor_for_address(5, 3, ert), None);
        let std = Transmitter::Standard;
        assert_eq!(sensor_for_address(0, 2, std), None);
        assert_eq!(sensor_for_address(1, 2, std), Some(0));
        assert_eq!(sensor_for_address(3, 2, std), None);
        assert_eq!(ert.units(3), 4);
        assert_eq!(std.units(3), 3);
    }
}
