//! Commands to the unit and its wireless dongle, as bytes (pure).
//!
//! * A binary command to a wired unit or to the dongle itself: `F7`, the command byte, its
//!   arguments (big-endian), and a checksum: the sum of the command byte and arguments,
//!   modulo 256 (the start byte is not counted).
//! * A binary command to a wireless unit through the dongle: `F8`, the unit's logical id
//!   (0–14, the slot it is paired in), the command byte, its arguments, and the checksum of
//!   everything after `F8`. The dongle answers every such command with a header: a status
//!   byte (0 = done), the logical id and the length of the data that follows; a failed
//!   command is answered by the status and the id alone.
//! * An ASCII command (the `vrpn.cfg` reset lines, decimal, e.g. `238,1,1,0`): `:` command
//!   `\n` to a wired unit, `>` id `,` command `\n` to a wireless one (which answers a line
//!   starting with its status, `0` when done); both followed by a NUL byte, as C++ sends
//!   them.

use super::record::SLOTS;

/// Start of a binary command to a wired unit or to the dongle.
pub const START_WIRED: u8 = 0xF7;
/// Start of a binary command to a wireless unit through the dongle.
pub const START_WIRELESS: u8 = 0xF8;

/// Stop streaming.
pub const STOP_STREAMING: u8 = 0x56;
/// Start streaming.
pub const START_STREAMING: u8 = 0x55;
/// Read the LED mode (answer: one byte).
pub const GET_LED_MODE: u8 = 0xC8;
/// Read the LED colour (answer: three floats).
pub const GET_LED_COLOR: u8 = 0xEF;
/// Set the LED mode (one byte).
pub const SET_LED_MODE: u8 = 0xC4;
/// Set the LED colour (three floats, 0–1).
pub const SET_LED_COLOR: u8 = 0xEE;
/// Calibrate the gyroscopes (the unit must be still).
pub const CALIBRATE_GYROS: u8 = 0xA5;
/// Tare with the current orientation.
pub const TARE: u8 = 0x60;
/// Choose the axis directions (argument 1: x right, z up, right-handed).
pub const SET_AXES: u8 = 0x74;
/// Streaming timing: interval µs, duration µs, delay µs.
pub const SET_TIMING: u8 = 0x52;
/// Streaming slots: eight command bytes.
pub const SET_SLOTS: u8 = 0x50;
/// Dongle: wireless streaming mode (argument 0: manual flush).
pub const SET_WIRELESS_MODE: u8 = 0xB0;
/// Dongle: release the oldest record held for a logical id.
pub const FLUSH_ONE: u8 = 0xB4;

/// The checksum of a command's bytes.
pub fn checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b))
}

/// Appends a binary command to a wired unit or to the dongle: `F7 cmd args.. sum`.
pub fn wired(cmd: &[u8], out: &mut Vec<u8>) {
    out.push(START_WIRED);
    out.extend_from_slice(cmd);
    out.push(checksum(cmd));
}

/// Appends a binary command to the wireless unit at `id`: `F8 id cmd args.. sum`.
pub fn wireless(id: u8, cmd: &[u8], out: &mut Vec<u8>) {
    out.push(START_WIRELESS);
    out.push(id);
    out.extend_from_slice(cmd);
    out.push(id.wrapping_add(checksum(cmd)));
}

/// Appends an ASCII command to a wired unit: `:cmd\n` and a NUL.
pub fn ascii_wired(cmd: &str, out: &mut Vec<u8>) {
    out.push(b':');
    out.extend_from_slice(cmd.as_bytes());
    out.extend_from_slice(b"\n\0");
}

/// Appends an ASCII command to the wireless unit at `id`: `>id,cmd\n` and a NUL.
pub fn ascii_wireless(id: u8, cmd: &str, out: &mut Vec<u8>) {
    out.push(b'>');
    out.extend_from_slice(id.to_string().as_bytes());
    out.push(b',');
    out.extend_from_slice(cmd.as_bytes());
    out.extend_from_slice(b"\n\0");
}

/// The LED-colour command's bytes.
pub fn set_led_color(rgb: [f32; 3]) -> [u8; 13] {
    let mut c = [0u8; 13];
    c[0] = SET_LED_COLOR;
    for (i, v) in rgb.iter().enumerate() {
        c[1 + 4 * i..5 + 4 * i].copy_from_slice(&v.to_be_bytes());
    }
    c
}

/// The streaming interval for `frames_per_second`, in µs (0, as fast as the unit can, for a
/// rate that is not positive, as C++ does).
pub fn interval_us(frames_per_second: f64) -> u32 {
    if frames_per_second > 0.0 {
        (1e6 / frames_per_second) as u32
    } else {
        0
    }
}

/// The streaming-timing command: `interval` µs, forever (`FFFFFFFF`), no delay.
pub fn set_timing(interval: u32) -> [u8; 13] {
    let mut c = [0u8; 13];
    c[0] = SET_TIMING;
    c[1..5].copy_from_slice(&interval.to_be_bytes());
    c[5..9].copy_from_slice(&u32::MAX.to_be_bytes());
    c
}

/// The streaming-slots command.
pub fn set_slots() -> [u8; 9] {
    let mut c = [0u8; 9];
    c[0] = SET_SLOTS;
    c[1..].copy_from_slice(&SLOTS);
    c
}

/// How a command is answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// Binary: this many data bytes (after the header, on a wireless unit).
    Data(usize),
    /// ASCII: a line (wireless units only; a wired unit answers nothing).
    Line,
}

/// One command of a reset: its bytes (without framing) and how it is answered.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// A binary command: command byte and arguments.
    Binary(Vec<u8>),
    /// An ASCII command from `vrpn.cfg`.
    Ascii(String),
}

impl Step {
    /// How the unit answers it.
    pub fn answer(&self) -> Answer {
        match self {
            Step::Binary(c) if c[0] == GET_LED_MODE => Answer::Data(1),
            Step::Binary(c) if c[0] == GET_LED_COLOR => Answer::Data(12),
            Step::Binary(_) => Answer::Data(0),
            Step::Ascii(_) => Answer::Line,
        }
    }

    /// Appends it as sent to a wired unit.
    pub fn wired(&self, out: &mut Vec<u8>) {
        match self {
            Step::Binary(c) => wired(c, out),
            Step::Ascii(s) => ascii_wired(s, out),
        }
    }

    /// Appends it as sent to the wireless unit at `id`.
    pub fn wireless(&self, id: u8, out: &mut Vec<u8>) {
        match self {
            Step::Binary(c) => wireless(id, c, out),
            Step::Ascii(s) => ascii_wireless(id, s, out),
        }
    }
}

/// What a unit is told once after its port opens (C++ says it once, at start-up): the LED
/// mode and colour, then the gyro calibration and the tare if asked for.
pub fn setup_steps(u: &super::config::Unit) -> Vec<Step> {
    let mut s = vec![
        Step::Binary(vec![SET_LED_MODE, u.led_mode]),
        Step::Binary(set_led_color(u.led_color).to_vec()),
    ];
    if u.calibrate_gyros {
        s.push(Step::Binary(vec![CALIBRATE_GYROS]));
    }
    if u.tare {
        s.push(Step::Binary(vec![TARE]));
    }
    s
}

/// The reset after streaming has been stopped and the input flushed: read back the LED
/// mode and colour (the answer proves the unit is there), set the axes, the timing and the
/// slots, send the `vrpn.cfg` commands, start streaming.
pub fn reset_steps(u: &super::config::Unit) -> Vec<Step> {
    let mut s = vec![
        Step::Binary(vec![GET_LED_MODE]),
        Step::Binary(vec![GET_LED_COLOR]),
        Step::Binary(vec![SET_AXES, 0x01]),
        Step::Binary(set_timing(interval_us(u.frames_per_second)).to_vec()),
        Step::Binary(set_slots().to_vec()),
    ];
    s.extend(u.reset_commands.iter().cloned().map(Step::Ascii));
    s.push(Step::Binary(vec![START_STREAMING]));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_and_checksums() {
        let mut out = Vec::new();
        wired(&[STOP_STREAMING], &mut out);
        assert_eq!(out, [0xF7, 0x56, 0x56]);
        out.clear();
        wired(&[SET_AXES, 1], &mut out);
        assert_eq!(out, [0xF7, 0x74, 0x01, 0x75]);
        out.clear();
        wireless(3, &[GET_LED_MODE], &mut out);
        assert_eq!(out, [0xF8, 3, 0xC8, 0xCB]);
        out.clear();
        wired(&[FLUSH_ONE, 14], &mut out);
        assert_eq!(out, [0xF7, 0xB4, 14, 0xC2]);
        out.clear();
        ascii_wireless(1, "238,0,1,1", &mut out);
        assert_eq!(out, b">1,238,0,1,1\n\0");
        out.clear();
        ascii_wired("238,1,1,0", &mut out);
        assert_eq!(out, b":238,1,1,0\n\0");
        assert_eq!(interval_us(200.0), 5000);
        assert_eq!(interval_us(0.0), 0);
        assert_eq!(
            &set_timing(5000)[1..9],
            &[0, 0, 0x13, 0x88, 0xFF, 0xFF, 0xFF, 0xFF]
        );
        assert_eq!(
            set_slots(),
            [0x50, 0x06, 0x00, 0x29, 0x25, 0x2B, 0x2D, 0xFA, 0xFF]
        );
    }
}
