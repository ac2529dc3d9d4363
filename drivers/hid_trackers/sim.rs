//! The reports the HID trackers send, byte for byte.

/// A SpacePoint report (15 bytes): the quaternion x, y, z, w as `u16` (32768 = 0) from byte
/// 6, buttons in byte 14.
pub fn spacepoint(quat: [u16; 4], buttons: u8) -> Vec<u8> {
    let mut r = vec![0u8; 15];
    for (i, q) in quat.iter().enumerate() {
        r[6 + 2 * i..8 + 2 * i].copy_from_slice(&q.to_le_bytes());
    }
    r[14] = buttons;
    r
}

/// A WinTracker record (24 bytes): type, sensor character, position (1/10000 m), azimuth,
/// elevation, roll, quaternion w, x, y, z (1/10000).
pub fn wintracker(sensor: u8, pos: [i16; 3], quat_wxyz: [i16; 4]) -> Vec<u8> {
    let mut r = vec![0u8; 24];
    r[0] = b'P';
    r[1] = sensor;
    for k in 0..3 {
        r[2 + 2 * k..4 + 2 * k].copy_from_slice(&pos[k].to_le_bytes());
    }
    for k in 0..4 {
        r[14 + 2 * k..16 + 2 * k].copy_from_slice(&quat_wxyz[k].to_le_bytes());
    }
    r
}

/// One Hydra wand's raw values.
#[derive(Clone, Copy, Debug, Default)]
pub struct WandRaw {
    /// Position, mm.
    pub pos: [i16; 3],
    /// Orientation w, x, y, z as sent (y and z are negated on the host), 32768 = 1.
    pub quat_wxyz: [i16; 4],
    /// Buttons byte.
    pub buttons: u8,
    /// Joystick x, y.
    pub stick: [i16; 2],
    /// Trigger.
    pub trigger: u8,
}

/// A Hydra motion report (52 bytes): the two wands at bytes 8 and 30.
pub fn hydra(wands: [WandRaw; 2]) -> Vec<u8> {
    let mut r = vec![0u8; 52];
    for (s, w) in wands.iter().enumerate() {
        let b = 8 + 22 * s;
        for k in 0..3 {
            r[b + 2 * k..b + 2 * k + 2].copy_from_slice(&w.pos[k].to_le_bytes());
        }
        for k in 0..4 {
            r[b + 6 + 2 * k..b + 8 + 2 * k].copy_from_slice(&w.quat_wxyz[k].to_le_bytes());
        }
        r[b + 14] = w.buttons;
        r[b + 15..b + 17].copy_from_slice(&w.stick[0].to_le_bytes());
        r[b + 17..b + 19].copy_from_slice(&w.stick[1].to_le_bytes());
        r[b + 19] = w.trigger;
    }
    r
}

/// The Hydra's feature report 0 as a device answers it: its serial number at offset 216.
pub fn hydra_feature(serial: &str, len: usize) -> Vec<u8> {
    let mut r = vec![0u8; len];
    for (i, b) in serial.bytes().take(17).enumerate() {
        if 216 + i < len {
            r[216 + i] = b;
        }
    }
    r
}
