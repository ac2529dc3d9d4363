//! The generic driver on real descriptors (see `fixtures/`): the layout each yields, values
//! decoded from reports built on it, and end to end through a real socket.

use std::cell::RefCell;
use std::rc::Rc;

use super::config::parse_ids;
use super::sim::{self, report};
use super::{hat_direction, normalize, Layout};
use crate::drivers::hid_pad::PadState;
use crate::hid::descriptor::{self, page, Descriptor};
use crate::hid::rig::Rig;

fn layout(bytes: &[u8]) -> (Descriptor, Layout) {
    let d = descriptor::parse(bytes).unwrap();
    let l = Layout::new(&d);
    (d, l)
}

#[test]
fn xbox_wireless_controller_a_game_pad() {
    let (d, l) = layout(&sim::xbox_wireless_controller());
    assert_eq!(
        d.applications[0],
        (page::GENERIC_DESKTOP, 0x05),
        "a game pad"
    );
    let usages: Vec<u16> = l.axes.iter().map(|f| f.usage).collect();
    assert_eq!(usages, vec![0x30, 0x31, 0x33, 0x34, 0x32, 0x35]);
    assert_eq!(
        (l.hats.len(), l.buttons.len()),
        (1, 11),
        "10 buttons and the Xbox button"
    );
    assert_eq!((l.channels(), l.button_count()), (7, 15));
    assert!(l.uses_report_ids);
    assert_eq!(
        d.report_bits.iter().find(|(id, _)| *id == 1),
        Some(&(1, 120))
    );
    let a = &l.axes;
    let r = report(
        true,
        1,
        15,
        &[
            (&a[0], 65535),
            (&a[1], 0),
            (&a[2], 32768),
            (&a[3], 16384),
            (&a[4], 1023),
            (&a[5], 0),
            (&l.hats[0], 3),
            (&l.buttons[0], 1),
            (&l.buttons[9], 1),
        ],
    );
    let mut s = PadState::default();
    assert!(l.decode(&r, &mut s));
    assert_eq!(
        s.channel[..6],
        [
            1.0,
            -1.0,
            2.0 * 32768.0 / 65535.0 - 1.0,
            2.0 * 16384.0 / 65535.0 - 1.0,
            1.0,
            -1.0
        ]
    );
    assert_eq!(s.channel[6], 90.0, "hat 3 of 1-8 is right");
    let on: Vec<usize> = (0..15).filter(|&i| s.button[i]).collect();
    assert_eq!(on, vec![0, 9, 12], "buttons 1 and 10, hat right");
    // The Xbox button comes in report 2; a centred hat reads 0 (outside 1-8).
    let r2 = report(true, 2, 1, &[(&l.buttons[10], 1)]);
    assert!(l.decode(&r2, &mut s));
    assert!(s.button[10]);
    let r3 = report(true, 1, 15, &[(&l.hats[0], 0)]);
    l.decode(&r3, &mut s);
    assert_eq!(s.channel[6], -1.0);
    assert!(!s.button[11..15].iter().any(|b| *b));
    // A battery report carries nothing served.
    assert!(!l.decode(&[4, 99], &mut s));
}

#[test]
fn raptor_mach2_a_flight_stick() {
    let (d, l) = layout(&sim::raptor_mach2());
    assert_eq!(
        d.applications[0],
        (page::GENERIC_DESKTOP, 0x04),
        "a joystick"
    );
    let usages: Vec<u16> = l.axes.iter().map(|f| f.usage).collect();
    assert_eq!(
        usages,
        vec![0x30, 0x31, 0x33, 0x32, 0x35, 0x34, 0x36],
        "the undefined axis is left out"
    );
    assert_eq!((l.buttons.len(), l.hats.len()), (128, 1));
    assert_eq!((l.channels(), l.button_count()), (8, 132));
    let (a, h) = (&l.axes, &l.hats[0]);
    let bytes = (d.report_bits[0].1 / 8) as usize;
    assert_eq!(bytes, 63);
    let r = report(
        true,
        1,
        bytes,
        &[
            (&a[0], 2047),
            (&a[1], 1024),
            (&a[2], 0),
            (&a[6], 1023),
            (h, 30),
            (&l.buttons[0], 1),
            (&l.buttons[127], 1),
        ],
    );
    let mut s = PadState::default();
    l.decode(&r, &mut s);
    assert_eq!(s.channel[0], 1.0);
    assert_eq!(s.channel[1], 2.0 * 1024.0 / 2047.0 - 1.0);
    assert_eq!(s.channel[2], -1.0);
    assert_eq!(s.channel[6], 1.0, "slider");
    assert_eq!(
        s.channel[7], 45.0,
        "30 of 0-239 in eight directions: up-right"
    );
    assert!(s.button[0] && s.button[127] && s.button[128] && s.button[129]);
    l.decode(&report(true, 1, bytes, &[(h, 240)]), &mut s);
    assert_eq!(s.channel[7], -1.0, "240 is the null value");
}

#[test]
fn spacemice_six_signed_axes() {
    let (_, nav) = layout(&sim::spacenavigator());
    assert_eq!(sim::spacenavigator().len(), 217);
    assert_eq!((nav.channels(), nav.button_count()), (6, 2));
    assert!(nav
        .axes
        .iter()
        .all(|f| (f.logical_min, f.logical_max) == (-350, 350)));
    assert!(
        nav.axes[0].relative,
        "declared relative, although positions"
    );
    let mut s = PadState::default();
    nav.decode(
        &report(
            true,
            1,
            6,
            &[
                (&nav.axes[0], -350),
                (&nav.axes[1], 175),
                (&nav.axes[2], 400),
            ],
        ),
        &mut s,
    );
    nav.decode(
        &report(true, 2, 6, &[(&nav.axes[3], 1), (&nav.axes[5], -7)]),
        &mut s,
    );
    nav.decode(&report(true, 3, 2, &[(&nav.buttons[1], 1)]), &mut s);
    assert_eq!(
        s.channel[..6],
        [-1.0, 0.5, 1.0, 1.0 / 350.0, 0.0, -7.0 / 350.0]
    );
    assert_eq!(s.button[..2], [false, true]);
    let (d, w) = layout(&sim::spacemouse_wireless());
    assert_eq!(sim::spacemouse_wireless().len(), 270);
    assert_eq!((w.channels(), w.button_count()), (6, 2));
    assert!(
        w.axes.iter().all(|f| f.report_id == 1),
        "all six in report 1"
    );
    assert!(
        d.fields.iter().any(|f| f.page == 0x06),
        "the battery is parsed but not served"
    );
}

#[test]
fn normalisation_and_hats() {
    let f = |lo, hi| crate::hid::descriptor::Field {
        report_id: 0,
        bit_offset: 0,
        bit_size: 8,
        page: 1,
        usage: 0x30,
        logical_min: lo,
        logical_max: hi,
        relative: false,
        null_state: false,
    };
    assert_eq!(normalize(&f(-127, 127), -127), -1.0);
    assert_eq!(normalize(&f(-128, 127), 64), 0.5);
    assert_eq!(normalize(&f(0, 255), 0), -1.0);
    assert_eq!(normalize(&f(0, 255), 255), 1.0);
    assert_eq!(normalize(&f(5, 5), 5), 0.0);
    assert_eq!(hat_direction(&f(0, 7), 7), Some(7));
    assert_eq!(hat_direction(&f(1, 8), 8), Some(7));
    assert_eq!(hat_direction(&f(0, 3), 1), Some(2), "a four-way hat");
    assert_eq!(hat_direction(&f(0, 7), 8), None);
    assert_eq!(parse_ids("045e:02e0"), Some((0x045e, 0x02e0)));
    assert_eq!(parse_ids("0x11C0:0x5606"), Some((0x11c0, 0x5606)));
    assert_eq!(parse_ids("45e"), None);
    assert_eq!(parse_ids("12345:1"), None);
}

/// Each fixture on a fake hidraw node (its descriptor in sysfs), selected by ids, by name
/// and by path; a client sees the decoded values.
#[test]
fn generic_end_to_end_on_every_fixture() {
    use crate::server::config::parse_str;
    let mut rig = Rig::new();
    rig.connect();
    let fixtures = [
        (
            "Pad",
            0x045e_u16,
            0x02e0_u16,
            "Xbox Wireless Controller",
            sim::xbox_wireless_controller(),
            "045e:02e0".to_string(),
        ),
        (
            "Stick",
            0x11c0,
            0x5606,
            "Sanmos Group FR-TEC Raptor MACH 2",
            sim::raptor_mach2(),
            "\"Sanmos Group FR-TEC Raptor MACH 2\"".to_string(),
        ),
        (
            "Nav",
            0x046d,
            0xc626,
            "3Dconnexion SpaceNavigator",
            sim::spacenavigator(),
            "/dev/hidraw52".to_string(),
        ),
    ];
    // One build context (one hub and hot-plug watcher) for every device, as a server has.
    let server = rig.server.clone();
    let cx = crate::driver::BuildContext::new(&server).with_device_tree(rig.fake.tree());
    let mut keep = Vec::new();
    for (i, (name, vendor, product, dev_name, rdesc, selector)) in fixtures.into_iter().enumerate()
    {
        let n = 50 + i as u32;
        let entries = parse_str(&format!("vrpn_HID_Generic {name} {selector}\n"), "g.cfg").unwrap();
        rig.devices.extend(entries[0].config.build(&cx).unwrap());
        let ar = crate::AnalogRemote::on_connection(name, &rig.client).unwrap();
        let got: Rc<RefCell<Option<Vec<f64>>>> = Rc::default();
        let g = got.clone();
        ar.on_report(move |r| *g.borrow_mut() = Some(r.channels().to_vec()));
        rig.fake.add_hidraw(n, vendor, product, 0, dev_name, "");
        rig.fake.set_report_descriptor(n, &rdesc);
        let l = rig.fake.listen_hidraw(n).unwrap();
        rig.pass();
        rig.fake
            .uevent("add", "hidraw", &format!("hidraw{n}"))
            .unwrap();
        let end = rig.accept(&l);
        let (d, lay) = layout(&rdesc);
        let id = lay.axes[0].report_id;
        let bytes = (d.report_bits.iter().find(|(r, _)| *r == id).unwrap().1 / 8) as usize;
        let hi = lay.axes[0].logical_max;
        let r = report(lay.uses_report_ids, id, bytes, &[(&lay.axes[0], hi)]);
        end.send_report(&r).unwrap();
        let mut want = PadState::default();
        lay.decode(&r, &mut want);
        assert_eq!(want.channel[0], 1.0);
        let c = lay.channels();
        rig.until(&format!("{name}: values"), |_| {
            got.borrow().as_deref() == Some(&want.channel[..c])
        });
        keep.push((ar, end, l));
    }
}
