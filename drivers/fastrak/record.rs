//! The binary record a Fastrak (or an IS-600 / IS-900 in Fastrak-compatible mode) streams for
//! one station, and the output-list command that selects its layout.
//!
//! A record is, in this order (every number IEEE-754 single precision, little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 1 | `'0'`, the record start |
//! | 1 | station number in ASCII, `'1'` for the first station (VRPN sensor 0) |
//! | 1 | status: a space, or a letter the tracker uses for warnings (ignored) |
//! | 12 | position x, y, z in inches |
//! | 16 | orientation quaternion w, x, y, z |
//! | 4 | only with IS-900 timestamps: milliseconds since the tracker clock was zeroed |
//! | 1 or 2 | only with a button device: IS-900 bit field (bit i = button i), or a Fastrak stylus pair whose second byte is ASCII `'0'` / `'1'` |
//! | 2 | only with a wand joystick: left/right then up/down, 0 = min, 127 = centre, 255 = max |
//! | 1 | a space |
//!
//! Records follow one another with no line ending in between.

use crate::time::TimeVal;

/// Most stations a driver serves (an IS-900 through the InterSense entry); a Fastrak has 4.
pub const MAX_STATIONS: usize = 8;

/// Length of a record with position and quaternion only.
pub const BASE_LEN: usize = 32;

/// Length of the longest record: timestamp, Fastrak stylus pair and joystick.
pub const MAX_RECORD_LEN: usize = BASE_LEN + 4 + 2 + 2;

/// Inches to metres, computed as C++ does (in double precision) so values match bit for bit.
pub const METRES_PER_INCH: f64 = 2.54 / 100.0;

/// How the buttons of a station are sent, if it has a button device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ButtonFormat {
    /// No button device on this station.
    None,
    /// IS-900 wand or stylus: one byte, bit i is button i (output-list item 22).
    Is900,
    /// Genuine Fastrak stylus: two bytes, the second is ASCII `'0'` or `'1'` (item 16).
    FastrakStylus,
}

/// The layout of one station's records, which the driver selects with an output-list command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StationFormat {
    /// IS-900 hardware timestamp (item 21).
    pub timestamp: bool,
    /// Button bytes.
    pub buttons: ButtonFormat,
    /// Wand joystick bytes (item 23).
    pub joystick: bool,
}

impl StationFormat {
    /// Position and quaternion only.
    pub const PLAIN: StationFormat = StationFormat {
        timestamp: false,
        buttons: ButtonFormat::None,
        joystick: false,
    };

    /// Bytes in one record of this layout.
    pub fn record_len(&self) -> usize {
        let buttons = match self.buttons {
            ButtonFormat::None => 0,
            ButtonFormat::Is900 => 1,
            ButtonFormat::FastrakStylus => 2,
        };
        BASE_LEN + if self.timestamp { 4 } else { 0 } + buttons + if self.joystick { 2 } else { 0 }
    }

    /// The output-list command for `station` (1-based), CR included: items 2 (position),
    /// 11 (quaternion), then 21 (timestamp), 16 or 22 (buttons), 23 (joystick) as needed, and
    /// 0 (the closing space). Example: `O1,2,11,21,22,23,0\r`.
    pub fn output_list_command(&self, station: u8) -> Vec<u8> {
        let mut cmd = format!("O{station},2,11");
        if self.timestamp {
            cmd.push_str(",21");
        }
        match self.buttons {
            ButtonFormat::None => {}
            ButtonFormat::Is900 => cmd.push_str(",22"),
            ButtonFormat::FastrakStylus => cmd.push_str(",16"),
        }
        if self.joystick {
            cmd.push_str(",23");
        }
        cmd.push_str(",0\r");
        cmd.into_bytes()
    }
}

/// One decoded record, values as the tracker sent them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Station, 1-based as on the wire.
    pub station: u8,
    /// The status byte (space or a letter).
    pub status: u8,
    /// Position in inches.
    pub pos_inches: [f32; 3],
    /// Orientation in the tracker's order w, x, y, z.
    pub quat_wxyz: [f32; 4],
    /// Tracker clock in milliseconds, with IS-900 timestamps.
    pub time_ms: Option<f32>,
    /// Button states as a bit field (bit i = button i); a Fastrak stylus sets bit 0 from its
    /// second byte minus `'0'` (any non-zero result is pressed).
    pub buttons: Option<u8>,
    /// Joystick bytes: left/right, up/down.
    pub joystick: Option<[u8; 2]>,
}

fn f32_le(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

impl Record {
    /// Decodes a framed record of `format` (`bytes.len()` is its record length; the framing
    /// has already checked the start, station, status and closing space).
    pub fn decode(bytes: &[u8], format: &StationFormat) -> Record {
        debug_assert_eq!(bytes.len(), format.record_len());
        let pos_inches = [f32_le(bytes, 3), f32_le(bytes, 7), f32_le(bytes, 11)];
        let quat_wxyz = [
            f32_le(bytes, 15),
            f32_le(bytes, 19),
            f32_le(bytes, 23),
            f32_le(bytes, 27),
        ];
        let mut at = 31;
        let time_ms = format.timestamp.then(|| {
            at += 4;
            f32_le(bytes, at - 4)
        });
        let buttons = match format.buttons {
            ButtonFormat::None => None,
            ButtonFormat::Is900 => {
                at += 1;
                Some(bytes[at - 1])
            }
            ButtonFormat::FastrakStylus => {
                at += 2;
                Some(u8::from(bytes[at - 1].wrapping_sub(b'0') != 0))
            }
        };
        let joystick = format.joystick.then(|| {
            at += 2;
            [bytes[at - 2], bytes[at - 1]]
        });
        Record {
            station: bytes[1] - b'0',
            status: bytes[2],
            pos_inches,
            quat_wxyz,
            time_ms,
            buttons,
            joystick,
        }
    }

    /// Position in metres, as VRPN reports it.
    pub fn position_m(&self) -> [f64; 3] {
        self.pos_inches.map(|v| f64::from(v) * METRES_PER_INCH)
    }

    /// Orientation in VRPN's order x, y, z, w, values as received (not normalised).
    pub fn quat_xyzw(&self) -> [f64; 4] {
        let [w, x, y, z] = self.quat_wxyz.map(f64::from);
        [x, y, z, w]
    }
}

/// The offset from the tracker's clock zero that an IS-900 timestamp of `ms` milliseconds
/// stands for, computed in single precision exactly as C++ does: whole seconds truncated from
/// `ms / 1000`, then the truncated microseconds of the remainder.
pub fn is900_offset(ms: f32) -> TimeVal {
    let secs = (ms / 1000.0) as i64;
    let rest = ms - (secs as f32) * 1000.0;
    let usecs = (rest * 1000.0) as i64;
    TimeVal::new(secs, usecs)
}

/// Joystick byte to the raw channel value C++ feeds the clip mapping: (b - 127) / 128.
pub fn joystick_raw(b: u8) -> f64 {
    (f64::from(b) - 127.0) / 128.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_and_output_lists() {
        assert_eq!(StationFormat::PLAIN.record_len(), 32);
        assert_eq!(StationFormat::PLAIN.output_list_command(1), b"O1,2,11,0\r");
        let wand = StationFormat {
            timestamp: true,
            buttons: ButtonFormat::Is900,
            joystick: true,
        };
        assert_eq!(wand.record_len(), 39);
        assert_eq!(wand.output_list_command(1), b"O1,2,11,21,22,23,0\r");
        let stylus = StationFormat {
            timestamp: false,
            buttons: ButtonFormat::FastrakStylus,
            joystick: false,
        };
        assert_eq!(stylus.record_len(), 34);
        assert_eq!(stylus.output_list_command(3), b"O3,2,11,16,0\r");
        let longest = StationFormat {
            timestamp: true,
            buttons: ButtonFormat::FastrakStylus,
            joystick: true,
        };
        assert_eq!(longest.record_len(), MAX_RECORD_LEN);
    }

    #[test]
    fn decodes_every_field() {
        let format = StationFormat {
            timestamp: true,
            buttons: ButtonFormat::Is900,
            joystick: true,
        };
        let mut b = vec![b'0', b'2', b'B'];
        for v in [1.0f32, -2.5, 10.0, 0.5, 0.5, -0.5, 0.5, 1234.5] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&[0b10_0101, 0, 255, b' ']);
        let r = Record::decode(&b, &format);
        assert_eq!(r.station, 2);
        assert_eq!(r.status, b'B');
        assert_eq!(r.pos_inches, [1.0, -2.5, 10.0]);
        assert_eq!(r.position_m(), [0.0254, -2.5 * METRES_PER_INCH, 0.254]);
        assert_eq!(r.quat_xyzw(), [0.5, -0.5, 0.5, 0.5]);
        assert_eq!(r.time_ms, Some(1234.5));
        assert_eq!(r.buttons, Some(0b10_0101));
        assert_eq!(r.joystick, Some([0, 255]));
    }

    #[test]
    fn fastrak_stylus_uses_the_second_byte() {
        let format = StationFormat {
            timestamp: false,
            buttons: ButtonFormat::FastrakStylus,
            joystick: false,
        };
        let mut b = vec![b'0', b'1', b' '];
        b.extend_from_slice(&[0; 28]);
        b.extend_from_slice(b"01 ");
        assert_eq!(Record::decode(&b, &format).buttons, Some(1));
        let n = b.len();
        b[n - 2] = b'0';
        assert_eq!(Record::decode(&b, &format).buttons, Some(0));
    }

    #[test]
    fn is900_time_is_split_in_single_precision() {
        assert_eq!(is900_offset(0.0), TimeVal::new(0, 0));
        assert_eq!(is900_offset(1500.0), TimeVal::new(1, 500_000));
        // 1234.567 as f32 is 1234.5670166…; the remainder 234.56702 ms truncates to 234567 µs.
        assert_eq!(is900_offset(1234.567), TimeVal::new(1, 234_567));
        // Large values lose precision the way C++ does: 100000.1 is 100000.1015625 as f32,
        // whose remainder 0.1015625 ms is 101 µs.
        assert_eq!(is900_offset(100_000.1), TimeVal::new(100, 101));
    }

    #[test]
    fn joystick_bytes_map_around_the_centre() {
        assert_eq!(joystick_raw(127), 0.0);
        assert_eq!(joystick_raw(255), 1.0);
        assert_eq!(joystick_raw(0), -127.0 / 128.0);
    }
}
