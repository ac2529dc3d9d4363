//! Every controller's reports decoded from the simulator's bytes, against values computed
//! here from the C++ formulas.

use super::decode::*;
use super::sim;
use super::{model, parse_hex_id, MODELS};
use crate::drivers::hid_pad::{PadState, Skip};

fn on(s: &PadState, n: usize) -> Vec<usize> {
    (0..n).filter(|&i| s.button[i]).collect()
}

/// C++'s 8-bit axis with dead zone 8: (v − 128) / 128, zero when |v − 128| < 6.
fn axis8(v: u8) -> f64 {
    let d = f64::from(v) - 128.0;
    if d.abs() < 6.0 {
        0.0
    } else {
        d / 128.0
    }
}

#[test]
fn sidewinders() {
    let mut s = PadState::default();
    sidewinder_precision_2(
        &sim::sidewinder_precision_2([0, 255, 131, 200], 0x81, 3),
        &mut s,
    )
    .unwrap();
    assert_eq!(s.channel[..4], [-1.0, axis8(255), 0.0, axis8(200)]);
    assert_eq!(on(&s, 12), vec![0, 7, 9, 10]);
    assert_eq!(s.channel[4], 135.0);
    sidewinder_precision_2(&sim::sidewinder_precision_2([128; 4], 0, 8), &mut s).unwrap();
    assert_eq!(s.channel[4], -1.0);
    assert_eq!(on(&s, 12), Vec::<usize>::new());
    assert_eq!(
        sidewinder_precision_2(&[0; 7], &mut s),
        Err(Skip::Length(7))
    );
    let mut s = PadState::default();
    sidewinder(&sim::sidewinder([140, 10, 128], 0x02), &mut s).unwrap();
    assert_eq!(s.channel[..3], [axis8(140), axis8(10), 0.0]);
    assert_eq!(on(&s, 8), vec![1]);
}

#[test]
fn xbox_s_sticks_buttons_and_hat() {
    let mut s = PadState::default();
    sidewinder(&sim::sidewinder([0; 3], 0), &mut s).unwrap();
    let mut s = PadState::default();
    xbox_s(&sim::xbox_s([32767, -32768], [16000, 0], 0x0a05, 5), &mut s).unwrap();
    // Left: halved, offset, doubled in 16 bits: 32767 → 16383 + 32768 = 49151 → 98302 mod
    // 65536 = 32766 → (32766 − 32768) / 32768 inside the dead zone → 0.
    assert_eq!(s.channel[0], 0.0);
    // −32768 → −16384 + 32768 = 16384 → 32768 → 0.
    assert_eq!(s.channel[1], 0.0);
    // Right: 16000 → 8000 + 32768 = 40768 → (40768 − 32768) / 32768 × 2.
    assert_eq!(s.channel[2], 8000.0 / 32768.0 * 2.0);
    assert_eq!(s.channel[3], 0.0);
    assert_eq!(on(&s, 16), vec![0, 2, 9, 11, 14, 15]);
    assert_eq!(s.channel[4], 225.0);
    let mut r = sim::xbox_s([0; 2], [0; 2], 0, 8);
    r[0] = 2;
    assert_eq!(xbox_s(&r, &mut s), Err(Skip::Kind(2)));
}

#[test]
fn xbox_360_family() {
    let mut s = PadState::default();
    // Centred on 0x8000 (C++ reads the bytes as signed, then as unsigned: the same bits).
    xbox_360(
        &sim::xbox_360(
            [0x8000, 0x8000 + 20000],
            [0x8000 + 9000, 0x8000 - 9000],
            0xff,
            0x11,
            0x02,
            6,
        ),
        &mut s,
    )
    .unwrap();
    assert_eq!(s.channel[0], 0.0);
    assert_eq!(s.channel[1], 20000.0 / 32768.0);
    // Right stick: |9000| ≥ 8689·3/4: kept.
    assert_eq!(s.channel[2], 9000.0 / 32768.0);
    assert_eq!(s.channel[3], -9000.0 / 32768.0);
    assert_eq!(s.channel[4], f64::from(127.0f32 * 2.0 / 255.0));
    assert_eq!(on(&s, 18), vec![0, 4, 9, 12, 13]);
    assert_eq!(s.channel[5], 225.0);
    xbox_360(
        &sim::xbox_360([0x8000 + 5000, 0], [0, 0xffff], 0x80 - 29, 0, 0, 0),
        &mut s,
    )
    .unwrap();
    assert_eq!(s.channel[0], 0.0, "inside the left dead zone");
    assert_eq!(s.channel[1], -1.0);
    assert_eq!(s.channel[3], 32767.0 / 32768.0);
    assert_eq!(s.channel[4], 0.0, "inside the trigger threshold");
    assert_eq!(s.channel[5], -1.0);
    assert_eq!(on(&s, 18), Vec::<usize>::new());
}

#[test]
fn logitech_extreme_3d_pro_10_bit_axes() {
    let mut s = PadState::default();
    let r = sim::logitech_extreme_3d_pro(1023, 0, 128 + 20, 0, 0x0801, 7);
    logitech_extreme_3d_pro(&r, &mut s).unwrap();
    assert_eq!(s.channel[0], 511.0 / 512.0);
    assert_eq!(s.channel[1], -1.0);
    // Twist: |20| ≥ 0x12·3/4 = 13: kept.
    assert_eq!(s.channel[2], 20.0 / 128.0);
    assert_eq!(s.channel[3], -1.0);
    assert_eq!(on(&s, 16), vec![0, 8, 11, 15]);
    assert_eq!(s.channel[4], 315.0);
    // |d| < 0x16·3/4 = 16, 0x12·3/4 = 13, 0x0e·3/4 = 10 (integer arithmetic) is zero.
    let r = sim::logitech_extreme_3d_pro(512 + 15, 512 - 15, 128 + 12, 128 - 9, 0, 8);
    logitech_extreme_3d_pro(&r, &mut s).unwrap();
    assert_eq!(s.channel[..4], [0.0, 0.0, 0.0, 0.0]);
    let r = sim::logitech_extreme_3d_pro(512 + 16, 512, 128 + 13, 128 + 10, 0, 8);
    logitech_extreme_3d_pro(&r, &mut s).unwrap();
    assert_eq!(
        s.channel[..4],
        [16.0 / 512.0, 0.0, 13.0 / 128.0, 10.0 / 128.0]
    );
}

#[test]
fn saitek_keeps_the_cpp_hat_angle() {
    let mut s = PadState::default();
    // Hat up (1): button 6; C++ takes the angle from buttons 7-10 (none pressed): −1.
    saitek_st290_pro(&sim::saitek_st290_pro([128; 4], 0x31, 1), &mut s).unwrap();
    assert_eq!(on(&s, 10), vec![0, 4, 5, 6]);
    assert_eq!(s.channel[4], -1.0);
    // Hat right (3): button 7, read by C++ as "up": 0°.
    saitek_st290_pro(&sim::saitek_st290_pro([128; 4], 0, 3), &mut s).unwrap();
    assert_eq!(s.channel[4], 0.0);
    // Down-left (6): buttons 8, 9 → "right" and "down": 135°.
    saitek_st290_pro(&sim::saitek_st290_pro([128; 4], 0, 6), &mut s).unwrap();
    assert_eq!(on(&s, 10), vec![8, 9]);
    assert_eq!(s.channel[4], 135.0);
}

#[test]
fn fighterstick_hats_and_mode() {
    let mut s = PadState::default();
    ch_fighterstick(
        &sim::ch_fighterstick([128, 0, 255], 0x9, 2, [8, 1, 4], 2),
        &mut s,
    )
    .unwrap();
    assert_eq!(s.channel[..3], [0.0, -1.0, axis8(255)]);
    assert_eq!(on(&s, 24), vec![0, 3, 4, 5, 8, 15, 17, 22]);
    assert_eq!(s.channel[3], 45.0);
    assert_eq!(s.channel[4], 0.0);
    assert_eq!(s.channel[5], 270.0);
    assert_eq!(s.channel[6], 2.0, "red: 90° / 90 + 1");
    assert_eq!(s.channel[7], 180.0);
    // Mode 0 leaves the last mode.
    ch_fighterstick(&sim::ch_fighterstick([128; 3], 0, 0, [0; 3], 0), &mut s).unwrap();
    assert_eq!(on(&s, 24), vec![17]);
    ch_fighterstick(&sim::ch_fighterstick([128; 3], 0, 0, [0; 3], 4), &mut s).unwrap();
    assert_eq!(s.channel[6], 3.0);
}

#[test]
fn retrolinks() {
    let mut s = PadState::default();
    retrolink_gamecube(&sim::retrolink_gamecube([0, 255, 128, 1], 0x9f, 3), &mut s).unwrap();
    assert_eq!(s.channel[..4], [-1.0, 1.0, 0.0, -1.0]);
    assert_eq!(s.channel[4], 135.0);
    assert_eq!(on(&s, 12), vec![0, 1, 2, 3, 4, 7, 9, 10]);
    retrolink_gamecube(&sim::retrolink_gamecube([128; 4], 0, 15), &mut s).unwrap();
    assert_eq!(s.channel[4], -1.0);
    let mut s = PadState::default();
    retrolink_genesis(&sim::retrolink_genesis(0xa5, Some(5)), &mut s).unwrap();
    assert_eq!(on(&s, 12), vec![0, 2, 5, 7, 10, 11]);
    assert_eq!(s.channel[0], 225.0);
    retrolink_genesis(&sim::retrolink_genesis(0, None), &mut s).unwrap();
    assert_eq!(s.channel[0], -1.0);
}

#[test]
fn futaba_switch_patterns() {
    let mut s = PadState::default();
    let scale = f64::from(1.0f32 / 0.70f32);
    futaba_interlink_elite(
        &sim::futaba(128, 200, 10, 130, 255, 0xa2 | 0x09, 0x41),
        &mut s,
    )
    .unwrap();
    assert_eq!(s.channel[0], 1.0, "rudder clamped");
    assert_eq!(s.channel[1], (-118.0 / 128.0 * scale).max(-1.0));
    assert_eq!(s.channel[2], 0.0);
    assert_eq!(s.channel[3], 72.0 / 128.0 * scale);
    assert_eq!(s.channel[4], 0.0, "flaps inside the dead zone of 5");
    assert_eq!(on(&s, 18), vec![0, 6, 12, 17]);
    let mut r = sim::futaba(0, 0, 0, 0, 0, 0, 0);
    r[0] = 4;
    assert_eq!(futaba_interlink_elite(&r, &mut s), Err(Skip::Kind(4)));
}

#[test]
fn shields() {
    let mut s = PadState::default();
    shield(
        &sim::shield(0x8001, 7, [65535, 0, 32767, 32768], [65535, 0]),
        &mut s,
    )
    .unwrap();
    assert_eq!(on(&s, 21), vec![0, 15, 16, 19]);
    assert_eq!(
        s.channel[..6],
        [
            32768.0 / 32768.0,
            -32767.0 / 32768.0,
            0.0,
            1.0 / 32768.0,
            1.0,
            0.0
        ]
    );
    assert_eq!(s.channel[8..10], [-1.0, -1.0]);
    shield(&sim::shield_report2(true, true, 255, 51), &mut s).unwrap();
    assert!(s.button[8] && s.button[20]);
    assert_eq!(s.channel[6..8], [1.0, 0.2]);
    assert_eq!(shield(&[1, 2, 3], &mut s), Err(Skip::Kind(1)));
    let mut s = PadState::default();
    shield_stealth(
        &sim::shield_stealth(0x03, true, 0x05, 2, [0, 65535, 1, 2], [0, 65535]),
        &mut s,
    )
    .unwrap();
    assert_eq!(on(&s, 21), vec![0, 1, 9, 12, 13, 17]);
    assert_eq!(
        s.channel[..6],
        [
            -32767.0 / 32768.0,
            1.0,
            -32766.0 / 32768.0,
            -32765.0 / 32768.0,
            0.0,
            1.0
        ]
    );
    assert_eq!(s.channel[8..10], [1.0, 0.0]);
}

#[test]
fn table_and_ids() {
    assert_eq!(MODELS.len(), 14);
    let x = model("vrpn_Microsoft_Controller_Raw_Xbox_360").unwrap();
    assert_eq!(
        (x.vendor, x.product, x.channels, x.buttons),
        (0x045e, 0x028e, 6, 18)
    );
    assert_eq!(parse_hex_id("0x046D"), Some(0x046d));
    assert_eq!(parse_hex_id("c21d"), Some(0xc21d));
    assert_eq!(parse_hex_id("xyz"), None);
}

#[test]
fn every_controller_end_to_end() {
    use crate::drivers::hid_e2e::{check, Entry};
    let entries = MODELS
        .iter()
        .map(|m| Entry {
            keyword: m.keyword,
            vendor: m.vendor,
            product: m.product,
            interface: 0,
            channels: m.channels,
            buttons: m.buttons,
            build: Box::new(
                move |name: &str, conn: &crate::Connection, hub: &crate::hid::DeviceHub| {
                    super::build(m, name, None, conn, hub)
                },
            ),
            decoder: super::Decoder {
                decode: m.decode,
                repeat: m.repeat,
            },
            samples: {
                let s = sim::samples(m.keyword);
                assert!(!s.is_empty(), "{} has no samples", m.keyword);
                s
            },
        })
        .collect();
    check(entries);
}

/// Controllers whose C++ driver sends the whole Analog every 1/30 s do so here too, while
/// open; the others send only changes.
#[test]
fn the_analog_repeats_at_30_hz_where_cpp_repeats_it() {
    use crate::hid::rig::Rig;
    use std::cell::Cell;
    use std::rc::Rc;
    use std::time::Duration;
    let mut rig = Rig::new();
    rig.connect();
    let mut counts = Vec::new();
    for (i, kw) in [
        "vrpn_Microsoft_Controller_Raw_Xbox_360",
        "vrpn_nVidia_shield_USB",
    ]
    .into_iter()
    .enumerate()
    {
        let m = model(kw).unwrap();
        let name = format!("Pad{i}");
        rig.devices
            .push(super::build(m, &name, None, &rig.server, &rig.hub).unwrap());
        let ar = crate::AnalogRemote::on_connection(&name, &rig.client).unwrap();
        let n = Rc::new(Cell::new(0u32));
        let c = n.clone();
        ar.on_report(move |_| c.set(c.get() + 1));
        let l = rig.plug(20 + i as u32, m.vendor, m.product, 0, kw);
        let end = rig.accept(&l);
        end.send_report(&sim::samples(kw)[0]).unwrap();
        counts.push((n, ar, end, l));
    }
    rig.until("first reports", |_| counts.iter().all(|c| c.0.get() >= 1));
    let before: Vec<u32> = counts.iter().map(|c| c.0.get()).collect();
    rig.run_for(Duration::from_millis(400));
    let repeats = counts[0].0.get() - before[0];
    assert!(
        (6..=14).contains(&repeats),
        "Xbox 360 repeats in 0.4 s: {repeats}"
    );
    assert_eq!(
        counts[1].0.get(),
        before[1],
        "the Shield sends only changes"
    );
}
