//! Every device's reports decoded from the simulator's bytes (values from the C++ formulas),
//! and each keyword end to end.

use super::sim;
use super::{model, Decoder, Kind, MODELS};
use crate::drivers::hid_pad::{PadDecoder, PadState, Skip};

#[test]
fn contour_shuttle_jog_and_buttons() {
    for kw in ["vrpn_Contour_ShuttleXpress", "vrpn_Contour_ShuttlePROv2"] {
        let m = model(kw).unwrap();
        let mut d = Decoder::new(m);
        let mut s = PadState::default();
        d.decode(&sim::contour(m.kind, 3, 250, 0b10001), &mut s)
            .unwrap();
        // 3 × 128 / 7 + 128 = 182.857… → 182 → 54 / 128.
        assert_eq!(s.channel[0], 54.0 / 128.0);
        assert_eq!(
            s.dial[0], 0.0,
            "the first report only sets the jog's position"
        );
        d.decode(&sim::contour(m.kind, -7, 2, 0b01010), &mut s)
            .unwrap();
        assert_eq!(s.channel[0], -1.0);
        // 2 − 250 = 8 as a signed byte.
        assert_eq!(s.dial[0], 0.8);
        assert_eq!(s.channel[1], 0.8);
        let on: Vec<usize> = (0..m.buttons).filter(|&i| s.button[i]).collect();
        assert_eq!(on, vec![1, 3], "{kw}");
        d.decode(&sim::contour(m.kind, 7, 2, 0), &mut s).unwrap();
        assert_eq!(s.channel[0], 1.0);
        assert_eq!(d.decode(&[0; 6], &mut s), Err(Skip::Length(6)));
    }
    let m = model("vrpn_Contour_ShuttlePROv2").unwrap();
    let mut s = PadState::default();
    Decoder::new(m)
        .decode(&sim::contour(Kind::ShuttlePro2, 0, 0, 0x4100), &mut s)
        .unwrap();
    assert!(s.button[8] && s.button[14]);
}

#[test]
fn powermate_ticks_and_press() {
    let m = model("vrpn_Griffin_PowerMate").unwrap();
    let mut d = Decoder::new(m);
    let mut s = PadState::default();
    d.decode(&sim::powermate(true, -3), &mut s).unwrap();
    assert_eq!(s.dial[0], -3.0);
    assert!(s.button[0]);
}

#[test]
fn drums_debounce_over_eight_samples() {
    let m = model("vrpn_Dream_Cheeky_USB_roll_up_drums").unwrap();
    let mut d = Decoder::new(m);
    let mut s = PadState::default();
    d.decode(&sim::drums([8, 3, 4, 0, 1, 5]), &mut s).unwrap();
    assert_eq!(s.button[..6], [true, false, true, false, false, true]);
    assert_eq!(d.decode(&[0; 7], &mut s), Err(Skip::Length(7)));
}

#[test]
fn every_device_end_to_end() {
    use crate::drivers::hid_e2e::{check, Entry};
    let entries = MODELS
        .iter()
        .map(|m| Entry {
            keyword: m.keyword,
            vendor: m.vendor,
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
