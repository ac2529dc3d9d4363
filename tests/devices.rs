//! Button, Analog, Dial and Text: in-process round trips, over loopback sockets, factoring
//! (several types under one name) and shared connections.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::button::{MOMENTARY, TOGGLE_OFF, TOGGLE_ON};
use vrpn::{
    AnalogExample, AnalogRemote, AnalogServer, ButtonExample, ButtonRemote, ButtonServer,
    Connection, DialExample, DialRemote, DialServer, ServerDevice, TextExample, TextReceiver,
    TextSender, TextSeverity, TimeVal, TrackerRemote, TrackerServer,
};

fn pump(
    conns: &[&Connection],
    devices: &mut [&mut dyn ServerDevice],
    timeout: Duration,
    mut done: impl FnMut() -> bool,
) -> bool {
    let start = Instant::now();
    while start.elapsed() < timeout {
        let now = vrpn::Now::read();
        for d in devices.iter_mut() {
            d.mainloop(now);
        }
        for c in conns {
            c.mainloop().unwrap();
        }
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    false
}

#[test]
fn button_changes_states_and_admin_in_process() {
    let conn = Connection::new_loopback();
    let server = ButtonServer::new("Button0", &conn, 3).unwrap();
    let remote = ButtonRemote::on_connection("Button0", &conn).unwrap();
    let changes = Rc::new(RefCell::new(Vec::new()));
    let c = changes.clone();
    remote.on_change(move |b| c.borrow_mut().push((b.button, b.state.raw(), b.time)));
    let t = TimeVal { sec: 5, usec: 7 };
    server.set_timestamp(t);
    server.set_button(1, true);
    server.report_changes().unwrap();
    conn.mainloop().unwrap();
    assert_eq!(*changes.borrow(), vec![(1, 1, t)]);
    assert!(remote.pressed(1));
    assert!(!remote.pressed(0));
    // No change, no message.
    server.report_changes().unwrap();
    assert_eq!(changes.borrow().len(), 1);

    // States: explicit report carries the physical states.
    let states = Rc::new(RefCell::new(Vec::new()));
    let s = states.clone();
    remote.on_states(move |st| {
        s.borrow_mut()
            .push(st.as_slice().iter().map(|b| b.raw()).collect::<Vec<_>>())
    });
    assert_eq!(remote.num_buttons(), 256);
    server.report_states().unwrap();
    assert_eq!(*states.borrow(), vec![vec![0, 1, 0]]);
    assert_eq!(remote.num_buttons(), 3);

    // A ping from the remote's sender triggers a States message too.
    remote.mainloop().unwrap();
    conn.mainloop().unwrap();
    assert!(states.borrow().len() >= 2);
    assert_eq!(states.borrow().last().unwrap(), &vec![0, 1, 0]);

    // Toggle mode via Admin: a press flips the toggle, a release sends nothing.
    server.set_alerts(true);
    remote.set_toggle(0, false).unwrap();
    conn.mainloop().unwrap();
    assert_eq!(server.mode(0), TOGGLE_OFF);
    changes.borrow_mut().clear();
    server.set_button(0, true);
    server.report_changes().unwrap();
    assert_eq!(changes.borrow().as_slice(), &[(0, 1, t)]);
    assert_eq!(server.mode(0), TOGGLE_ON);
    server.set_button(0, false);
    server.report_changes().unwrap();
    assert_eq!(changes.borrow().len(), 1);
    server.set_button(0, true);
    server.report_changes().unwrap();
    assert_eq!(changes.borrow()[1], (0, 0, t));
    assert_eq!(server.mode(0), TOGGLE_OFF);
    remote.set_all_momentary().unwrap();
    conn.mainloop().unwrap();
    assert_eq!(server.mode(0), MOMENTARY);
    // Out-of-range request from the remote is refused locally.
    assert!(remote.set_momentary(3).is_err());
}

#[test]
fn button_alerts_on_toggle() {
    let conn = Connection::new_loopback();
    let server = ButtonServer::new("B", &conn, 2).unwrap();
    let _remote = ButtonRemote::on_connection("B", &conn).unwrap();
    let alert_t = conn.register_type("vrpn_Button Alert").unwrap();
    let alerts = Rc::new(RefCell::new(Vec::new()));
    let a = alerts.clone();
    conn.register_handler(alert_t, vrpn::SenderFilter::Any, move |m| {
        let b = i32::from_be_bytes(m.payload[0..4].try_into().unwrap());
        let e = i32::from_be_bytes(m.payload[4..8].try_into().unwrap());
        a.borrow_mut().push((b, e));
    });
    server.set_mode(1, TOGGLE_OFF);
    assert!(alerts.borrow().is_empty(), "alerts are off by default");
    server.set_alerts(true);
    server.set_mode(1, TOGGLE_OFF);
    server.set_button(1, true);
    server.report_changes().unwrap();
    assert_eq!(*alerts.borrow(), vec![(1, TOGGLE_OFF), (1, TOGGLE_ON)]);
}

#[test]
fn analog_reports_in_process() {
    let conn = Connection::new_loopback();
    let mut server = AnalogServer::new("Analog0", &conn, 3).unwrap();
    let remote = AnalogRemote::on_connection("Analog0", &conn).unwrap();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    remote.on_report(move |r| g.borrow_mut().push(r.channels().to_vec()));
    assert_eq!(remote.num_channels(), 128);
    server.set_channel(0, 0.5);
    server.set_channel(2, -1.25);
    assert!(server
        .report_changes(Some(TimeVal { sec: 1, usec: 2 }))
        .unwrap());
    assert!(!server.report_changes(None).unwrap());
    server.report(None).unwrap();
    assert_eq!(
        *got.borrow(),
        vec![vec![0.5, 0.0, -1.25], vec![0.5, 0.0, -1.25]]
    );
    assert_eq!(remote.num_channels(), 3);
    assert_eq!(remote.channel(2), -1.25);
    assert_eq!(remote.channel(5), 0.0);
    assert_eq!(AnalogExample::value_at(0, 2.5), 1.0);
}

#[test]
fn dial_reports_in_process() {
    let conn = Connection::new_loopback();
    let mut server = DialServer::new("Dial0", &conn, 3).unwrap();
    let remote = DialRemote::on_connection("Dial0", &conn).unwrap();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    remote.on_update(move |d| g.borrow_mut().push((d.dial, d.change)));
    server.add_rotation(1, 0.25);
    server.add_rotation(1, 0.25);
    server.report_changes().unwrap();
    assert_eq!(*got.borrow(), vec![(1, 0.5)]);
    server.report_changes().unwrap();
    assert_eq!(got.borrow().len(), 1, "accumulators reset after sending");
    server.report().unwrap();
    assert_eq!(got.borrow()[1..], [(0, 0.0), (1, 0.0), (2, 0.0)]);
}

#[test]
fn text_in_process() {
    let conn = Connection::new_loopback();
    let sender = TextSender::new("Text0", &conn).unwrap();
    let recv = TextReceiver::on_connection("Text0", &conn).unwrap();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    recv.on_message(move |m| {
        g.borrow_mut()
            .push((m.severity, m.level, m.text().to_string(), m.time))
    });
    let t = TimeVal { sec: 9, usec: 1 };
    sender
        .send_message("hello", TextSeverity::Normal, 0, Some(t))
        .unwrap();
    sender
        .send_message("careful", TextSeverity::Warning, 3, Some(t))
        .unwrap();
    assert!(sender
        .send_message(&"x".repeat(1024), TextSeverity::Error, 0, None)
        .is_err());
    assert_eq!(
        *got.borrow(),
        vec![
            (TextSeverity::Normal, 0, "hello".to_string(), t),
            (TextSeverity::Warning, 3, "careful".to_string(), t)
        ]
    );
    assert_eq!(recv.received(), 2);
}

fn server() -> (Connection, u16) {
    let s = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let p = s.local_port().unwrap();
    (s, p)
}

#[test]
fn example_servers_over_sockets_share_one_connection() {
    let (srv, port) = server();
    let mut button = ButtonExample::new("Button0", &srv, 2, 50.0).unwrap();
    let mut dial = DialExample::new("Dial0", &srv, 2, 1.0, 10.0).unwrap();
    let mut analog = AnalogExample::new("Analog0", &srv, 4, 50.0).unwrap();
    let mut text = TextExample::new("Text0", &srv, 0.05, "Hello there").unwrap();
    let b = ButtonRemote::new(&format!("Button0@127.0.0.1:{port}")).unwrap();
    let d = DialRemote::new(&format!("Dial0@127.0.0.1:{port}")).unwrap();
    let a = AnalogRemote::new(&format!("Analog0@127.0.0.1:{port}")).unwrap();
    let t = TextReceiver::new(&format!("Text0@127.0.0.1:{port}")).unwrap();
    assert!(b.connection().same_as(d.connection()));
    assert!(b.connection().same_as(a.connection()));
    assert!(b.connection().same_as(t.connection()));

    let changes = Rc::new(RefCell::new(Vec::new()));
    let c = changes.clone();
    b.on_change(move |x| c.borrow_mut().push((x.button, x.state)));
    let states = Rc::new(Cell::new(0));
    let s = states.clone();
    b.on_states(move |x| {
        assert_eq!(x.num_buttons, 2);
        s.set(s.get() + 1)
    });
    let dials = Rc::new(RefCell::new(Vec::new()));
    let dd = dials.clone();
    d.on_update(move |x| dd.borrow_mut().push((x.dial, x.change)));
    let analogs = Rc::new(Cell::new(0));
    let aa = analogs.clone();
    a.on_report(move |r| {
        assert_eq!(r.num_channel, 4);
        assert!(r.channels().iter().all(|v| v.abs() <= 1.0));
        aa.set(aa.get() + 1)
    });
    let texts = Rc::new(RefCell::new(Vec::new()));
    let tt = texts.clone();
    t.on_message(move |m| tt.borrow_mut().push(m.text().to_string()));

    // Only the text receiver's mainloop runs the client connection: all devices still get data.
    let ok = pump(
        &[&srv],
        &mut [&mut button, &mut dial, &mut analog, &mut text],
        Duration::from_secs(10),
        || {
            t.mainloop().unwrap();
            changes.borrow().len() >= 8
                && states.get() >= 1
                && dials.borrow().len() >= 4
                && analogs.get() >= 3
                && texts.borrow().len() >= 2
        },
    );
    assert!(
        ok,
        "changes {:?} states {} dials {:?} analogs {} texts {:?}",
        changes.borrow(),
        states.get(),
        dials.borrow(),
        analogs.get(),
        texts.borrow()
    );
    // Both buttons flip together: consecutive pairs share a state, and states alternate.
    let ch = changes.borrow();
    for pair in ch.chunks(2).filter(|p| p.len() == 2) {
        assert_eq!((pair[0].0, pair[1].0), (0, 1));
        assert_eq!(pair[0].1, pair[1].1);
    }
    for w in ch.chunks(2).collect::<Vec<_>>().windows(2) {
        if w[1].len() == 2 {
            assert_ne!(w[0][0].1, w[1][0].1);
        }
    }
    assert!(dials.borrow().iter().all(|&(i, c)| i < 2 && c == 0.1));
    assert!(texts.borrow().iter().all(|m| m == "Hello there"));
    assert_eq!(b.num_buttons(), 2);
}

#[test]
fn one_name_exports_tracker_and_button() {
    // A Phantom-like server: Tracker + Button under the same name on one connection.
    let (srv, port) = server();
    let tracker = TrackerServer::new("Phantom0", &srv, 1).unwrap();
    let buttons = ButtonServer::new("Phantom0", &srv, 2).unwrap();
    let name = format!("Phantom0@127.0.0.1:{port}");
    let tr = TrackerRemote::new(&name).unwrap();
    let br = ButtonRemote::new(&name).unwrap();
    let dr = DialRemote::new(&name).unwrap(); // not implemented by the server: silently nothing
    let dials = Rc::new(Cell::new(0));
    let dd = dials.clone();
    dr.on_update(move |_| dd.set(dd.get() + 1));
    let poses = Rc::new(Cell::new(0));
    let p = poses.clone();
    tr.on_pose(move |x| {
        assert_eq!(x.pos.x, 0.25);
        p.set(p.get() + 1)
    });
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    br.on_change(move |x| g.borrow_mut().push((x.button, x.state.raw())));
    let mut pressed = false;
    let ok = pump(&[&srv], &mut [], Duration::from_secs(10), || {
        br.mainloop().unwrap();
        tr.mainloop().unwrap();
        dr.mainloop().unwrap();
        if srv.connected_peers() > 0 {
            let _ = tracker.report_pose(0, TimeVal::now(), [0.25, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]);
            if !pressed {
                buttons.set_button(1, true);
                buttons.report_changes().unwrap();
                pressed = true;
            }
        }
        poses.get() >= 3 && !got.borrow().is_empty() && br.got_states()
    });
    assert!(ok, "poses {} changes {:?}", poses.get(), got.borrow());
    assert_eq!(got.borrow()[0], (1, 1));
    assert!(br.pressed(1));
    assert_eq!(dials.get(), 0);
    assert_eq!(tr.bad_messages(), 0);
}
