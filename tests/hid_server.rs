//! USB HID and input devices through a `vrpn_server` child on a fake device tree
//! (`-devroot`): a server whose devices are not plugged in runs and says it is waiting;
//! each device is served when it is plugged in; an unplug is reported; a replug is served
//! again. And `--list-devices` lists what is plugged in with the lines that would serve it.

mod common;

use std::cell::RefCell;
use std::io::Write;
use std::process::Command;
use std::rc::Rc;
use std::time::{Duration, Instant};

use common::start_server_with;
use vrpn::drivers::{spacemouse, xkeys};
use vrpn::hid::fake::FakeTree;
use vrpn::{AnalogRemote, ButtonRemote};

fn pump(what: &str, remotes: &[&dyn Fn()], mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "timed out: {what}"
        );
        for r in remotes {
            r();
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn wait_stderr(server: &common::Server, what: &str) {
    let start = Instant::now();
    while !server.stderr.lock().unwrap().contains(what) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no {what:?} on the server's stderr: {}",
            server.stderr.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn waiting_plugged_unplugged_replugged() {
    let fake = FakeTree::new();
    let cfg = "vrpn_3DConnexion_Navigator Nav0\n\
               vrpn_Xkeys_XK3 Pedals0\n\
               vrpn_DevInput Kbd0 \"Test Keyboard\" keyboard 255\n";
    let root = fake.root().to_str().unwrap().to_string();
    let server = start_server_with(cfg, 0, &["-devroot", &root]);
    // Nothing plugged in: the server runs and says it waits, for each device.
    wait_stderr(&server, "Nav0: waiting for 046d:c626 to be plugged in");
    wait_stderr(&server, "Pedals0: waiting for 05f3:042c to be plugged in");
    wait_stderr(
        &server,
        "Kbd0: waiting for \"Test Keyboard\" to be plugged in",
    );
    let at = |n: &str| format!("{n}@127.0.0.1:{}", server.port);
    let nav = AnalogRemote::new(&at("Nav0")).unwrap();
    let nav_buttons = ButtonRemote::new(&at("Nav0")).unwrap();
    let pedals = ButtonRemote::new(&at("Pedals0")).unwrap();
    let kbd = ButtonRemote::new(&at("Kbd0")).unwrap();
    let channels: Rc<RefCell<Vec<f64>>> = Rc::default();
    let c = channels.clone();
    nav.on_report(move |r| *c.borrow_mut() = r.channels().to_vec());
    let pressed: Rc<RefCell<Vec<(String, usize, i32)>>> = Rc::default();
    for (name, b) in [("nav", &nav_buttons), ("pedals", &pedals), ("kbd", &kbd)] {
        let p = pressed.clone();
        b.on_change(move |ch| {
            p.borrow_mut()
                .push((name.to_string(), ch.button, ch.state.raw()))
        });
    }
    let run = || {
        let _ = nav.mainloop();
        let _ = nav_buttons.mainloop();
        let _ = pedals.mainloop();
        let _ = kbd.mainloop();
    };
    pump("clients connect", &[&run], || nav.connection().connected());
    let model = spacemouse::model("vrpn_3DConnexion_Navigator").unwrap();
    let xk3 = xkeys::model("vrpn_Xkeys_XK3").unwrap();
    for round in 0..2usize {
        // Plug in: sysfs entries, the simulators' nodes, the uevents.
        fake.add_hidraw(
            1,
            model.vendor,
            model.product,
            0,
            "3Dconnexion SpaceNavigator",
            "",
        );
        fake.add_hidraw(
            2,
            xkeys::VENDOR,
            xk3.product,
            0,
            "P. I. Engineering XK-3",
            "",
        );
        fake.add_input(3, "Test Keyboard", 1, 1, "120013", "3ff0000", "", "");
        let l1 = fake.listen_hidraw(1).unwrap();
        let l2 = fake.listen_hidraw(2).unwrap();
        let fifo = fake.fifo_input(3).unwrap();
        fake.uevent("add", "hidraw", "hidraw1").unwrap();
        fake.uevent("add", "hidraw", "hidraw2").unwrap();
        fake.uevent("add", "input", "input/event3").unwrap();
        let mut e1 = None;
        let mut e2 = None;
        pump("the server opens the devices", &[&run], || {
            e1 = e1.take().or_else(|| l1.accept().unwrap());
            e2 = e2.take().or_else(|| l2.accept().unwrap());
            e1.is_some() && e2.is_some()
        });
        let (e1, e2) = (e1.unwrap(), e2.unwrap());
        let mut kw = None;
        pump("the server opens the event node", &[&run], || {
            use std::os::unix::fs::OpenOptionsExt;
            kw = std::fs::OpenOptions::new()
                .write(true)
                .custom_flags(nix::libc::O_NONBLOCK)
                .open(&fifo)
                .ok();
            kw.is_some()
        });
        let mut kw = kw.unwrap();
        let k = 100 * (round + 1) as i16;
        e1.send_report(&spacemouse::sim::translation(k, -k, 0))
            .unwrap();
        // Other buttons each round: a held button stays held across an unplug (the server
        // reports only what the device says), so pressing it again changes nothing.
        e1.send_report(&spacemouse::sim::buttons(model, 1 << round))
            .unwrap();
        let mut pedal = [false; 3];
        pedal[round] = true;
        e2.send_report(&xkeys::sim::xk3(pedal)).unwrap();
        let ev = |kind: u16, code: u16, value: i32| {
            vrpn::hid::input_event::InputEvent { kind, code, value }.encode(0, 0)
        };
        kw.write_all(&[ev(1, 30 + round as u16, 1), ev(0, 0, 0)].concat())
            .unwrap();
        let want = f64::from(f32::from(k) * (1.0f32 / 400.0));
        let start = Instant::now();
        loop {
            let ok = {
                let p = pressed.borrow();
                channels.borrow().first() == Some(&want)
                    && p.contains(&("nav".into(), round, 1))
                    && p.contains(&("pedals".into(), round, 1))
                    && p.contains(&("kbd".into(), 30 + round, 1))
            };
            if ok {
                break;
            }
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "round {round}: channels {:?}, buttons {:?}, server said: {}",
                channels.borrow(),
                pressed.borrow(),
                server.stderr.lock().unwrap()
            );
            run();
            std::thread::sleep(Duration::from_millis(2));
        }
        assert_eq!(channels.borrow()[..3], [want, -want, 0.0]);
        if round == 1 {
            break;
        }
        // Unplug everything: reported on the server's stderr.
        drop((e1, e2, kw, l1, l2));
        fake.remove_hidraw(1);
        fake.remove_hidraw(2);
        fake.remove_input(3);
        fake.uevent("remove", "hidraw", "hidraw1").unwrap();
        fake.uevent("remove", "hidraw", "hidraw2").unwrap();
        fake.uevent("remove", "input", "input/event3").unwrap();
        wait_stderr(&server, "Nav0: ");
        for name in ["Nav0", "Pedals0", "Kbd0"] {
            let start = Instant::now();
            loop {
                let text = server.stderr.lock().unwrap().clone();
                if text.lines().any(|l| {
                    l.contains(&format!("{name}: "))
                        && l.contains("reopening it when it comes back")
                }) {
                    break;
                }
                assert!(
                    start.elapsed() < Duration::from_secs(20),
                    "{name} unplug not reported: {text}"
                );
                run();
                std::thread::sleep(Duration::from_millis(5));
            }
        }
        pressed.borrow_mut().clear();
    }
    // Back: each open reported, twice.
    let start = Instant::now();
    while server.stderr.lock().unwrap().matches(" is open").count() < 6 {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{}",
            server.stderr.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn list_devices_names_the_lines_that_serve_them() {
    let fake = FakeTree::new();
    fake.add_hidraw(0, 0x046d, 0xc626, 0, "3Dconnexion SpaceNavigator", "");
    fake.set_report_descriptor(0, &vrpn::drivers::hid_generic::sim::spacenavigator());
    fake.add_hidraw(
        1,
        0x11c0,
        0x5606,
        0,
        "Sanmos Group FR-TEC Raptor MACH 2",
        "",
    );
    fake.set_report_descriptor(1, &vrpn::drivers::hid_generic::sim::raptor_mach2());
    fake.add_input(
        2,
        "USB Optical Mouse",
        0x046d,
        0xc077,
        "17",
        "70000 0 0 0 0",
        "103",
        "",
    );
    let out = Command::new(env!("CARGO_BIN_EXE_vrpn_server"))
        .args(["--list-devices", "-devroot", fake.root().to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for want in [
        "hidraw0  usb 046d:c626 interface 0  \"3Dconnexion SpaceNavigator\"",
        "    vrpn_3DConnexion_Navigator SpaceMouse0",
        "    vrpn_HID_Generic Device0 046d:c626 0",
        "    vrpn_HID_Generic Device0 11c0:5606 0",
        "    vrpn_DevInput Mouse0 \"USB Optical Mouse\" relative",
    ] {
        assert!(text.contains(want), "{want:?} not in:\n{text}");
    }
}
