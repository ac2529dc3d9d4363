//! The reports these devices send, byte for byte.

use super::{Kind, Model};

/// A Contour's 5-byte report: shuttle (−7…7), jog position (wraps), 0, then the buttons —
/// ShuttleXpress: 4 in bits 4-7 of byte 3 and 1 in bit 0 of byte 4; ShuttlePRO v2: 16 in
/// bytes 3 and 4.
pub fn contour(kind: Kind, shuttle: i8, jog: u8, buttons: u16) -> Vec<u8> {
    let (b3, b4) = match kind {
        Kind::ShuttleXpress => (((buttons & 0x0f) << 4) as u8, ((buttons >> 4) & 1) as u8),
        _ => (buttons as u8, (buttons >> 8) as u8),
    };
    vec![shuttle as u8, jog, 0, b3, b4]
}

/// A PowerMate's 6-byte report: the button, the turn in ticks (signed).
pub fn powermate(pressed: bool, ticks: i8) -> Vec<u8> {
    vec![u8::from(pressed), ticks as u8, 0, 0, 0, 0]
}

/// A drum kit's 8-byte report: eight samples of the six pads, `hits[i]` of them with pad
/// `i` down.
pub fn drums(hits: [usize; 6]) -> Vec<u8> {
    let mut r = vec![0u8; 8];
    for (pad, n) in hits.iter().enumerate() {
        for b in r.iter_mut().take((*n).min(8)) {
            *b |= 1 << pad;
        }
    }
    r
}

/// A few reports exercising `model`.
pub fn samples(model: &Model) -> Vec<Vec<u8>> {
    match model.kind {
        Kind::ShuttleXpress | Kind::ShuttlePro2 => vec![
            contour(model.kind, 3, 250, 0b10001),
            contour(model.kind, -7, 2, 0b01010),
            contour(model.kind, 7, 255, 0x4000),
        ],
        Kind::PowerMate => vec![powermate(true, 3), powermate(false, -2)],
        Kind::Drums => vec![drums([8, 3, 4, 0, 0, 5]), drums([0; 6])],
    }
}
