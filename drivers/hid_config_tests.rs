//! Every HID and evdev keyword's C++ sample line (from C++ 07.38's `server_src/vrpn.cfg`,
//! uncommented, spacing kept) is accepted and serves what C++ serves; malformed lines are
//! errors naming file, line and problem.

use crate::driver::registry::{Interface, Served};
use crate::server::config::parse_str;

/// The sample lines, as C++ ships them (tabs included).
const CPP_SAMPLES: &str = "\
vrpn_Tracker_Wintracker Wintracker0\t1\t0\t0\t0\tX
vrpn_Futaba_InterLink_Elite futaba0
vrpn_Griffin_PowerMate griffin0
vrpn_Retrolink_GameCube retrolink0
vrpn_Retrolink_Genesis retrolink1
vrpn_Contour_ShuttleXpress contour0
vrpn_Contour_ShuttlePROv2 contour1
vrpn_Microsoft_SideWinder_Precision_2 microsoft0
vrpn_Microsoft_SideWinder microsoft1
vrpn_Microsoft_Controller_Raw_Xbox_S microsoft2
vrpn_Microsoft_Controller_Raw_Xbox_360 microsoft3
vrpn_Microsoft_Controller_Raw_Xbox_360_Wireless microsoft4
vrpn_Afterglow_Ax1_For_Xbox_360 microsoft5
vrpn_Microsoft_Controller_Raw_Xbox_360 device0 0x045e 0x028e
vrpn_Microsoft_Controller_Raw_Xbox_360 wireless0 0x045e 0x02a1
vrpn_Microsoft_Controller_Raw_Xbox_360 AfterGlowAX1 0x0e6f 0x0213
vrpn_Microsoft_Controller_Raw_Xbox_360 LogitechF310 0x046D 0xC21D
vrpn_Xkeys_Desktop xkeys0
vrpn_Xkeys_Pro xkeys1
vrpn_Xkeys_Joystick xkeys2
vrpn_Xkeys_Joystick12 xkeys3
vrpn_Xkeys_Jog_And_Shuttle xkeys4
vrpn_Xkeys_Jog_And_Shuttle12 xkeys5
vrpn_Xkeys_Jog_And_Shuttle68 xkeys6
vrpn_Xkeys_XK3 xkeys7
vrpn_Logitech_Extreme_3D_Pro logitech0
vrpn_Saitek_ST290_Pro saitek0
vrpn_CHProducts_Fighterstick_USB chproducts0
vrpn_3DConnexion_Navigator device1
vrpn_3DConnexion_Navigator_for_Notebooks device2
vrpn_3DConnexion_Traveler device3
vrpn_3DConnexion_SpaceMouse device4
vrpn_3DConnexion_SpaceMousePro device5
vrpn_3DConnexion_SpaceMouseCompact device6
vrpn_3DConnexion_SpaceMouseWireless device7
vrpn_3DConnexion_SpaceMouseWireless2 device8
vrpn_3DConnexion_SpaceMouseProWireless device9
vrpn_3DConnexion_SpaceExplorer device10
vrpn_3DConnexion_SpaceBall5000 device11
vrpn_3DConnexion_SpacePilot spacepilot
vrpn_3DConnexion_SpacePilotPro spacepilotpro
vrpn_Mouse\tMouse0
vrpn_DevInput           Input0          \"AT Translated keyboard\" keyboard 255
vrpn_DevInput           Input1          \"USB Optical Mouse\" relative -1
vrpn_Dream_Cheeky_USB_roll_up_drums drums0
vrpn_Tracker_SpacePoint SpacePoint0 0
vrpn_Analog_5dtUSB_Glove5Right Glove5Right
vrpn_Analog_5dtUSB_Glove5Left Glove5Left
vrpn_Analog_5dtUSB_Glove14Right Glove14Right
vrpn_Analog_5dtUSB_Glove14Left Glove14Left
vrpn_Tracker_RazerHydra Tracker0
vrpn_Tracker_OSVRHackerDevKit Tracker1
vrpn_Oculus_DK1 Oculus0
vrpn_Oculus_DK2_inertial Oculus1
vrpn_Oculus_DK2_LEDs Oculus2
vrpn_nVidia_shield_USB shield0
vrpn_nVidia_shield_stealth_USB shield1
vrpn_Laputa Laputa0
vrpn_Vality_vGlass Vality0
vrpn_Event_Mouse EvMouse0 /dev/input/event0
";

#[test]
fn every_cpp_sample_line_is_accepted() {
    let entries = parse_str(CPP_SAMPLES, "vrpn.cfg").unwrap();
    assert_eq!(entries.len(), CPP_SAMPLES.lines().count());
    for (e, line) in entries.iter().zip(CPP_SAMPLES.lines()) {
        let name = line.split_whitespace().nth(1).unwrap();
        assert_eq!(e.config.name(), name, "{line}");
        assert!(!e.config.served().is_empty(), "{line}");
    }
    // Spot checks of what is served.
    let served = |i: usize| -> Vec<Interface> {
        entries[i]
            .config
            .served()
            .iter()
            .map(|s: &Served<'_>| s.interface)
            .collect()
    };
    assert_eq!(served(0), vec![Interface::Tracker]);
    assert_eq!(
        served(2),
        vec![Interface::Analog, Interface::Button, Interface::Dial]
    );
    assert_eq!(
        served(17),
        vec![Interface::Button],
        "X-keys Desktop: keys only"
    );
    assert_eq!(
        served(19),
        vec![Interface::Analog, Interface::Button, Interface::Dial]
    );
    assert_eq!(
        served(50),
        vec![Interface::Tracker, Interface::Analog, Interface::Button],
        "Razer Hydra"
    );
}

#[test]
fn every_keyword_of_the_issue_is_registered() {
    let keywords: Vec<&str> = crate::drivers::REGISTRY
        .iter()
        .flat_map(|d| d.keywords.iter().copied())
        .collect();
    for kw in CPP_SAMPLES
        .lines()
        .map(|l| l.split_whitespace().next().unwrap())
    {
        assert!(keywords.contains(&kw), "{kw} is not registered");
    }
    for kw in keywords.iter() {
        assert_eq!(
            keywords.iter().filter(|k| *k == kw).count(),
            1,
            "{kw} registered twice"
        );
    }
}

#[test]
fn malformed_lines_name_file_line_and_problem() {
    let cases = [
        ("vrpn_3DConnexion_SpaceMouse\n", "name"),
        (
            "vrpn_Microsoft_Controller_Raw_Xbox_360 pad 0x045e\n",
            "vendor product",
        ),
        (
            "vrpn_Microsoft_Controller_Raw_Xbox_360 pad 0x045e nope\n",
            "hexadecimal",
        ),
        ("vrpn_DevInput in0 keyboard 5\n", "double quotes"),
        ("vrpn_DevInput in0 \"Kbd keyboard 5\n", "closing quote"),
        ("vrpn_DevInput in0 \"Kbd\" keyboard 0\n", "1 to 255"),
        (
            "vrpn_DevInput in0 \"Kbd\" joystick 5\n",
            "keyboard, absolute or relative",
        ),
        ("vrpn_Tracker_Wintracker w 1 1 1\n", "hemisphere"),
        ("vrpn_Tracker_SpacePoint sp x\n", "index"),
        ("vrpn_Event_Mouse m\n", "event device"),
    ];
    for (text, want) in cases {
        let e = parse_str(text, "vrpn.cfg").unwrap_err().to_string();
        assert!(e.starts_with("vrpn.cfg:1: "), "{e}");
        assert!(e.contains(want), "{text:?}: {e}");
    }
    // The DevInput fields as C++ reads them.
    use crate::drivers::evdev::config::{EvdevKind, EvdevLine};
    use crate::drivers::evdev::DevInputKind;
    let e = parse_str(
        "vrpn_DevInput j \"Logitech Logitech Extreme 3D\" absolute 1023\n",
        "f",
    )
    .unwrap();
    let line = e[0].config.downcast_ref::<EvdevLine>().unwrap();
    assert_eq!(
        line.kind,
        EvdevKind::DevInput {
            device: "Logitech Logitech Extreme 3D".into(),
            kind: DevInputKind::Absolute(1023.0)
        }
    );
}

/// `vrpn_server --list-devices`: each node with the lines the drivers suggest for it, every
/// one of them a line the server accepts.
mod suggestions {
    use crate::hid::fake::FakeTree;
    use crate::hid::list::{list, render};

    #[test]
    fn every_node_with_the_lines_that_serve_it() {
        let t = FakeTree::new();
        t.add_hidraw(0, 0x046d, 0xc626, 0, "3Dconnexion SpaceNavigator", "");
        t.set_report_descriptor(0, &crate::drivers::hid_generic::sim::spacenavigator());
        t.add_hidraw(1, 0x1234, 0x5678, 0, "Some Vendor Thing", "");
        t.add_input(
            2,
            "USB Optical Mouse",
            0x046d,
            0xc077,
            "17",
            "70000 0 0 0 0",
            "103",
            "",
        );
        t.add_input(
            3,
            "AT Translated Set 2 keyboard",
            1,
            1,
            "120013",
            "3ff0000",
            "",
            "",
        );
        let listed = list(&t.tree(), crate::drivers::SUGGESTERS);
        assert_eq!(listed.len(), 4);
        assert_eq!(
            listed[0].lines,
            vec![
                "vrpn_3DConnexion_Navigator SpaceMouse0".to_string(),
                "vrpn_HID_Generic Device0 046d:c626 0".to_string()
            ]
        );
        assert!(listed[1].lines.is_empty());
        assert_eq!(
            listed[2].lines,
            vec!["vrpn_DevInput Mouse0 \"USB Optical Mouse\" relative".to_string()]
        );
        assert_eq!(
            listed[3].lines,
            vec![
                "vrpn_DevInput Keyboard0 \"AT Translated Set 2 keyboard\" keyboard 255".to_string()
            ]
        );
        let text = render(&listed);
        assert!(
            text.starts_with("hidraw0  usb 046d:c626 interface 0  \"3Dconnexion SpaceNavigator\"")
        );
        assert!(text.contains("    (no driver for it)\n"));
        // Every suggested line is one the server accepts.
        for l in listed.iter().flat_map(|l| l.lines.iter()) {
            crate::server::config::parse_str(&format!("{l}\n"), "suggested").unwrap();
        }
        assert_eq!(render(&[]), "no HID or input devices found\n");
    }
}
