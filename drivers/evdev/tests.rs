//! The evdev drivers fed event records: values as C++ computes them, node selection by name
//! and by capability, and each keyword end to end through a named pipe standing in for the
//! event node (unplug, replug).

use std::cell::RefCell;
use std::io::Write;
use std::rc::Rc;

use super::sim::{abs, bytes, key, rel, syn};
use super::{build, DevInputKind, EvdevDriver, MOUSE_BUTTONS};
use crate::hid::input_event::{BTN_LEFT, BTN_MIDDLE, BTN_RIGHT, REL_WHEEL, REL_X, REL_Y};
use crate::hid::rig::Rig;
use crate::{AnalogRemote, ButtonRemote};

/// What a client sees of one device.
struct Client {
    analog: Rc<RefCell<Vec<Vec<f64>>>>,
    buttons: Rc<RefCell<Vec<(usize, i32)>>>,
    texts: Rc<RefCell<Vec<String>>>,
    _remotes: (AnalogRemote, ButtonRemote),
}

fn client(rig: &Rig, name: &str) -> Client {
    let ar = AnalogRemote::on_connection(name, &rig.client).unwrap();
    let br = ButtonRemote::on_connection(name, &rig.client).unwrap();
    let analog: Rc<RefCell<Vec<Vec<f64>>>> = Rc::default();
    let buttons: Rc<RefCell<Vec<(usize, i32)>>> = Rc::default();
    let (a, b) = (analog.clone(), buttons.clone());
    ar.on_report(move |r| a.borrow_mut().push(r.channels().to_vec()));
    br.on_change(move |c| b.borrow_mut().push((c.button, c.state.raw())));
    let texts: Rc<RefCell<Vec<String>>> = Rc::default();
    let t = texts.clone();
    let sender = rig.client.register_sender(name).unwrap();
    let ty = rig
        .client
        .register_type(crate::devices::base::TEXT_MESSAGE)
        .unwrap();
    rig.client
        .register_handler(ty, crate::SenderFilter::Only(sender), move |m| {
            if let Some((_, _, s)) = crate::devices::text::decode_text(m.payload) {
                t.borrow_mut().push(s.to_owned());
            }
        });
    Client {
        analog,
        buttons,
        texts,
        _remotes: (ar, br),
    }
}

/// Plugs in event node `n` (sysfs entry, a named pipe as its node, the uevent) and returns
/// the pipe's writing end once the server has opened it.
fn plug(rig: &mut Rig, n: u32, name: &str, mouse: bool) -> std::fs::File {
    add(rig, n, name, mouse);
    let path = rig.fake.root().join(format!("dev/input/event{n}"));
    let mut w = None;
    rig.until("the server opens the event node", |_| {
        use std::os::unix::fs::OpenOptionsExt;
        // Opening a pipe to write without blocking fails until a reader has it open.
        w = std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(nix::libc::O_NONBLOCK)
            .open(&path)
            .ok();
        w.is_some()
    });
    w.unwrap()
}

/// Plugs in event node `n` without waiting for anyone to open it.
fn add(rig: &mut Rig, n: u32, name: &str, mouse: bool) {
    let (ev, key, rel) = if mouse {
        ("7", "70000 0 0 0 0", "103")
    } else {
        ("120013", "ffffffff", "")
    };
    rig.fake
        .add_input(n, name, 0x046d, 0xc077, ev, key, rel, "");
    rig.fake.fifo_input(n).unwrap();
    rig.pass();
    rig.fake
        .uevent("add", "input", &format!("input/event{n}"))
        .unwrap();
}

fn unplug(rig: &mut Rig, n: u32) {
    rig.fake.remove_input(n);
    rig.fake
        .uevent("remove", "input", &format!("input/event{n}"))
        .unwrap();
}

#[test]
fn dev_input_keyboard_relative_and_absolute() {
    let mut rig = Rig::new();
    rig.connect();
    let conn = rig.server.clone();
    let hub = rig.hub.clone();
    let kbd = EvdevDriver::dev_input(
        "Kbd",
        "AT Translated Set 2 keyboard",
        DevInputKind::Keyboard(255),
        &conn,
    )
    .unwrap();
    let mouse =
        EvdevDriver::dev_input("Rel", "USB Optical Mouse", DevInputKind::Relative, &conn).unwrap();
    let stick = EvdevDriver::dev_input(
        "Abs",
        "Logitech Joystick",
        DevInputKind::Absolute(1023.0),
        &conn,
    )
    .unwrap();
    for d in [kbd, mouse, stick] {
        rig.devices.push(build(d, &conn, &hub));
    }
    let (k, m, j) = (
        client(&rig, "Kbd"),
        client(&rig, "Rel"),
        client(&rig, "Abs"),
    );
    // A decoy with another name first: the driver must take the named one.
    add(&mut rig, 0, "Some Other Keyboard", false);
    let mut kw = plug(&mut rig, 1, "AT Translated Set 2 keyboard", false);
    let mut mw = plug(&mut rig, 2, "USB Optical Mouse", true);
    let mut jw = plug(&mut rig, 3, "Logitech Joystick", false);
    kw.write_all(&bytes(&[
        key(30, 1),
        syn(),
        key(30, 2),
        syn(),
        key(30, 0),
        syn(),
    ]))
    .unwrap();
    rig.until("keyboard", |_| {
        *k.buttons.borrow() == vec![(30, 1), (30, 0)]
    });
    assert!(k.analog.borrow().is_empty());
    mw.write_all(&bytes(&[
        rel(REL_X, 5),
        rel(REL_Y, -2),
        syn(),
        rel(REL_X, 5),
        syn(),
        key(BTN_RIGHT, 1),
        syn(),
    ]))
    .unwrap();
    rig.until("relative", |_| {
        m.analog.borrow().len() == 3 && m.buttons.borrow().len() == 1
    });
    let a = m.analog.borrow();
    assert_eq!(a[0].len(), 63);
    assert_eq!((a[0][0], a[0][1]), (5.0, 0.0));
    assert_eq!((a[1][0], a[1][1]), (5.0, -2.0));
    assert_eq!(
        (a[2][0], a[2][1]),
        (5.0, -2.0),
        "the same motion again is sent again"
    );
    assert_eq!(*m.buttons.borrow(), vec![(1, 1)]);
    drop(a);
    jw.write_all(&bytes(&[
        abs(0, 512),
        abs(1, 1023),
        syn(),
        key(0x120, 1),
        syn(),
    ]))
    .unwrap();
    rig.until("absolute", |_| {
        j.analog.borrow().len() == 2 && !j.buttons.borrow().is_empty()
    });
    let a = j.analog.borrow();
    assert_eq!(a[0].len(), 15);
    assert_eq!(a[1][..2], [512.0 / 1023.0, 1.0]);
    assert_eq!(
        *j.buttons.borrow(),
        vec![(16, 1)],
        "BTN_TRIGGER is button 16"
    );
    drop(a);
    // Unplug the keyboard, replug it: reported, then served again.
    drop(kw);
    unplug(&mut rig, 1);
    rig.until("keyboard unplugged", |_| {
        k.texts.borrow().iter().any(|t| t.contains("unplugged"))
    });
    let mut kw = plug(&mut rig, 1, "AT Translated Set 2 keyboard", false);
    kw.write_all(&bytes(&[key(2, 1), syn()])).unwrap();
    rig.until("keyboard back", |_| {
        k.buttons.borrow().last() == Some(&(2, 1))
    });
    assert_eq!(MOUSE_BUTTONS, 80);
}

#[test]
fn mouse_and_event_mouse() {
    let mut rig = Rig::new();
    rig.connect();
    let conn = rig.server.clone();
    let hub = rig.hub.clone();
    rig.devices.push(build(
        EvdevDriver::mouse("Mouse0", &conn).unwrap(),
        &conn,
        &hub,
    ));
    rig.devices.push(build(
        EvdevDriver::event_mouse("EvMouse", "/dev/input/event7", &conn).unwrap(),
        &conn,
        &hub,
    ));
    let (m, e) = (client(&rig, "Mouse0"), client(&rig, "EvMouse"));
    // A keyboard first: vrpn_Mouse takes the first node that is a mouse.
    add(&mut rig, 4, "Keyboard", false);
    let mut mw = plug(&mut rig, 5, "Mouse A", true);
    mw.write_all(&bytes(&[
        rel(REL_X, 3),
        rel(REL_X, 4),
        rel(REL_Y, 1),
        syn(),
        key(BTN_MIDDLE, 1),
        syn(),
    ]))
    .unwrap();
    rig.until("vrpn_Mouse", |_| {
        m.analog.borrow().len() == 1 && m.buttons.borrow().len() == 1
    });
    assert_eq!(m.analog.borrow()[0], vec![7.0, 1.0]);
    assert_eq!(*m.buttons.borrow(), vec![(1, 1)]);
    // vrpn_Event_Mouse by path: the /dev path is read inside the tree.
    let mut ew = plug(&mut rig, 7, "Mouse B", true);
    ew.write_all(&bytes(&[
        rel(REL_X, -3),
        rel(REL_WHEEL, 1),
        syn(),
        key(BTN_RIGHT, 1),
        key(BTN_LEFT, 2),
        syn(),
        rel(REL_Y, 9),
        rel(REL_X, -3),
        syn(),
    ]))
    .unwrap();
    rig.until("vrpn_Event_Mouse", |_| {
        e.analog.borrow().len() == 2 && e.buttons.borrow().len() == 1
    });
    assert_eq!(e.analog.borrow()[0], vec![-3.0, 0.0, 1.0]);
    assert_eq!(e.analog.borrow()[1], vec![-3.0, 9.0, 1.0]);
    assert_eq!(
        *e.buttons.borrow(),
        vec![(1, 1)],
        "right is button 1; a repeat (2) ignored"
    );
}
