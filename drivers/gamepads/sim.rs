//! The reports the game controllers send, byte for byte (what hidraw returns for one read:
//! no report id unless the device numbers its reports). Hat codes are as on the wire.

/// SideWinder Precision 2: X, Y, twist, slider, buttons 1-8, hat in the high nibble (8 =
/// centred).
pub fn sidewinder_precision_2(axes: [u8; 4], buttons: u8, hat: u8) -> Vec<u8> {
    vec![axes[0], axes[1], axes[2], axes[3], buttons, hat << 4]
}

/// SideWinder: X, Y, slider, buttons 1-8.
pub fn sidewinder(axes: [u8; 3], buttons: u8) -> Vec<u8> {
    vec![axes[0], axes[1], axes[2], buttons]
}

/// Xbox Controller S report 1 (40 bytes): 12 buttons, sticks as signed 16-bit at 4, 6
/// (left) and 10, 12 (right), the hat's low nibble at 18 (8 = centred).
pub fn xbox_s(left: [i16; 2], right: [i16; 2], buttons: u16, hat: u8) -> Vec<u8> {
    let mut r = vec![0u8; 40];
    r[0] = 1;
    r[1] = buttons as u8;
    r[2] = (buttons >> 8) as u8 & 0x0f;
    r[4..6].copy_from_slice(&left[0].to_le_bytes());
    r[6..8].copy_from_slice(&left[1].to_le_bytes());
    r[10..12].copy_from_slice(&right[0].to_le_bytes());
    r[12..14].copy_from_slice(&right[1].to_le_bytes());
    r[18] = 0xf0 | (hat & 0x0f);
    r
}

/// Xbox 360 as its HID report (14 bytes): sticks as unsigned 16-bit centred on 0x8000, the
/// triggers' combined axis at 9 (0x80 at rest), buttons at 10, stick clicks and the hat (1-8
/// clockwise from up, 0 centred) at 11.
pub fn xbox_360(
    left: [u16; 2],
    right: [u16; 2],
    triggers: u8,
    buttons: u8,
    clicks: u8,
    hat: u8,
) -> Vec<u8> {
    let mut r = vec![0u8; 14];
    for (i, v) in [left[0], left[1], right[0], right[1]]
        .into_iter()
        .enumerate()
    {
        r[2 * i..2 * i + 2].copy_from_slice(&v.to_le_bytes());
    }
    r[8] = 0x80;
    r[9] = triggers;
    r[10] = buttons;
    r[11] = (clicks & 0x03) | (hat << 2);
    r
}

/// Logitech Extreme 3D Pro (7 bytes): 10-bit X and Y packed, hat (8 = centred), twist,
/// buttons 1-8, slider, buttons 9-12.
pub fn logitech_extreme_3d_pro(
    x: u16,
    y: u16,
    twist: u8,
    slider: u8,
    buttons: u16,
    hat: u8,
) -> Vec<u8> {
    vec![
        x as u8,
        ((x >> 8) as u8 & 0x03) | ((y as u8 & 0x3f) << 2),
        ((y >> 6) as u8 & 0x0f) | (hat << 4),
        twist,
        buttons as u8,
        slider,
        (buttons >> 8) as u8 & 0x0f,
    ]
}

/// Saitek ST290 Pro (6 bytes): X, Y, twist, slider, buttons 1-4 over the hat (1-8, 0
/// centred), 0xf0 over buttons 5-8.
pub fn saitek_st290_pro(axes: [u8; 4], buttons: u8, hat: u8) -> Vec<u8> {
    vec![
        axes[0],
        axes[1],
        axes[2],
        axes[3],
        (buttons << 4) | (hat & 0x0f),
        0xf0 | (buttons >> 4),
    ]
}

/// CH Fighterstick (6 bytes): X, Y, throttle, buttons over the 8-way hat (1-8), hat 2 over
/// hat 1, mode over hat 3 (4-way hats: 1 up, 2 right, 4 down, 8 left).
pub fn ch_fighterstick(axes: [u8; 3], buttons: u8, hat: u8, hats: [u8; 3], mode: u8) -> Vec<u8> {
    vec![
        axes[0],
        axes[1],
        axes[2],
        (buttons << 4) | hat,
        (hats[1] << 4) | hats[0],
        (mode << 4) | hats[2],
    ]
}

/// Retrolink GameCube (8 bytes): sticks at 0, 1, 3, 4; byte 5 buttons 1-4 over the rocker
/// (0-7, 15 centred); byte 6 buttons 5-7 in bits 0-2 and button 8 in bit 5.
pub fn retrolink_gamecube(axes: [u8; 4], buttons: u8, rocker: u8) -> Vec<u8> {
    vec![
        axes[0],
        axes[1],
        0x80,
        axes[2],
        axes[3],
        ((buttons & 0x0f) << 4) | (rocker & 0x0f),
        ((buttons >> 4) & 0x07) | ((buttons >> 7) << 5),
        0,
    ]
}

/// Retrolink Genesis (8 bytes): the pad's direction as two axis bytes (0x00, 0x7f, 0xff),
/// buttons 1-8 spread over bytes 5 and 6 as the adapter does.
pub fn retrolink_genesis(buttons: u8, direction: Option<u8>) -> Vec<u8> {
    let (x, y) = match direction {
        Some(0) => (0x7f, 0x00),
        Some(1) => (0xff, 0x00),
        Some(2) => (0xff, 0x7f),
        Some(3) => (0xff, 0xff),
        Some(4) => (0x7f, 0xff),
        Some(5) => (0x00, 0xff),
        Some(6) => (0x00, 0x7f),
        Some(7) => (0x00, 0x00),
        _ => (0x7f, 0x7f),
    };
    let mut r = vec![0x01, 0x7f, 0x7f, x, y, 0x0f, 0, 0];
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
        if buttons & (1 << b) != 0 {
            r[byte] |= 1 << bit;
        }
    }
    r
}

/// Futaba InterLink Elite report 5 (8 bytes): aileron, elevator, throttle, flaps, rudder,
/// the packed switch byte, buttons.
pub fn futaba(
    aileron: u8,
    elevator: u8,
    throttle: u8,
    flaps: u8,
    rudder: u8,
    switches: u8,
    buttons: u8,
) -> Vec<u8> {
    vec![
        5, aileron, elevator, throttle, flaps, rudder, switches, buttons,
    ]
}

/// nVidia Shield report 1 (16 bytes): buttons 0-15, hat (0-7, 8 centred), sticks and
/// triggers as unsigned 16-bit.
pub fn shield(buttons: u16, hat: u8, sticks: [u16; 4], triggers: [u16; 2]) -> Vec<u8> {
    let mut r = vec![1];
    r.extend_from_slice(&buttons.to_le_bytes());
    r.push(hat);
    for v in sticks.iter().chain(triggers.iter()) {
        r.extend_from_slice(&v.to_le_bytes());
    }
    r
}

/// nVidia Shield report 2 (6 bytes): two buttons and two 8-bit values.
pub fn shield_report2(button8: bool, button20: bool, a: u8, b: u8) -> Vec<u8> {
    vec![2, u8::from(button8) | (u8::from(button20) << 7), a, 0, b, 0]
}

/// nVidia Shield 2017 report 1 (33 bytes): hat at 2, buttons 0-7 at 3, button 9 at 4,
/// triggers at 5, sticks at 9, buttons 12, 11, 13 at 17.
pub fn shield_stealth(
    buttons: u8,
    button9: bool,
    extra: u8,
    hat: u8,
    sticks: [u16; 4],
    triggers: [u16; 2],
) -> Vec<u8> {
    let mut r = vec![0u8; 33];
    r[0] = 1;
    r[2] = hat;
    r[3] = buttons;
    r[4] = u8::from(button9);
    for (i, v) in triggers.iter().enumerate() {
        r[5 + 2 * i..7 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    for (i, v) in sticks.iter().enumerate() {
        r[9 + 2 * i..11 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    r[17] = extra;
    r
}

/// A few reports exercising the axes, buttons and hats of the controller `keyword` names.
pub fn samples(keyword: &str) -> Vec<Vec<u8>> {
    match keyword {
        "vrpn_Microsoft_SideWinder_Precision_2" => vec![
            sidewinder_precision_2([0, 255, 131, 200], 0x81, 3),
            sidewinder_precision_2([128; 4], 0, 8),
        ],
        "vrpn_Microsoft_SideWinder" => {
            vec![sidewinder([140, 10, 128], 0x02), sidewinder([0; 3], 0x80)]
        }
        "vrpn_Microsoft_Controller_Raw_Xbox_S" => vec![
            xbox_s([32767, -32768], [16000, 0], 0x0a05, 5),
            xbox_s([0; 2], [-20000, 30000], 0, 8),
        ],
        "vrpn_Microsoft_Controller_Raw_Xbox_360"
        | "vrpn_Microsoft_Controller_Raw_Xbox_360_Wireless"
        | "vrpn_Afterglow_Ax1_For_Xbox_360" => vec![
            xbox_360(
                [0x8000, 0x8000 + 20000],
                [0x8000 + 9000, 0x8000 - 9000],
                0xff,
                0x11,
                0x02,
                6,
            ),
            xbox_360([0x8000; 2], [0x8000; 2], 0x10, 0, 0, 0),
        ],
        "vrpn_Logitech_Extreme_3D_Pro" => vec![
            logitech_extreme_3d_pro(1023, 0, 148, 0, 0x0801, 7),
            logitech_extreme_3d_pro(512, 512, 128, 128, 0, 8),
        ],
        "vrpn_Saitek_ST290_Pro" => vec![
            saitek_st290_pro([0, 64, 128, 255], 0x31, 1),
            saitek_st290_pro([128; 4], 0, 6),
        ],
        "vrpn_CHProducts_Fighterstick_USB" => vec![
            ch_fighterstick([128, 0, 255], 0x9, 2, [8, 1, 4], 2),
            ch_fighterstick([128; 3], 0, 0, [0; 3], 4),
        ],
        "vrpn_Retrolink_GameCube" => vec![
            retrolink_gamecube([0, 255, 128, 1], 0x9f, 3),
            retrolink_gamecube([128; 4], 0, 15),
        ],
        "vrpn_Retrolink_Genesis" => {
            vec![retrolink_genesis(0xa5, Some(5)), retrolink_genesis(0, None)]
        }
        "vrpn_Futaba_InterLink_Elite" => vec![
            futaba(128, 200, 10, 130, 255, 0xa2 | 0x09, 0x41),
            futaba(0, 128, 255, 200, 128, 0x03, 0),
        ],
        "vrpn_nVidia_shield_USB" => vec![
            shield(0x8001, 7, [65535, 0, 32767, 32768], [65535, 0]),
            shield_report2(true, true, 255, 51),
            shield(0, 8, [32767; 4], [0, 0]),
        ],
        "vrpn_nVidia_shield_stealth_USB" => vec![
            shield_stealth(0x03, true, 0x05, 2, [0, 65535, 1, 2], [0, 65535]),
            shield_stealth(0, false, 0, 8, [32767; 4], [0; 2]),
        ],
        _ => Vec::new(),
    }
}
