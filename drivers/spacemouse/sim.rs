//! The reports a 3Dconnexion device sends, byte for byte, for simulators and tests.

use super::{Layout, Model};

/// Translation report: `01`, X, Y, Z as little-endian `i16`.
pub fn translation(x: i16, y: i16, z: i16) -> Vec<u8> {
    axes(1, &[x, y, z])
}

/// Rotation report: `02`, A, B, C as little-endian `i16`.
pub fn rotation(a: i16, b: i16, c: i16) -> Vec<u8> {
    axes(2, &[a, b, c])
}

/// The SpaceMouse Pro Wireless's 13-byte report 1: all six axes.
pub fn six_axes(v: [i16; 6]) -> Vec<u8> {
    axes(1, &v)
}

fn axes(id: u8, v: &[i16]) -> Vec<u8> {
    let mut r = vec![id];
    for a in v {
        r.extend_from_slice(&a.to_le_bytes());
    }
    r
}

/// Button report for `model`: `03` and one bit per button, as many bytes as the model's
/// buttons need (13 bytes in all on the SpaceMouse Pro Wireless).
pub fn buttons(model: &Model, pressed: u32) -> Vec<u8> {
    let mut r = vec![3];
    let bytes = model.buttons.div_ceil(8);
    r.extend_from_slice(&pressed.to_le_bytes()[..bytes.min(4)]);
    if model.layout == Layout::ProWireless {
        r.resize(13, 0);
    }
    r
}

/// The SpaceMouse Pro Wireless's report 0x17 (sent after some data; ignored).
pub fn report_0x17() -> Vec<u8> {
    let mut r = vec![0x17];
    r.resize(13, 0);
    r
}

/// A few reports exercising every axis and some buttons of `model`.
pub fn samples(model: &Model) -> Vec<Vec<u8>> {
    match model.layout {
        Layout::Classic => vec![
            translation(100, -250, 401),
            rotation(-401, 7, -32768),
            buttons(model, 0b101),
            translation(0, 0, -3),
            buttons(model, 1 << (model.buttons - 1)),
        ],
        Layout::ProWireless => vec![
            six_axes([350, -175, 1, -351, 0, 12]),
            buttons(model, 1 << 31 | 1),
            report_0x17(),
            buttons(model, 0),
        ],
    }
}
