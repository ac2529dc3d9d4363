//! Magellan records: the nibble characters, the record letters and their lengths, and the
//! decoding of axis and key records (with the encoding the simulator needs).
//!
//! Every record is one lowercase letter, data characters, and a CR. A data character carries
//! four bits in its low nibble; the device picks the high bits so that each character has
//! even parity, which makes exactly sixteen characters valid ([`NIBBLE_CHARS`]). Neither a
//! record letter nor CR is among them, so a record start can never hide inside a record.

/// The character for each nibble value 0..=15.
pub const NIBBLE_CHARS: [u8; 16] = *b"0AB3D56GH9:K<MN?";
/// Carriage return: ends every command and every record.
pub const CR: u8 = b'\r';
/// Longest record (an axis record).
pub const MAX_RECORD: usize = 26;
/// Analog channels: X, Y, Z translation, then A, B, C rotation.
pub const AXES: usize = 6;
/// Buttons: 0 is the `*` key, 1 to 8 the numbered keys.
pub const BUTTONS: usize = 9;
/// Raw axis value that maps to 1.0 (the largest values seen are about 7200).
pub const AXIS_SCALE: f64 = 7500.0;
/// Bit of a mode record's nibble that says the device is in mouse mode.
pub const MOUSE_MODE: u8 = 0x08;
/// Null radius the reset sets (`nH`).
pub const RESET_NULL_RADIUS: i32 = 8;

/// The character that carries nibble `n` (only its low four bits count).
pub fn nibble_char(n: u8) -> u8 {
    NIBBLE_CHARS[usize::from(n & 0x0F)]
}

/// Whether `b` is one of the sixteen characters a device sends as data.
pub fn is_nibble_char(b: u8) -> bool {
    NIBBLE_CHARS[usize::from(b & 0x0F)] == b
}

/// The value a data character carries (its low four bits, as C++ VRPN decodes it).
pub fn nibble(b: u8) -> u8 {
    b & 0x0F
}

/// Total length (letter and CR included) of a record starting with `letter`, or `None` if
/// no record starts with it.
pub fn record_len(letter: u8) -> Option<usize> {
    Some(match letter {
        b'k' => 5,
        b'd' => MAX_RECORD,
        b'b' | b'z' => 2,
        b'm' | b'n' => 3,
        b'q' | b'p' | b'c' => 4,
        _ => return None,
    })
}

/// The raw value of axis `i` (0..6) of an axis record: four nibbles, most significant
/// first, less 32768.
pub fn axis_raw(record: &[u8], i: usize) -> i32 {
    let at = 1 + 4 * i;
    record[at..at + 4]
        .iter()
        .fold(0i32, |v, &c| (v << 4) | i32::from(nibble(c)))
        - 32768
}

/// The channel value of a raw axis value: 0 within the null radius, else raw / 7500.
pub fn axis_value(raw: i32, null_radius: i32) -> f64 {
    if raw.abs() <= null_radius {
        0.0
    } else {
        f64::from(raw) / AXIS_SCALE
    }
}

/// The button states of a key record as a bit mask (bit `i` = button `i`): button 0 is bit 0
/// of the third data character, buttons 1 to 4 bits 0 to 3 of the first, buttons 5 to 8 bits
/// 0 to 3 of the second.
pub fn keys(record: &[u8]) -> u16 {
    let (a, b, c) = (nibble(record[1]), nibble(record[2]), nibble(record[3]));
    u16::from(c & 1) | (u16::from(a) << 1) | (u16::from(b) << 5)
}

/// An axis record carrying `raw` values (each clamped to -32768..=32767).
pub fn encode_axes(raw: &[i32; AXES]) -> [u8; MAX_RECORD] {
    let mut r = [0u8; MAX_RECORD];
    r[0] = b'd';
    for (i, &v) in raw.iter().enumerate() {
        let u = (v.clamp(-32768, 32767) + 32768) as u16;
        for k in 0..4 {
            r[1 + 4 * i + k] = nibble_char((u >> (12 - 4 * k)) as u8);
        }
    }
    r[MAX_RECORD - 1] = CR;
    r
}

/// A key record for the button mask `mask` (bit `i` = button `i`, nine buttons).
pub fn encode_keys(mask: u16) -> [u8; 5] {
    [
        b'k',
        nibble_char(((mask >> 1) & 0x0F) as u8),
        nibble_char(((mask >> 5) & 0x0F) as u8),
        nibble_char((mask & 1) as u8),
        CR,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nibble_characters_have_even_parity_and_decode() {
        for n in 0..16u8 {
            let c = nibble_char(n);
            assert_eq!(c.count_ones() % 2, 0, "{}", c as char);
            assert!(is_nibble_char(c));
            assert_eq!(nibble(c), n);
        }
        for b in [b'k', b'd', b'm', b'\r', b'1', b'a', b'I'] {
            assert!(!is_nibble_char(b), "{}", b as char);
        }
    }

    #[test]
    fn letters_and_lengths() {
        let lens: Vec<_> = b"kdbmnqzpc".iter().map(|&l| record_len(l)).collect();
        let want = [5, 26, 2, 3, 3, 4, 2, 4, 4].map(Some);
        assert_eq!(lens, want);
        assert_eq!(record_len(b'x'), None);
        assert_eq!(record_len(b'K'), None);
    }

    #[test]
    fn axes_round_trip_with_the_null_radius() {
        let raw = [0, 8, -9, 7500, -32768, 32767];
        let rec = encode_axes(&raw);
        assert_eq!(rec[0], b'd');
        assert_eq!(rec[25], CR);
        assert!(rec[1..25].iter().all(|&c| is_nibble_char(c)));
        let got: Vec<i32> = (0..AXES).map(|i| axis_raw(&rec, i)).collect();
        assert_eq!(got, raw);
        assert_eq!(axis_value(8, 8), 0.0);
        assert_eq!(axis_value(-8, 8), 0.0);
        assert_eq!(axis_value(-9, 8), -9.0 / 7500.0);
        assert_eq!(axis_value(7500, 8), 1.0);
        // All-zero nibbles are the most negative value.
        assert_eq!(axis_raw(b"d0000", 0), -32768);
    }

    #[test]
    fn keys_map_as_the_device_sends_them() {
        // The `*` key alone.
        assert_eq!(keys(b"k00A\r"), 1);
        // Keys 1 and 4 (bits 0 and 3 of the first character), key 8 (bit 3 of the second).
        assert_eq!(keys(b"k9H0\r"), 0b1_0001_0010);
        assert_eq!(keys(b"k0H0\r"), 1 << 8);
        for mask in 0..512u16 {
            assert_eq!(keys(&encode_keys(mask)), mask);
        }
    }
}
