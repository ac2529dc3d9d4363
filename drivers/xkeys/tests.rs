//! Every X-keys model's reports decoded from the simulator's bytes, the LED reports, and the
//! dial arithmetic, against values computed here from the C++ formulas.

use super::sim;
use super::{led_reports, model, Decoder, Led, Leds, MODELS};
use crate::drivers::hid_pad::{PadDecoder, PadState, Skip};
use crate::hid::HidOps;

fn decoder(keyword: &str) -> Decoder {
    Decoder::new(model(keyword).unwrap())
}

#[test]
fn desktop_keys_and_switch() {
    let mut d = decoder("vrpn_Xkeys_Desktop");
    let mut s = PadState::default();
    d.decode(&sim::desktop(true, 1 | 1 << 7 | 1 << 19), &mut s)
        .unwrap();
    let on: Vec<usize> = (0..21).filter(|&i| s.button[i]).collect();
    assert_eq!(on, vec![0, 1, 8, 20]);
    let mut bad = sim::desktop(false, 0);
    bad[10] = 0;
    assert_eq!(d.decode(&bad, &mut s), Err(Skip::Corrupt));
    assert!(s.button[0], "a corrupted report changed nothing");
}

#[test]
fn original_models_read_in_two_halves_or_whole() {
    let keys: u64 = 1 | 1 << 34 | 1 << 35 | 1 << 57;
    for kw in [
        "vrpn_Xkeys_Pro",
        "vrpn_Xkeys_Joystick",
        "vrpn_Xkeys_Jog_And_Shuttle",
    ] {
        let mut d = decoder(kw);
        let mut s = PadState::default();
        let (a, b) = sim::halves([128, 128, 128], true, keys);
        d.decode(&a, &mut s).unwrap();
        d.decode(&b, &mut s).unwrap();
        let on: Vec<usize> = (0..59).filter(|&i| s.button[i]).collect();
        assert_eq!(on, vec![0, 1, 35, 36, 58], "{kw}");
        let mut s2 = PadState::default();
        d.decode(&sim::whole([128, 128, 128], true, keys), &mut s2)
            .unwrap();
        assert_eq!(s.button[..59], s2.button[..59], "{kw}");
        assert_eq!(d.decode(&[0; 9], &mut s), Err(Skip::Length(9)));
    }
}

#[test]
fn jog_and_shuttle_channels_and_dial() {
    let mut d = decoder("vrpn_Xkeys_Jog_And_Shuttle");
    d.opened(&mut PadState::default(), &mut HidOps::new());
    let mut s = PadState::default();
    let (a, _) = sim::halves([(-7i8) as u8, 10, 0], false, 0);
    d.decode(&a, &mut s).unwrap();
    assert_eq!(s.channel[0], -1.0);
    assert_eq!(s.channel[1], 10.0);
    assert_eq!(
        s.dial[0],
        10.0 / 256.0,
        "the first report counts from 0, as C++"
    );
    s.dial[0] = 0.0;
    let (a, _) = sim::halves([3, 250, 0], false, 0);
    d.decode(&a, &mut s).unwrap();
    assert_eq!(s.channel[0], 3.0 / 7.0);
    // 250 − 10 = 240 → −16 as a signed byte.
    assert_eq!(s.dial[0], -16.0 / 256.0);
}

#[test]
fn original_joystick_axes() {
    let mut d = decoder("vrpn_Xkeys_Joystick");
    let mut s = PadState::default();
    let (a, _) = sim::halves([0, 255, 200], false, 0);
    d.decode(&a, &mut s).unwrap();
    assert_eq!(s.channel[..3], [-1.0, 127.0 / 128.0, 72.0 / 128.0]);
    // The whole report: Y inverted, twist as a dial from the second report on.
    d.decode(&sim::whole([64, 64, 10], false, 0), &mut s)
        .unwrap();
    assert_eq!(s.channel[..2], [-0.5, 0.5]);
    assert_eq!(s.dial[0], 0.0);
    d.decode(&sim::whole([64, 64, 14], false, 0), &mut s)
        .unwrap();
    assert_eq!(s.dial[0], 4.0 / 256.0);
}

#[test]
fn twelve_key_models() {
    let mut d = decoder("vrpn_Xkeys_Jog_And_Shuttle12");
    let mut s = PadState::default();
    d.decode(
        &sim::twelve(true, 1 << 11 | 1, [2, (-3i8) as u8, 0]),
        &mut s,
    )
    .unwrap();
    let on: Vec<usize> = (0..13).filter(|&i| s.button[i]).collect();
    assert_eq!(on, vec![0, 1, 12]);
    assert_eq!(s.dial[0], 0.2);
    assert_eq!(s.channel[0], -3.0 / 7.0);
    assert_eq!(s.channel[1], 0.2);
    s.dial[0] = 0.0;
    d.decode(&sim::twelve(false, 0, [(-1i8) as u8, 0, 0]), &mut s)
        .unwrap();
    assert_eq!(s.channel[1], 0.2 + -0.1, "channel 1 sums the turns");

    let mut d = decoder("vrpn_Xkeys_Joystick12");
    let mut s = PadState::default();
    d.decode(&sim::twelve(false, 0, [127, 0x81, 100]), &mut s)
        .unwrap();
    assert_eq!(s.channel[..2], [1.0, 1.0]);
    assert_eq!(s.dial[0], 0.0);
    d.decode(&sim::twelve(false, 0, [0, 0, 98]), &mut s)
        .unwrap();
    assert_eq!(s.dial[0], -2.0 / 256.0);
    assert_eq!(s.channel[2], -2.0 / 256.0);
    let mut bad = sim::twelve(false, 0, [0, 0, 0]);
    bad[0] = 1;
    assert_eq!(d.decode(&bad, &mut s), Err(Skip::Corrupt));
    assert_eq!(d.decode(&[0; 31], &mut s), Err(Skip::Length(31)));
}

#[test]
fn sixty_eight_keys_skip_the_shuttle_slots() {
    let mut d = decoder("vrpn_Xkeys_Jog_And_Shuttle68");
    let mut s = PadState::default();
    let keys: u128 = 1 | 1 << 28 | 1 << 29 | 1 << 44 | 1 << 67;
    d.decode(&sim::sixty_eight(false, keys, -2, 7), &mut s)
        .unwrap();
    let on: Vec<usize> = (0..69).filter(|&i| s.button[i]).collect();
    assert_eq!(on, vec![1, 29, 30, 45, 68]);
    assert_eq!(sim::slot68(29), 32);
    assert_eq!(sim::slot68(44), 56);
    assert_eq!(s.channel[0], 1.0);
    assert_eq!(s.dial[0], -0.2);
}

#[test]
fn xk3_pedals() {
    let mut d = decoder("vrpn_Xkeys_XK3");
    let mut s = PadState::default();
    d.decode(&sim::xk3([true, false, true]), &mut s).unwrap();
    assert_eq!(s.button[..3], [true, false, true]);
    assert_eq!(d.decode(&[0; 32], &mut s), Err(Skip::Corrupt));
}

#[test]
fn leds_are_the_cpp_output_reports() {
    let v1 = led_reports(Leds::V1, Led::On, Led::Off);
    assert_eq!(v1, vec![vec![0, 0, 0, 0, 0, 0, 0, 0, 0x80]]);
    assert_eq!(led_reports(Leds::V1, Led::Off, Led::On)[0][8], 0x40);
    let v2 = led_reports(Leds::V2, Led::Off, Led::On);
    assert_eq!(v2.len(), 2);
    assert_eq!(v2[0][..4], [0, 0xb3, 7, 0]);
    assert_eq!(v2[1][..4], [0, 0xb3, 6, 1]);
    assert!(v2
        .iter()
        .all(|r| r.len() == 36 && r[4..].iter().all(|b| *b == 0)));
    assert!(led_reports(Leds::None, Led::On, Led::On).is_empty());
    // Red while nobody is connected, green with a client, off at shutdown.
    let mut d = decoder("vrpn_Xkeys_Desktop");
    let mut ops = HidOps::new();
    d.clients(false, &mut ops);
    d.clients(true, &mut ops);
    d.shutdown(&mut ops);
    let bytes: Vec<u8> = ops
        .ops()
        .iter()
        .map(|op| match *op {
            crate::hid::HidOp::Output { start, len, .. } => ops.bytes(start, len)[8],
            _ => panic!("not an output report"),
        })
        .collect();
    assert_eq!(bytes, vec![0x80, 0x40, 0]);
}

#[test]
fn every_keyword_is_there() {
    assert_eq!(MODELS.len(), 8);
    assert_eq!(model("vrpn_Xkeys_Jog_And_Shuttle68").unwrap().buttons, 69);
}

#[test]
fn every_model_end_to_end() {
    use crate::drivers::hid_e2e::{check, Entry};
    let entries = MODELS
        .iter()
        .map(|m| Entry {
            keyword: m.keyword,
            vendor: super::VENDOR,
            product: m.product,
            interface: 0,
            channels: m.channels.unwrap_or(0),
            buttons: m.buttons,
            build: Box::new(
                move |name: &str, conn: &crate::Connection, hub: &crate::hid::DeviceHub| {
                    super::build(m, name, conn, hub)
                },
            ),
            decoder: Decoder::new(m),
            samples: sim::samples(m),
        })
        .collect();
    check(entries);
}

/// The LEDs through the device: green once a client is connected, red when the last one
/// leaves, off when the server stops — each an output report the simulator receives.
#[test]
fn leds_follow_the_clients() {
    use crate::hid::fake::HostRequest;
    use crate::hid::rig::Rig;
    let m = model("vrpn_Xkeys_Desktop").unwrap();
    let mut rig = Rig::new();
    rig.connect();
    let dev = super::build(m, "Keys", &rig.server, &rig.hub).unwrap();
    rig.devices.push(dev);
    let l = rig.plug(3, super::VENDOR, m.product, 0, "X-keys");
    let end = rig.accept(&l);
    let mut leds = Vec::new();
    let mut wait_for = |rig: &mut Rig, byte: u8| {
        rig.until(&format!("LED report {byte:#x}"), |_| {
            while let Ok(Some(r)) = end.try_request() {
                match r {
                    HostRequest::Output(b) => leds.push(b[8]),
                    other => panic!("unexpected request {other:?}"),
                }
            }
            leds.last() == Some(&byte)
        });
    };
    wait_for(&mut rig, 0x40);
    // The client leaves: red.
    rig.client = crate::Connection::client_in(
        &rig.reactor,
        "127.0.0.1",
        9,
        false,
        crate::Limits::default(),
    )
    .unwrap();
    wait_for(&mut rig, 0x80);
    // The server stops: both off.
    rig.devices.clear();
    wait_for(&mut rig, 0x00);
}
