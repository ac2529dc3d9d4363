//! The glove's reports decoded (values from the C++ formula), the product bits, each keyword
//! end to end.

use super::{description, model, sim, Decoder, MODELS};
use crate::drivers::hid_pad::{PadDecoder, PadState, Skip};

#[test]
fn five_and_fourteen_sensor_layouts() {
    let mut v = [0i16; 16];
    for (i, x) in v.iter_mut().enumerate() {
        *x = (i as i16 + 1) * 100 * if i % 2 == 0 { 1 } else { -1 };
    }
    let r = sim::report(v);
    let want = |i: usize| f64::from(v[i] as f32 * (1.0f32 / 4096.0));
    let mut s = PadState::default();
    Decoder::new(model("vrpn_Analog_5dtUSB_Glove14Right").unwrap())
        .decode(&r, &mut s)
        .unwrap();
    assert_eq!(
        s.channel[..14].to_vec(),
        (0..14).map(want).collect::<Vec<_>>()
    );
    let mut s = PadState::default();
    Decoder::new(model("vrpn_Analog_5dtUSB_Glove5Left").unwrap())
        .decode(&r, &mut s)
        .unwrap();
    assert_eq!(
        s.channel[..5],
        [want(0), want(3), want(6), want(9), want(12)]
    );
    assert_eq!(s.channel[1], -400.0 / 4096.0);
    assert_eq!(
        Decoder::new(&MODELS[0]).decode(&[0; 63], &mut s),
        Err(Skip::Length(63))
    );
}

#[test]
fn product_bits_select_hand_and_size() {
    use crate::hid::sysfs::{Bus, HidInfo};
    use crate::hid::NodeInfo;
    let info = |product| {
        NodeInfo::Hid(HidInfo {
            node: "hidraw0".into(),
            number: 0,
            devnode: "/d/hidraw0".into(),
            bus: Bus::USB,
            vendor: super::VENDOR,
            product,
            interface: Some(0),
            name: String::new(),
            phys: String::new(),
            serial: String::new(),
            sys_device: Default::default(),
        })
    };
    let dev = std::path::Path::new("/d");
    let left5 = model("vrpn_Analog_5dtUSB_Glove5Left").unwrap().matcher();
    assert!(left5.accepts(&info(0x0011), dev));
    assert!(
        left5.accepts(&info(0x0013), dev),
        "wireless port A, left, 5"
    );
    assert!(!left5.accepts(&info(0x0010), dev));
    let right14 = model("vrpn_Analog_5dtUSB_Glove14Right").unwrap().matcher();
    assert!(right14.accepts(&info(0x0000), dev));
    assert!(right14.accepts(&info(0x0004), dev));
    assert!(!right14.accepts(&info(0x0001), dev));
    assert_eq!(description(0x0011), "left hand, 5 sensors, wired USB");
    assert_eq!(
        description(0x0002),
        "right hand, 14 sensors, wireless port A"
    );
    assert_eq!(
        description(0x0014),
        "right hand, 5 sensors, wireless port B"
    );
}

#[test]
fn every_glove_end_to_end() {
    use crate::drivers::hid_e2e::{check, Entry};
    let entries = MODELS
        .iter()
        .map(|m| Entry {
            keyword: m.keyword,
            vendor: super::VENDOR,
            product: m.product_bits(),
            interface: 0,
            channels: m.sensors,
            buttons: 0,
            build: Box::new(
                move |name: &str, conn: &crate::Connection, hub: &crate::hid::DeviceHub| {
                    super::build(m, name, conn, hub)
                },
            ),
            decoder: Decoder::new(m),
            samples: sim::samples(),
        })
        .collect();
    check(entries);
}
