//! Layered devices over analogs (and analog outputs) end to end: a `vrpn_server` serving the
//! layered device over an upstream this test serves (`Src@127.0.0.1:PORT`, a device on another
//! server) or one of its own (`*NAME`), fed the same input as C++ VRPN 07.38 was when the
//! fixtures in tests/fixtures/ were captured; what a client hears must be C++'s numbers.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::sim::rig::ServerProcess;
use vrpn::{AnalogServer, Connection, TimeVal, TrackerRemote};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(20);

/// The records of a fixture: a tag and numbers per line.
fn records(text: &str) -> Vec<(String, Vec<f64>)> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let mut t = l.split_whitespace();
            let tag = t.next().unwrap().to_string();
            (tag, t.map(|v| v.parse().unwrap()).collect())
        })
        .collect()
}

/// An upstream Analog `Src` on a server of this test.
struct Upstream {
    conn: Connection,
    src: AnalogServer,
}

impl Upstream {
    fn new() -> Upstream {
        let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let src = AnalogServer::new("Src", &conn, 16).unwrap();
        Upstream { conn, src }
    }

    fn at(&self) -> String {
        format!("Src@127.0.0.1:{}", self.conn.local_port().unwrap())
    }

    /// Sends one report of `values` stamped `time`.
    fn send(&mut self, time: TimeVal, values: &[f64]) {
        self.src.set_num_channels(values.len());
        self.src.channels_mut().copy_from_slice(values);
        self.src.report(Some(time)).unwrap();
        let _ = self.conn.mainloop();
    }
}

/// Every pose a client hears, as the fixtures write them: sensor, time, position, quaternion.
fn watch_poses(remote: &TrackerRemote) -> Rc<RefCell<Vec<Vec<f64>>>> {
    let heard: Rc<RefCell<Vec<Vec<f64>>>> = Rc::default();
    let h = heard.clone();
    remote.on_pose(move |p| {
        let t = p.sender_time;
        h.borrow_mut().push(vec![
            p.sensor as f64,
            t.sec as f64,
            t.usec as f64,
            p.pos.x,
            p.pos.y,
            p.pos.z,
            p.quat.i,
            p.quat.j,
            p.quat.k,
            p.quat.w,
        ]);
    });
    heard
}

/// Services `conns` until `done` or a time-out (a failure naming `what`).
fn pump_until(conns: &[&dyn Fn()], what: &str, server: &ServerProcess, done: impl Fn() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < WAIT,
            "timed out waiting for {what}; the server said {}",
            server.stderr()
        );
        for c in conns {
            c();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Starts a server on `cfg` with a client of tracker `name` once the server's link to the
/// upstream is up.
fn start_tracker(
    up: &Upstream,
    cfg: &str,
    name: &str,
) -> (ServerProcess, TrackerRemote, Rc<RefCell<Vec<Vec<f64>>>>) {
    let server = ServerProcess::start(SERVER.as_ref(), cfg).unwrap();
    let remote = TrackerRemote::new(&format!("{name}@tcp://127.0.0.1:{}", server.port())).unwrap();
    let heard = watch_poses(&remote);
    let (c, r) = (&up.conn, &remote);
    pump_until(
        &[&|| drop(c.mainloop()), &|| drop(r.mainloop())],
        "the server's link to the upstream and the client's connection",
        &server,
        || c.connected_peers() >= 1 && r.connection().connected(),
    );
    // Let the server see the client before the first input (a new client resets some devices).
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(200) {
        let _ = c.mainloop();
        let _ = r.mainloop();
        std::thread::sleep(Duration::from_millis(1));
    }
    (server, remote, heard)
}

/// Feeds a fixture's `IN` records to the upstream and checks that the client hears exactly
/// the fixture's `OUT` records (C++'s output), in order. Returns how many values were compared.
/// With `restamp`, each expected report carries its input's time (where C++ stamps 0).
fn replay_tracker_fixture(
    fixture: &str,
    cfg: impl Fn(&str) -> String,
    name: &str,
    restamp: bool,
) -> usize {
    let mut up = Upstream::new();
    let (server, remote, heard) = start_tracker(&up, &cfg(&up.at()), name);
    let recs = records(fixture);
    let mut want: Vec<Vec<f64>> = Vec::new();
    for (i, (tag, v)) in recs.iter().enumerate() {
        if tag != "IN" {
            continue;
        }
        let t = TimeVal {
            sec: v[0] as i64,
            usec: v[1] as i64,
        };
        let n = v[2] as usize;
        up.send(t, &v[3..3 + n]);
        want.extend(
            recs[i + 1..]
                .iter()
                .take_while(|(t, _)| t != "IN")
                .map(|(_, o)| {
                    let mut o = o.clone();
                    if restamp {
                        (o[1], o[2]) = (v[0], v[1]);
                    }
                    o
                }),
        );
        let (c, r) = (&up.conn, &remote);
        pump_until(
            &[&|| drop(c.mainloop()), &|| drop(r.mainloop())],
            "the reports of an input",
            &server,
            || heard.borrow().len() >= want.len(),
        );
    }
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(100) {
        let _ = up.conn.mainloop();
        let _ = remote.mainloop();
        std::thread::sleep(Duration::from_millis(1));
    }
    let heard = heard.borrow();
    assert_eq!(heard.len(), want.len(), "reports heard vs C++'s");
    for (k, (h, w)) in heard.iter().zip(&want).enumerate() {
        assert_eq!(h, w, "report {k}: heard {h:?}, C++ sent {w:?}");
    }
    want.len() * want.first().map_or(0, Vec::len)
}

#[test]
fn gametrak_reports_what_cxx_reports() {
    let compared = replay_tracker_fixture(
        include_str!("fixtures/cxx_gametrak.txt"),
        |src| format!("vrpn_Tracker_GameTrak GT {src}\naxis_mapping 1 0 2 4 3 5\n"),
        "GT",
        false,
    );
    assert_eq!(compared, 120 * 10);
}

/// A heard glove report or button change, in arrival order.
enum Heard {
    Glove(TimeVal, Vec<f64>),
    Button(TimeVal, usize, bool),
}

#[test]
fn glove_buttons_from_a_local_5dt16() {
    use vrpn::drivers::glove5dt16::sim::{Glove16Sim, SimConfig};
    use vrpn::sim::SimulatedDevice;
    use vrpn::{AnalogRemote, ButtonRemote};
    const T: [f64; 16] = [
        2048.0, 1000.0, 3000.0, 2500.0, 1500.0, 2048.5, 100.0, 4000.0, 2000.0, 2100.0, 1800.0,
        2600.0, 900.0, 3500.0, 0.0, 4095.0,
    ];
    let glove =
        SimulatedDevice::start("glove16", || Glove16Sim::new(SimConfig::new(19200))).unwrap();
    let thresholds: Vec<String> = T.iter().map(|t| t.to_string()).collect();
    let cfg = format!(
        "vrpn_5dt16 Glove {} 19200\nvrpn_Button_5DT_Server B5 Glove {}\n",
        glove.path().display(),
        thresholds.join(" ")
    );
    let server = ServerProcess::start(SERVER.as_ref(), &cfg).unwrap();
    let at = |n: &str| format!("{n}@tcp://127.0.0.1:{}", server.port());
    let analog = AnalogRemote::new(&at("Glove")).unwrap();
    let buttons = ButtonRemote::new(&at("B5")).unwrap();
    let heard: Rc<RefCell<Vec<Heard>>> = Rc::default();
    let h = heard.clone();
    analog.on_report(move |r| {
        h.borrow_mut()
            .push(Heard::Glove(r.sender_time, r.channels().to_vec()))
    });
    let h = heard.clone();
    buttons.on_change(move |c| {
        h.borrow_mut()
            .push(Heard::Button(c.sender_time, c.button, c.state.is_pressed()))
    });
    let reports = || {
        heard
            .borrow()
            .iter()
            .filter(|h| matches!(h, Heard::Glove(..)))
            .count()
    };
    let (a, b) = (&analog, &buttons);
    pump_until(
        &[&|| drop(a.mainloop()), &|| drop(b.mainloop())],
        "60 glove reports",
        &server,
        || reports() >= 60,
    );
    // Every change is of a button whose side of its threshold differs in the latest report
    // heard from what the client knew, and is stamped with that report's time (the server may
    // merge reports of one pass); after the last report the client knows its state exactly.
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(200) {
        let _ = analog.mainloop();
        let _ = buttons.mainloop();
        std::thread::sleep(Duration::from_millis(1));
    }
    let heard = heard.borrow();
    let mut latest: Option<(TimeVal, Vec<bool>)> = None;
    let mut known: Option<Vec<bool>> = None;
    let mut first: Option<TimeVal> = None;
    let mut compared = 0;
    for h in heard.iter() {
        match h {
            Heard::Glove(t, ch) => {
                let now: Vec<bool> = (0..16).map(|i| ch[i] > T[i]).collect();
                if known.is_none() {
                    known = Some(now.clone());
                    first = Some(*t);
                }
                latest = Some((*t, now));
            }
            Heard::Button(t, i, p) => {
                let (lt, now) = latest.as_ref().expect("a report before any change");
                let known = known.as_mut().unwrap();
                if Some(*t) == first || (compared == 0 && *t != *lt) {
                    continue; // a change of the client's first report, or of one before it
                }
                assert_eq!((*t, *p), (*lt, now[*i]), "button {i}");
                assert_ne!(known[*i], *p, "button {i} changed to what it was");
                known[*i] = *p;
                compared += 1;
            }
        }
    }
    assert_eq!(
        known,
        latest.map(|l| l.1),
        "the client's buttons after the last report"
    );
    assert!(compared >= 20, "{compared} changes compared");
}

#[test]
fn analog_poser_drives_what_cxx_drives() {
    use vrpn::devices::analog_output::AnalogOutputServer;
    use vrpn::devices::poser::PoserRemote;
    let fixture = records(include_str!("fixtures/cxx_poser_analog.txt"));
    let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let ao = AnalogOutputServer::new("AO", &conn, 8).unwrap();
    let received: Rc<RefCell<Vec<Vec<f64>>>> = Rc::default();
    let r = received.clone();
    ao.on_request(move |v| r.borrow_mut().push(v.channel[..3].to_vec()));
    let at = format!("AO@127.0.0.1:{}", conn.local_port().unwrap());
    let cfg = format!(
        "vrpn_Poser_Analog PA 1\n\
         X {at} 0 0.5 2.0 -1 1.5\n\
         Y {at} 2 -0.25 -3.0 -2 2\n\
         Z {at} 1 0.0 0.1 0 100\n\
         RX NULL 0 0.0 1.0 -10 10\n\
         RY NULL 0 0.0 1.0 -10 10\n\
         RZ NULL 0 0.0 1.0 -10 10\n"
    );
    let server = ServerProcess::start(SERVER.as_ref(), &cfg).unwrap();
    let name = format!("PA@tcp://127.0.0.1:{}", server.port());
    let poser = PoserRemote::new(&name).unwrap();
    let tracker = TrackerRemote::new(&name).unwrap();
    let heard = watch_poses(&tracker);
    let h = heard.clone();
    tracker.on_velocity(move |v| {
        h.borrow_mut().push(vec![
            v.sensor as f64,
            v.vel.x,
            v.vel.y,
            v.vel.z,
            v.vel_quat.i,
            v.vel_quat.j,
            v.vel_quat.k,
            v.vel_quat.w,
            v.vel_quat_dt,
        ])
    });
    let (c, p, t) = (&conn, &poser, &tracker);
    let all: [&dyn Fn(); 3] = [&|| drop(c.mainloop()), &|| drop(p.mainloop()), &|| {
        drop(t.mainloop())
    }];
    pump_until(&all, "the connections", &server, || {
        c.connected_peers() >= 1 && p.connection().connected() && t.connection().connected()
    });
    let (mut ao_want, mut tracker_want) = (0, 0);
    for (tag, v) in &fixture {
        match tag.as_str() {
            "IN" => {
                let time = TimeVal {
                    sec: v[0] as i64,
                    usec: v[1] as i64,
                };
                poser
                    .request_pose(time, [v[2], v[3], v[4]], [v[5], v[6], v[7], v[8]])
                    .unwrap();
                ao_want += 3;
                tracker_want += 1;
            }
            "INVEL" => {
                let time = TimeVal { sec: 1, usec: 0 };
                poser
                    .request_pose_velocity(time, [v[0], v[1], v[2]], [v[3], v[4], v[5], v[6]], v[7])
                    .unwrap();
                tracker_want += 1;
            }
            _ => continue,
        }
        pump_until(&all, "the poser's outputs", &server, || {
            received.borrow().len() >= ao_want && heard.borrow().len() >= tracker_want
        });
    }
    let cxx_ao: Vec<Vec<f64>> = fixture
        .iter()
        .filter(|(t, _)| t == "AO")
        .map(|(_, v)| v.clone())
        .collect();
    assert_eq!(*received.borrow(), cxx_ao, "the analog output's channels");
    // Poses without their time (the server's clock), and velocities, as C++ sent them.
    let cxx_tracker: Vec<Vec<f64>> = fixture
        .iter()
        .filter_map(|(t, v)| match t.as_str() {
            "OUT" => Some([&v[..1], &v[3..]].concat()),
            "VEL" => Some(v.clone()),
            _ => None,
        })
        .collect();
    let heard: Vec<Vec<f64>> = heard
        .borrow()
        .iter()
        .map(|v| {
            if v.len() == 10 {
                [&v[..1], &v[3..]].concat()
            } else {
                v.clone()
            }
        })
        .collect();
    assert_eq!(heard, cxx_tracker, "the tracker's reports");
}

#[test]
fn joyfly_flies_as_cxx_flies() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/cxx_joyfly.cfg");
    let compared = replay_tracker_fixture(
        include_str!("fixtures/cxx_joyfly.txt"),
        |src| format!("vrpn_JoyFly JF {src} {file}\n"),
        "JF",
        true,
    );
    assert_eq!(compared, 53 * 10);
}

/// `v` without records equal to the one before (a tracker's periodic repeats of its last
/// report).
fn without_repeats(v: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for r in v {
        if out.last() != Some(r) {
            out.push(r.clone());
        }
    }
    out
}

#[test]
fn wiimote_head_tracks_as_cxx_tracks() {
    let fixture = records(include_str!("fixtures/cxx_wiimote_head.txt"));
    let mut up = Upstream::new();
    let cfg = format!("vrpn_Tracker_WiimoteHead WH {} 4 0.25\n", up.at());
    let (server, remote, heard) = start_tracker(&up, &cfg, "WH");
    // Before any input: the start-up pose, 1 m in front of the camera, as C++.
    let (c, r) = (&up.conn, &remote);
    pump_until(
        &[&|| drop(c.mainloop()), &|| drop(r.mainloop())],
        "a report before any input",
        &server,
        || !heard.borrow().is_empty(),
    );
    for h in heard.borrow().iter() {
        assert_eq!(h[3..], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "{h:?}");
    }
    heard.borrow_mut().clear();
    let first_in = fixture.iter().position(|(t, _)| t == "IN").unwrap();
    let mut want: Vec<Vec<f64>> = Vec::new();
    for (i, (tag, v)) in fixture.iter().enumerate().skip(first_in) {
        if tag != "IN" {
            continue;
        }
        let t = TimeVal {
            sec: v[0] as i64,
            usec: v[1] as i64,
        };
        up.send(t, &v[3..3 + v[2] as usize]);
        want.extend(
            fixture[i + 1..]
                .iter()
                .take_while(|(t, _)| t != "IN")
                .map(|(_, o)| o.clone()),
        );
        let want_now = without_repeats(&want).len();
        let (c, r) = (&up.conn, &remote);
        pump_until(
            &[&|| drop(c.mainloop()), &|| drop(r.mainloop())],
            "the report of an input",
            &server,
            || without_repeats(&heard.borrow()).len() >= want_now,
        );
    }
    // A periodic repeat (4 a second) of the last pose.
    let last = heard.borrow().len();
    let (c, r) = (&up.conn, &remote);
    pump_until(
        &[&|| drop(c.mainloop()), &|| drop(r.mainloop())],
        "a periodic report",
        &server,
        || heard.borrow().len() > last,
    );
    let heard = heard.borrow();
    assert_eq!(
        heard.last(),
        want.last(),
        "the periodic report repeats the last"
    );
    // Periodic repeats fall wherever the server's clock puts them: compare without them.
    let (heard, want) = (without_repeats(&heard), without_repeats(&want));
    assert_eq!(heard.len(), 60, "one report per input");
    assert_eq!(heard.len(), want.len(), "reports heard vs C++'s");
    for (k, (h, w)) in heard.iter().zip(&want).enumerate() {
        assert_eq!(h, w, "report {k}: heard {h:?}, C++ sent {w:?}");
    }
}
