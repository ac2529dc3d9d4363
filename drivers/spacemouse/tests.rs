//! Decoding every model's reports from the simulator's bytes; expected values computed here
//! from the C++ formulas.

use super::sim;
use super::{model, Decoder, Layout, MODELS};
use crate::drivers::hid_pad::{PadDecoder, PadState, Skip};

fn expect(count: i16, scale: f32) -> f64 {
    let v = f64::from(count as f32 * scale);
    v.clamp(-1.0, 1.0)
}

#[test]
fn classic_models_decode_translation_rotation_and_buttons() {
    for m in MODELS.iter().filter(|m| m.layout == Layout::Classic) {
        let mut d = Decoder::new(m);
        let mut s = PadState::default();
        d.decode(&sim::translation(100, -250, 401), &mut s).unwrap();
        d.decode(&sim::rotation(-401, 7, -32768), &mut s).unwrap();
        let scale = 1.0f32 / 400.0f32;
        assert_eq!(
            s.channel[..6],
            [
                expect(100, scale),
                expect(-250, scale),
                1.0,
                -1.0,
                expect(7, scale),
                -1.0
            ]
        );
        // 0.25 exactly: 100 × (1/400 in single precision), as C++ computes it.
        assert_eq!(s.channel[0], f64::from(100.0f32 * (1.0f32 / 400.0)));
        let all = if m.buttons >= 32 {
            u32::MAX
        } else {
            (1u32 << m.buttons) - 1
        };
        d.decode(&sim::buttons(m, all), &mut s).unwrap();
        assert!(s.button[..m.buttons].iter().all(|b| *b), "{}", m.keyword);
        d.decode(&sim::buttons(m, 0b101), &mut s).unwrap();
        let want: Vec<bool> = (0..m.buttons).map(|i| i == 0 || i == 2).collect();
        assert_eq!(s.button[..m.buttons].to_vec(), want, "{}", m.keyword);
        assert_eq!(d.decode(&[9, 0, 0, 0, 0, 0, 0], &mut s), Err(Skip::Kind(9)));
        assert_eq!(d.decode(&[], &mut s), Err(Skip::Length(0)));
    }
}

#[test]
fn a_short_button_report_reads_missing_bytes_as_zero() {
    let m = model("vrpn_3DConnexion_SpaceMousePro").unwrap();
    let mut d = Decoder::new(m);
    let mut s = PadState::default();
    s.button[26] = true;
    d.decode(&[3, 0xff], &mut s).unwrap();
    assert!(s.button[..8].iter().all(|b| *b));
    assert!(!s.button[8..27].iter().any(|b| *b));
}

#[test]
fn the_pro_wireless_sends_all_axes_in_one_report() {
    let m = model("vrpn_3DConnexion_SpaceMouseProWireless").unwrap();
    let mut d = Decoder::new(m);
    let mut s = PadState::default();
    d.decode(&sim::six_axes([350, -175, 1, -351, 0, 12]), &mut s)
        .unwrap();
    let scale = 1.0f32 / 350.0f32;
    assert_eq!(
        s.channel[..6],
        [
            1.0,
            expect(-175, scale),
            expect(1, scale),
            -1.0,
            0.0,
            expect(12, scale)
        ]
    );
    d.decode(&sim::buttons(m, 1 << 31 | 1), &mut s).unwrap();
    assert!(s.button[0] && s.button[31] && !s.button[1]);
    assert_eq!(d.decode(&sim::report_0x17(), &mut s), Err(Skip::Quiet));
    assert_eq!(
        d.decode(&sim::translation(1, 2, 3), &mut s),
        Err(Skip::Length(7))
    );
}

#[test]
fn every_keyword_has_its_cpp_ids() {
    assert_eq!(MODELS.len(), 13);
    let nav = model("vrpn_3DConnexion_Navigator").unwrap();
    assert_eq!((nav.vendor, nav.product, nav.buttons), (0x046d, 50726, 2));
    let sm = model("vrpn_3DConnexion_SpaceMouseWireless").unwrap();
    assert_eq!((sm.vendor, sm.product), (9583, 50735));
    assert!(model("vrpn_3DConnexion_Nope").is_none());
}

#[test]
fn every_model_end_to_end() {
    use crate::drivers::hid_e2e::{check, Entry};
    let entries = MODELS
        .iter()
        .map(|m| Entry {
            keyword: m.keyword,
            vendor: m.vendor,
            product: m.product,
            interface: 0,
            channels: 6,
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
