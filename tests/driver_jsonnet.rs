//! vrpn_Tracker_JsonNet end to end: a real `vrpn_server` with the device on a UDP port, fed
//! the datagrams C++ VRPN 07.38 was fed when tests/fixtures/cxx_jsonnet.txt was captured
//! (every message type, values of every JSON kind, malformed and refused datagrams); a
//! client must hear exactly what C++'s server made a client hear, in the same order.

use std::cell::RefCell;
use std::net::UdpSocket;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::sim::rig::ServerProcess;
use vrpn::{AnalogRemote, ButtonRemote, TextReceiver, TextSeverity, TrackerRemote};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(20);
const CAPTURE: &str = include_str!("fixtures/cxx_jsonnet.txt");

/// The capture's datagrams, each with the lines a client heard after it.
fn capture() -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in CAPTURE.lines().filter(|l| !l.starts_with('#')) {
        if let Some(rest) = line.strip_prefix("SEND ") {
            let (_, datagram) = rest.split_once(' ').unwrap();
            out.push((datagram.to_string(), Vec::new()));
        } else {
            out.last_mut().unwrap().1.push(line.to_string());
        }
    }
    out
}

/// A UDP port free at the moment.
fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

#[test]
fn a_client_hears_what_cxx_sends_for_the_same_datagrams() {
    let udp = free_udp_port();
    let server =
        ServerProcess::start(SERVER.as_ref(), &format!("vrpn_Tracker_JsonNet JN {udp}\n")).unwrap();
    let at = format!("JN@tcp://127.0.0.1:{}", server.port());
    let heard: Rc<RefCell<Vec<String>>> = Rc::default();
    let tracker = TrackerRemote::new(&at).unwrap();
    let h = heard.clone();
    tracker.on_pose(move |p| {
        h.borrow_mut().push(format!(
            "OUT {} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            p.sensor, p.pos.x, p.pos.y, p.pos.z, p.quat.i, p.quat.j, p.quat.k, p.quat.w
        ))
    });
    let buttons = ButtonRemote::new(&at).unwrap();
    let h = heard.clone();
    buttons.on_change(move |c| {
        h.borrow_mut()
            .push(format!("BTN {} {}", c.button, c.state.raw()))
    });
    let analog = AnalogRemote::new(&at).unwrap();
    let h = heard.clone();
    analog.on_report(move |r| {
        let nz: Vec<String> = r
            .channels()
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(i, v)| format!("{i} {v:?}"))
            .collect();
        h.borrow_mut()
            .push(format!("ANA {} {}", r.channels().len(), nz.join(" ")))
    });
    let texts = TextReceiver::new(&at).unwrap();
    let h = heard.clone();
    let warnings = Rc::new(RefCell::new(Vec::new()));
    let w = warnings.clone();
    texts.on_message(move |m| {
        if m.severity == TextSeverity::Normal {
            h.borrow_mut().push(format!("TXT 0 {:?}", m.text()));
        } else {
            w.borrow_mut().push(m.text().to_string());
        }
    });
    let pump = || {
        let _ = tracker.mainloop();
        let _ = buttons.mainloop();
        let _ = analog.mainloop();
        let _ = texts.mainloop();
        std::thread::sleep(Duration::from_millis(1));
    };
    let start = Instant::now();
    while !(tracker.connection().connected() && buttons.got_states()) {
        assert!(start.elapsed() < WAIT, "no connection: {}", server.stderr());
        pump();
    }
    heard.borrow_mut().clear();
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut want: Vec<String> = Vec::new();
    for (datagram, cxx) in capture() {
        sock.send_to(datagram.as_bytes(), ("127.0.0.1", udp))
            .unwrap();
        want.extend(cxx);
        let start = Instant::now();
        while heard.borrow().len() < want.len() {
            assert!(
                start.elapsed() < WAIT,
                "waiting for {want:?}, heard {:?}; the server said {}",
                heard.borrow(),
                server.stderr()
            );
            pump();
        }
    }
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(300) {
        pump();
    }
    assert_eq!(*heard.borrow(), want);
    assert_eq!(want.len(), 41);
    // The refused datagrams were named in a warning (at most one a second).
    assert!(
        warnings
            .borrow()
            .iter()
            .any(|w| w.contains("datagram skipped")),
        "{:?}",
        warnings.borrow()
    );
}
