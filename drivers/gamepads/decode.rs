//! The report formats of the game controllers, as the C++ drivers read them. Each function
//! decodes one report into the pad state; the arithmetic (integer, single or double
//! precision) is C++'s, so values are bit for bit the same.

use crate::drivers::hid_pad::{
    dpad_angle, le_i16, le_u16, normalize_axis, normalize_byte_axis, PadState, Skip,
};

/// The C++ gamepads' thumb-stick dead zones (XInput's).
pub const LEFT_THUMB_DEADZONE: i32 = 7849;
/// Right stick.
pub const RIGHT_THUMB_DEADZONE: i32 = 8689;
/// Trigger threshold.
pub const TRIGGER_THRESHOLD: i32 = 30;

fn len(report: &[u8], want: usize) -> Result<(), Skip> {
    if report.len() == want {
        Ok(())
    } else {
        Err(Skip::Length(report.len()))
    }
}

/// The eight-way hat as four buttons from `first` (up, right, down, left), from a code that
/// counts clockwise from up at `up_code`; any other code is centred.
fn hat8(s: &mut PadState, first: usize, code: u8, up_code: u8) {
    for b in &mut s.button[first..first + 4] {
        *b = false;
    }
    if let Some(k) = code.checked_sub(up_code).filter(|k| *k < 8) {
        let k = usize::from(k);
        s.button[first + k / 2] = true;
        if k % 2 == 1 {
            s.button[first + (k / 2 + 1) % 4] = true;
        }
    }
}

/// A four-way hat: one bit per direction (1 up, 2 right, 4 down, 8 left); only a single
/// direction counts.
fn hat4(s: &mut PadState, first: usize, nibble: u8) {
    for b in &mut s.button[first..first + 4] {
        *b = false;
    }
    match nibble {
        1 => s.button[first] = true,
        2 => s.button[first + 1] = true,
        4 => s.button[first + 2] = true,
        8 => s.button[first + 3] = true,
        _ => {}
    }
}

fn hat_angle(s: &PadState, first: usize) -> f64 {
    dpad_angle(
        s.button[first],
        s.button[first + 1],
        s.button[first + 2],
        s.button[first + 3],
    )
}

fn bits(s: &mut PadState, first: usize, value: u8, count: usize) {
    for i in 0..count {
        s.button[first + i] = value & (1 << i) != 0;
    }
}

/// Microsoft SideWinder Precision 2: X, Y, twist, slider, 8 buttons, hat (6 bytes).
pub fn sidewinder_precision_2(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 6)?;
    s.channel[0] = normalize_axis(r[0].into(), 8, 1.0, 8);
    s.channel[1] = normalize_axis(r[1].into(), 8, 1.0, 8);
    s.channel[2] = normalize_axis(r[2].into(), 8, 1.0, 8);
    s.channel[3] = normalize_axis(r[3].into(), 8, 1.0, 8);
    bits(s, 0, r[4], 8);
    hat8(s, 8, r[5] >> 4, 0);
    s.channel[4] = hat_angle(s, 8);
    Ok(())
}

/// Microsoft SideWinder: X, Y, slider, 8 buttons (4 bytes).
pub fn sidewinder(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 4)?;
    s.channel[0] = normalize_axis(r[0].into(), 8, 1.0, 8);
    s.channel[1] = normalize_axis(r[1].into(), 8, 1.0, 8);
    s.channel[2] = normalize_axis(r[2].into(), 8, 1.0, 8);
    bits(s, 0, r[3], 8);
    Ok(())
}

/// C++'s conversion of the Xbox S's signed sticks: halved (rounding toward zero), moved to
/// unsigned, optionally doubled, all in 16 bits.
fn xbox_s_axis(r: &[u8], at: usize, double: bool) -> u32 {
    let temp = le_i16(r, at) / 2;
    let x = (temp as i32 + (1 << 15)) as u16;
    u32::from(if double { x.wrapping_mul(2) } else { x })
}

/// Xbox Controller S (through an XBCD-style driver): 40-byte report 1.
pub fn xbox_s(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 40)?;
    if r[0] != 1 {
        return Err(Skip::Kind(r[0]));
    }
    let (x, y) = (xbox_s_axis(r, 4, true), xbox_s_axis(r, 6, true));
    s.channel[0] = normalize_axis(x, LEFT_THUMB_DEADZONE, 1.0, 16);
    s.channel[1] = normalize_axis(y, LEFT_THUMB_DEADZONE, 1.0, 16);
    let (x, y) = (xbox_s_axis(r, 10, false), xbox_s_axis(r, 12, false));
    s.channel[2] = normalize_axis(x, LEFT_THUMB_DEADZONE, 2.0, 16);
    s.channel[3] = normalize_axis(y, LEFT_THUMB_DEADZONE, 2.0, 16);
    bits(s, 0, r[1], 8);
    bits(s, 8, r[2], 4);
    hat8(s, 12, r[18] & 0x0f, 0);
    s.channel[4] = hat_angle(s, 12);
    Ok(())
}

/// C++'s trigger: centred on 0x80, zero within the threshold, else scaled in single
/// precision (left trigger positive, right negative).
fn trigger(v: u8) -> f64 {
    let value = i32::from(v) - 0x80;
    if value.abs() < TRIGGER_THRESHOLD {
        0.0
    } else {
        f64::from(value as f32 * 2.0f32 / 255.0f32)
    }
}

/// Xbox 360 wired and wireless (and compatibles such as the Afterglow AX.1): 14 bytes.
pub fn xbox_360(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 14)?;
    let u = |at: usize| u32::from(le_i16(r, at) as u16);
    s.channel[0] = normalize_axis(u(0), LEFT_THUMB_DEADZONE, 1.0, 16);
    s.channel[1] = normalize_axis(u(2), LEFT_THUMB_DEADZONE, 1.0, 16);
    s.channel[2] = normalize_axis(u(4), RIGHT_THUMB_DEADZONE, 1.0, 16);
    s.channel[3] = normalize_axis(u(6), RIGHT_THUMB_DEADZONE, 1.0, 16);
    s.channel[4] = trigger(r[9]);
    bits(s, 0, r[10], 8);
    bits(s, 8, r[11], 2);
    hat8(s, 10, (r[11] & 0x3c) >> 2, 1);
    s.channel[5] = hat_angle(s, 10);
    Ok(())
}

/// Logitech Extreme 3D Pro: 10-bit X and Y, twist, slider, 12 buttons, hat (7 bytes).
pub fn logitech_extreme_3d_pro(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 7)?;
    let x = (u32::from(r[1] & 0x03) << 8) + u32::from(r[0]);
    let y = (u32::from(r[2] & 0x0f) << 6) + u32::from(r[1] >> 2);
    s.channel[0] = normalize_axis(x, 0x16, 1.0, 10);
    s.channel[1] = normalize_axis(y, 0x16, 1.0, 10);
    s.channel[2] = normalize_axis(r[3].into(), 0x12, 1.0, 8);
    s.channel[3] = normalize_axis(r[5].into(), 0x0e, 1.0, 8);
    bits(s, 0, r[4], 8);
    bits(s, 12, r[6], 4);
    hat8(s, 8, r[2] >> 4, 0);
    s.channel[4] = hat_angle(s, 8);
    Ok(())
}

/// Saitek ST290 Pro: X, Y, twist, slider, 6 buttons, hat (6 bytes).
pub fn saitek_st290_pro(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 6)?;
    s.channel[0] = normalize_axis(r[0].into(), 8, 1.0, 8);
    s.channel[1] = normalize_axis(r[1].into(), 8, 1.0, 8);
    s.channel[2] = normalize_axis(r[2].into(), 8, 1.0, 8);
    s.channel[3] = normalize_axis(r[3].into(), 8, 1.0, 8);
    bits(s, 0, r[4] >> 4, 4);
    bits(s, 4, r[5] & 0x0f, 4);
    // The hat takes buttons 6-9 (overwriting 6 and 7), and C++ computes its angle from
    // buttons 7-10: kept, so clients see the same angle.
    hat8(s, 6, r[4] & 0x0f, 1);
    s.channel[4] = dpad_angle(s.button[7], s.button[8], s.button[9], s.button[10]);
    Ok(())
}

/// CH Products Fighterstick USB: X, Y, throttle, 4 buttons, an 8-way and three 4-way hats,
/// mode switch (6 bytes).
pub fn ch_fighterstick(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 6)?;
    s.channel[0] = normalize_axis(r[0].into(), 8, 1.0, 8);
    s.channel[1] = normalize_axis(r[1].into(), 8, 1.0, 8);
    s.channel[2] = normalize_axis(r[2].into(), 8, 1.0, 8);
    bits(s, 0, r[3] >> 4, 4);
    hat8(s, 4, r[3] & 0x0f, 1);
    s.channel[3] = hat_angle(s, 4);
    hat4(s, 8, r[4] >> 4);
    s.channel[4] = hat_angle(s, 8);
    hat4(s, 12, r[4] & 0x0f);
    s.channel[5] = hat_angle(s, 12);
    // The mode switch: green, red, yellow; any other value leaves the last mode.
    let mode = match r[5] >> 4 {
        1 => Some(16),
        2 => Some(17),
        4 => Some(18),
        _ => None,
    };
    if let Some(m) = mode {
        for b in 16..19 {
            s.button[b] = b == m;
        }
    }
    if s.button[16..20].iter().any(|b| *b) {
        s.channel[6] = hat_angle(s, 16) / 90.0 + 1.0;
    }
    hat4(s, 20, r[5] & 0x0f);
    s.channel[7] = hat_angle(s, 20);
    Ok(())
}

fn retrolink_axis(v: u8) -> f64 {
    ((f64::from(v) - 128.0) / 127.0).clamp(-1.0, 1.0)
}

/// The Retrolinks' rocker: 0-7 clockwise from up, anything else centred. Sets the angle and
/// four direction buttons from `first`.
fn rocker(s: &mut PadState, first: usize, value: u8) -> f64 {
    hat8(s, first, value, 0);
    if value < 8 {
        45.0 * f64::from(value)
    } else {
        -1.0
    }
}

/// Retrolink GameCube adapter: two sticks, 8 buttons, rocker (8 bytes).
pub fn retrolink_gamecube(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 8)?;
    s.channel[0] = retrolink_axis(r[0]);
    s.channel[1] = retrolink_axis(r[1]);
    s.channel[2] = retrolink_axis(r[3]);
    s.channel[3] = retrolink_axis(r[4]);
    for (b, (byte, bit)) in [
        (5, 4),
        (5, 5),
        (5, 6),
        (5, 7),
        (6, 0),
        (6, 1),
        (6, 2),
        (6, 5),
    ]
    .into_iter()
    .enumerate()
    {
        s.button[b] = r[byte] & (1 << bit) != 0;
    }
    s.channel[4] = rocker(s, 8, r[5] & 0x0f);
    Ok(())
}

/// Retrolink Genesis adapter: 8 buttons, a rocker given as two axis bytes (8 bytes).
pub fn retrolink_genesis(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 8)?;
    for (b, (byte, bit)) in [
        (5, 6),
        (5, 5),
        (6, 1),
        (5, 7),
        (5, 4),
        (6, 0),
        (6, 4),
        (6, 5),
    ]
    .into_iter()
    .enumerate()
    {
        s.button[b] = r[byte] & (1 << bit) != 0;
    }
    let value = match (r[3], r[4]) {
        (0x00, 0x00) => 7,
        (0x00, 0x7f) => 6,
        (0x00, 0xff) => 5,
        (0x7f, 0x00) => 0,
        (0x7f, 0xff) => 4,
        (0xff, 0x00) => 1,
        (0xff, 0x7f) => 2,
        (0xff, 0xff) => 3,
        _ => 8,
    };
    s.channel[0] = rocker(s, 8, value);
    Ok(())
}

/// Futaba InterLink Elite (an RC transmitter as a USB joystick): report 5, 8 bytes.
pub fn futaba_interlink_elite(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    len(r, 8)?;
    if r[0] != 5 {
        return Err(Skip::Kind(r[0]));
    }
    let scale = f64::from(1.0f32 / 0.70f32);
    s.channel[0] = normalize_byte_axis(r[5].into(), 5, scale);
    s.channel[1] = normalize_byte_axis(r[3].into(), 5, scale);
    s.channel[2] = normalize_byte_axis(r[1].into(), 5, scale);
    s.channel[3] = normalize_byte_axis(r[2].into(), 5, scale);
    s.channel[4] = normalize_byte_axis(r[4].into(), 5, 1.0);
    bits(s, 0, r[7], 8);
    // Byte 6 packs ten switch positions as overlapping bit patterns; C++ peels them off
    // from the widest.
    let mut value = r[6];
    const PATTERNS: [u8; 10] = [0xa2, 0x51, 0x36, 0x1b, 0x12, 0x09, 0x06, 0x03, 0x02, 0x01];
    for (i, p) in PATTERNS.into_iter().enumerate() {
        let on = value & p == p;
        if on {
            value ^= p;
        }
        s.button[17 - i] = on;
    }
    Ok(())
}

/// The Shields' hat byte: four direction buttons from 16 and channels 8 (X) and 9 (Y).
fn shield_hat(s: &mut PadState, code: u8) {
    hat8(s, 16, code, 0);
    let (x, y) = match code {
        0 => (0.0, -1.0),
        1 => (1.0, -1.0),
        2 => (1.0, 0.0),
        3 => (1.0, 1.0),
        4 => (0.0, 1.0),
        5 => (-1.0, 1.0),
        6 => (-1.0, 0.0),
        7 => (-1.0, -1.0),
        _ => (0.0, 0.0),
    };
    s.channel[8] = x;
    s.channel[9] = y;
}

fn shield_sticks(r: &[u8], s: &mut PadState, axes_at: usize, triggers_at: usize) {
    for k in 0..4 {
        let raw = i32::from(le_u16(r, axes_at + 2 * k));
        s.channel[k] = f64::from(raw - 32767) / 32768.0;
    }
    for k in 0..2 {
        s.channel[4 + k] = f64::from(le_u16(r, triggers_at + 2 * k)) / 65535.0;
    }
}

/// nVidia Shield controller (original), over USB: report 1 (16 bytes) and report 2.
pub fn shield(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    match r.first() {
        Some(2) if r.len() >= 6 => {
            s.button[8] = r[1] & 0x01 != 0;
            s.button[20] = r[1] & 0x80 != 0;
            s.channel[6] = f64::from(r[2]) / 255.0;
            s.channel[7] = f64::from(r[4]) / 255.0;
        }
        Some(1) if r.len() == 16 => {
            bits(s, 0, r[1], 8);
            bits(s, 8, r[2], 8);
            shield_hat(s, r[3]);
            shield_sticks(r, s, 4, 12);
        }
        Some(k) => return Err(Skip::Kind(*k)),
        None => return Err(Skip::Length(0)),
    }
    Ok(())
}

/// nVidia Shield controller (2017, "stealth"), over USB: report 1, at least 33 bytes.
pub fn shield_stealth(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    match r.first() {
        Some(1) if r.len() >= 33 => {
            bits(s, 0, r[3], 8);
            s.button[9] = r[4] & 0x01 != 0;
            s.button[12] = r[17] & 0x01 != 0;
            s.button[11] = r[17] & 0x02 != 0;
            s.button[13] = r[17] & 0x04 != 0;
            shield_hat(s, r[2]);
            shield_sticks(r, s, 9, 5);
        }
        Some(k) => return Err(Skip::Kind(*k)),
        None => return Err(Skip::Length(0)),
    }
    Ok(())
}
