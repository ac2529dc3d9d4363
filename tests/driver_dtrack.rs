//! vrpn_Tracker_DTrack end to end: a DTRACK controller simulator sends UDP frames to a real
//! `vrpn_server`, and a real client checks every report against the values the simulator
//! computed independently: all line types, garbage, truncated, over-long and late datagrams
//! (counted and skipped), multicast on the loopback interface, and the stateful-firewall
//! message.

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use vrpn::driver::udp::loopback_multicast_sender;
use vrpn::driver::Interface;
use vrpn::drivers::dtrack::sim::{free_udp_port, Controller, Frame};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::TimeVal;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(10);

fn wall() -> (u32, u32) {
    let d = SystemTime::now().duration_since(UNIX_EPOCH).unwrap();
    (d.as_secs() as u32, d.subsec_micros())
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

fn pos_of(p: &vrpn::TrackerPose) -> [f64; 3] {
    [p.pos.x, p.pos.y, p.pos.z]
}

fn quat_of(p: &vrpn::TrackerPose) -> [f64; 4] {
    let q = p.quat.quaternion();
    [q.i, q.j, q.k, q.w]
}

fn same_quat(a: &[f64; 4], b: &[f64; 4]) -> bool {
    close(a, b, 2e-5) || close(a, &b.map(|v| -v), 2e-5)
}

/// A frame stamped now (the server then reports the controller's time as it is).
fn frame_now(k: u32) -> Frame {
    let (sec, usec) = wall();
    Frame::standard(k, sec, usec)
}

/// The report time of a frame stamped `t`, as the client sees it: `t` (or, when the server
/// read the datagram more than 0.1 s after it was stamped on a loaded machine, its arrival
/// less the stated latency of 1.5 ms), moved by the client's estimate of the offset between
/// its clock and the server's (the same clock here: a few hundred microseconds).
fn time_matches(heard: TimeVal, t: TimeVal) -> bool {
    (-0.005..5.0).contains(&heard.seconds_since(t))
}

fn time_of(f: &Frame) -> TimeVal {
    let (sec, usec, _) = f.ts2.unwrap();
    TimeVal::new(sec as i64, usec as i64)
}

/// Sends frames until the client has heard a pose (the client connected), returning the
/// counter to continue from.
fn warm_up(ctl: &Controller, client: &Client, server: &ServerProcess, mut k: u32) -> u32 {
    let start = Instant::now();
    while client.poses().is_empty() {
        assert!(
            start.elapsed() < WAIT,
            "no pose heard; server said {}",
            server.stderr()
        );
        ctl.send(frame_now(k).text().as_bytes()).unwrap();
        k += 1;
        client.pump_until(Duration::from_millis(20), |c| !c.poses().is_empty());
    }
    // What follows is stamped well after every warm-up frame.
    std::thread::sleep(Duration::from_millis(20));
    client.pump_until(Duration::from_millis(20), |_| false);
    k
}

#[test]
fn every_line_type_through_a_real_server_with_damage_skipped() {
    let port = free_udp_port().unwrap();
    let server = ServerProcess::start(
        SERVER.as_ref(),
        &format!("vrpn_Tracker_DTrack DT {port} 3d\n"),
    )
    .unwrap();
    let client = Client::connect(
        "DT",
        server.port(),
        &[Interface::Tracker, Interface::Button, Interface::Analog],
    )
    .unwrap();
    let ctl = Controller::new(SocketAddr::from((Ipv4Addr::LOCALHOST, port))).unwrap();
    let first = warm_up(&ctl, &client, &server, 1);

    let mut sent: Vec<Frame> = Vec::new();
    let mut previous = frame_now(first);
    ctl.send(previous.text().as_bytes()).unwrap();
    // Reports of the warm-up frames are earlier than this by more than 10 ms.
    let from_time = time_of(&previous).plus_secs(-0.002);
    let (mut skipped_sent, mut expected_poses) = (0, previous.expected_poses(true).len());
    sent.push(previous.clone());
    for k in first + 1..first + 60 {
        // Damage between frames: garbage, a truncated frame, an over-long datagram, a late
        // frame (the previous one again) and an old one from the window.
        match k % 6 {
            0 => ctl.send(b"\x01\x02 garbage [[[ 6d 1 [").unwrap(),
            1 => {
                // Cut inside the first body's block.
                let t = frame_now(k).text();
                ctl.send(&t.as_bytes()[..t.find("6d ").unwrap() + 8])
                    .unwrap()
            }
            2 => ctl.send(&vec![b'x'; 25_000]).unwrap(),
            3 => ctl.send(previous.text().as_bytes()).unwrap(),
            4 => ctl.send(frame_now(k - 5).text().as_bytes()).unwrap(),
            _ => ctl.send(b"").unwrap(),
        }
        skipped_sent += 1;
        std::thread::sleep(Duration::from_millis(1));
        let f = frame_now(k);
        ctl.send(f.text().as_bytes()).unwrap();
        expected_poses += f.expected_poses(true).len();
        previous = f.clone();
        sent.push(f);
        // Lockstep: the frame's poses are in before the next is sent.
        client.wait_until(WAIT, "the frame's poses", &server, |c| {
            c.poses().iter().filter(|p| p.time >= from_time).count() >= expected_poses
        });
    }
    // Exactly the frames' poses, in order, nothing from a skipped datagram.
    let heard: Vec<_> = client
        .poses()
        .into_iter()
        .filter(|p| p.time >= from_time)
        .collect();
    let want: Vec<(TimeVal, usize, [f64; 3], [f64; 4])> = sent
        .iter()
        .flat_map(|f| {
            f.expected_poses(true)
                .into_iter()
                .map(move |(s, p, q)| (time_of(f), s, p, q))
        })
        .collect();
    assert_eq!(heard.len(), want.len());
    for (h, (t, s, p, q)) in heard.iter().zip(&want) {
        assert_eq!(h.sensor, *s);
        assert!(time_matches(h.time, *t), "{:?} for {t:?}", h.time);
        assert!(close(&pos_of(h), p, 1e-6), "{:?} vs {p:?}", h.pos);
        assert!(same_quat(&quat_of(h), q), "{:?} vs {q:?}", h.quat);
    }
    // Buttons: each change heard once, at the frame that made it.
    let mut want_buttons = Vec::new();
    for pair in sent.windows(2) {
        let (a, b) = (pair[0].sticks[0].buttons, pair[1].sticks[0].buttons);
        for i in 0..8 {
            if (a ^ b) >> i & 1 == 1 {
                want_buttons.push((i, b >> i & 1 == 1, time_of(&pair[1])));
            }
        }
    }
    // The changes heard end with those of the frames after the first (before them come
    // those of the warm-up frames and the first frame).
    let all_buttons: Vec<_> = client
        .reports_from(0)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((button, pressed, time)),
            _ => None,
        })
        .collect();
    assert!(all_buttons.len() >= want_buttons.len());
    let heard_buttons = &all_buttons[all_buttons.len() - want_buttons.len()..];
    assert_eq!(heard_buttons.len(), want_buttons.len());
    for (h, w) in heard_buttons.iter().zip(&want_buttons) {
        assert_eq!((h.0, h.1), (w.0, w.1));
        assert!(time_matches(h.2, w.2), "{h:?} for {w:?}");
    }
    // Analog: every frame whose joystick changed.
    let mut want_analog = Vec::new();
    for pair in sent.windows(2) {
        let v = |f: &Frame| {
            let j = f.sticks[0].joystick;
            let text = |x: f64| format!("{x:.2}").parse::<f32>().unwrap() as f64;
            vec![text(j[0]), text(j[1])]
        };
        if v(&pair[0]) != v(&pair[1]) {
            want_analog.push((v(&pair[1]), time_of(&pair[1])));
        }
    }
    let all_analog: Vec<_> = client
        .reports_from(0)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels, time)),
            _ => None,
        })
        .collect();
    assert!(all_analog.len() >= want_analog.len());
    let heard_analog = &all_analog[all_analog.len() - want_analog.len()..];
    assert_eq!(heard_analog.len(), want_analog.len());
    for (h, w) in heard_analog.iter().zip(&want_analog) {
        assert_eq!(h.0, w.0);
        assert!(time_matches(h.1, w.1), "{h:?} for {w:?}");
    }
    // The skipped datagrams were reported.
    client.wait_text(0, "skipped", WAIT, &server);
    assert!(skipped_sent > 0);
}

#[test]
fn multicast_group_on_the_loopback_interface() {
    let port = free_udp_port().unwrap();
    let group = Ipv4Addr::new(225, 1, 1, (std::process::id() % 200) as u8 + 1);
    let server = ServerProcess::start(
        SERVER.as_ref(),
        &format!("vrpn_Tracker_DTrack DT {group}:{port}\n"),
    )
    .unwrap();
    let client = Client::connect("DT", server.port(), &[Interface::Tracker]).unwrap();
    let ctl = Controller::on(
        loopback_multicast_sender().unwrap(),
        SocketAddr::from((group, port)),
    );
    let k = warm_up(&ctl, &client, &server, 1);
    let f = frame_now(k);
    ctl.send(f.text().as_bytes()).unwrap();
    let t = time_of(&f);
    let of_frame = |p: &vrpn::TrackerPose| time_matches(p.time, t);
    client.wait_until(WAIT, "the multicast frame", &server, |c| {
        c.poses().iter().any(of_frame)
    });
    let got: Vec<_> = client.poses().into_iter().filter(of_frame).collect();
    let want = f.expected_poses(false);
    assert_eq!(got.len(), want.len());
    for (g, (s, p, q)) in got.iter().zip(&want) {
        assert_eq!(g.sensor, *s);
        assert!(close(&pos_of(g), p, 1e-6) && same_quat(&quat_of(g), q));
    }
}

/// A controller address on the loopback network nobody else uses, with the firewall port.
fn controller_socket() -> UdpSocket {
    let pid = std::process::id();
    for i in 0..50u32 {
        let n = pid.wrapping_mul(31).wrapping_add(i * 7919);
        let ip = Ipv4Addr::new(
            127,
            10 + (n % 200) as u8,
            (n >> 8) as u8,
            2 + (n >> 16) as u8 % 250,
        );
        if let Ok(s) = UdpSocket::bind((ip, 50107)) {
            return s;
        }
    }
    panic!("no free 127.x.y.z:50107");
}

#[test]
fn stateful_firewall_message_then_frames_from_the_controller() {
    let port = free_udp_port().unwrap();
    let sock = controller_socket();
    let host = sock.local_addr().unwrap().ip();
    let server = ServerProcess::start(
        SERVER.as_ref(),
        &format!("vrpn_Tracker_DTrack DT {host}:{port}:fw\n"),
    )
    .unwrap();
    sock.set_read_timeout(Some(WAIT)).unwrap();
    let mut buf = [0u8; 64];
    let (n, from) = sock.recv_from(&mut buf).expect("the firewall message");
    assert_eq!(&buf[..n], b"fw4vrpndt\0");
    assert_eq!(from.port(), port, "sent from the data port");
    let client = Client::connect("DT", server.port(), &[Interface::Tracker]).unwrap();
    let ctl = Controller::on(sock, SocketAddr::from((Ipv4Addr::LOCALHOST, port)));
    warm_up(&ctl, &client, &server, 1);
}
