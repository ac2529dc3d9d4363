//! The 3SPACE and ISOTRAK drivers against the simulator on a virtual serial line, with the
//! driver's servers and a client's remotes on one in-process connection: reset bytes and
//! timing, exact values and stamps, styluses, resynchronisation, the watchdog, reopening,
//! failed resets, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::{Stylus, ThreeSpace};
use super::reset::{BREAK_GAP, CONFIG_GAP, QUIET};
use super::sim::{SentRecord, SimConfig, StatusReply, ThreeSpaceSim};
use super::ThreeSpaceProtocol;
use crate::config::continuation::ResetStep;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{ButtonRemote, Connection, Now, SenderFilter, TimeVal, TrackerPose, TrackerRemote};

type Shared<T> = Rc<RefCell<Vec<T>>>;

const ISOTRAK: &str = "vrpn_Tracker_Isotrak Iso0 /dev/ttyS0 19200\n";
const THREESPACE: &str = "vrpn_Tracker_3Space Tracker0 /dev/ttyS0 19200\n";

fn collect_texts(conn: &Connection, name: &str) -> Shared<(TextSeverity, String)> {
    let texts: Shared<(TextSeverity, String)> = Rc::default();
    let sender = conn.register_sender(name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((sev, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push((sev, text.to_owned()));
        }
    });
    texts
}

struct Rig {
    line: VirtualLine<Lifecycle<ThreeSpaceProtocol>, ThreeSpaceSim>,
    start: Now,
    poses: Shared<TrackerPose>,
    buttons: Shared<(String, bool, TimeVal)>,
    texts: Shared<(TextSeverity, String)>,
    _remotes: (TrackerRemote, Vec<ButtonRemote>),
    _conn: Connection,
}

fn rig(cfg_text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: ThreeSpace = parse_one(cfg_text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
    let buttons: Shared<(String, bool, TimeVal)> = Rc::default();
    let mut button_remotes = Vec::new();
    for s in &cfg.styluses {
        let r = ButtonRemote::on_connection(&s.name, &conn).unwrap();
        let (b, name) = (buttons.clone(), s.name.clone());
        r.on_change(move |c| {
            b.borrow_mut()
                .push((name.clone(), c.state.is_pressed(), c.time))
        });
        button_remotes.push(r);
    }
    let texts = collect_texts(&conn, &cfg.name);
    let mut sim = SimConfig::new(cfg.model, cfg.baud);
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, ThreeSpaceSim::new(sim), start, seed),
        start,
        poses,
        buttons,
        texts,
        _remotes: (remote, button_remotes),
        _conn: conn,
    }
}

impl Rig {
    fn run_to_first_pose(&mut self, max: Duration) -> Duration {
        let poses = self.poses.clone();
        let opened = self.line.now().mono;
        assert!(
            self.line.run_until(max, |_| !poses.borrow().is_empty()),
            "no pose within {max:?}; texts: {:?}",
            self.texts.borrow()
        );
        self.line.now().mono - opened
    }

    /// Runs to a moment between records, then forgets what was sent and seen.
    fn forget(&mut self) {
        let poses = self.poses.clone();
        let n = poses.borrow().len();
        assert!(self
            .line
            .run_until(Duration::from_secs(1), |_| poses.borrow().len() > n));
        self.line.device.clear_log();
        self.poses.borrow_mut().clear();
        self.buttons.borrow_mut().clear();
    }

    fn run_to_streaming(&mut self) {
        self.run_to_first_pose(Duration::from_secs(30));
        self.forget();
    }

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.texts.borrow();
        t.iter().filter(|(_, t)| t.contains(needle)).count()
    }

    fn arrival_wall(&self, t: Instant) -> TimeVal {
        self.start
            .wall
            .plus(t + self.line.latency - self.start.mono)
    }

    fn assert_pose(&self, pose: &TrackerPose, rec: &SentRecord) {
        let (sensor, pos, quat) = rec.sample.expected();
        assert_eq!(pose.sensor, sensor, "{rec:?}");
        assert_eq!([pose.pos.x, pose.pos.y, pose.pos.z], pos, "{rec:?}");
        let q = pose.quat.into_inner();
        assert_eq!([q.i, q.j, q.k, q.w], quat, "{rec:?}");
        // A slow read's records all carry its wake time: values only.
        if self.line.read_lag.is_zero() {
            assert_eq!(pose.time, self.arrival_wall(rec.first_byte), "{rec:?}");
        }
    }

    /// The poses seen are exactly the records sent, in order, but for one still on the line.
    fn assert_all_arrived(&self) {
        let sent = self.line.device.sent();
        let poses = self.poses.borrow();
        assert!(!poses.is_empty());
        assert!(
            sent.len() - poses.len() <= 1,
            "{} sent, {} arrived; texts {:?}",
            sent.len(),
            poses.len(),
            self.texts.borrow()
        );
        for (p, rec) in poses.iter().zip(sent) {
            self.assert_pose(p, rec);
        }
    }

    fn commands(&self) -> Vec<String> {
        self.line.device.commands().to_vec()
    }
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers or records at once: the reset
    // still completes, and every record from the first after it is reported, in order. (The
    // reset ends by asking for records: none can share a read with its last answer.)
    let mut r = rig(THREESPACE, |_| {}, 21);
    r.line.read_lag = Duration::from_millis(12);
    assert!(r
        .line
        .run_until(Duration::from_secs(10), |l| l.driver.is_streaming()));
    r.line.device.clear_log();
    r.poses.borrow_mut().clear();
    r.line.run_for(Duration::from_secs(2));
    assert!(r.poses.borrow().len() > 40, "{}", r.poses.borrow().len());
    r.assert_all_arrived();
}

#[test]
fn port_settings_and_what_is_served() {
    let r = rig(
        "vrpn_Tracker_Isotrak Iso1 /dev/ttyUSB0 9600 /\nStylus Pen 1\n",
        |_| {},
        1,
    );
    assert_eq!(r.line.driver.name(), "Iso1");
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    assert_eq!(r.line.driver.protocol().tracker().num_sensors(), 2);
    let r = rig(THREESPACE, |_| {}, 1);
    assert_eq!(r.line.driver.protocol().tracker().num_sensors(), 4);
}

#[test]
fn the_isotrak_reset_sends_c_plus_plus_commands_and_starts_in_half_a_second() {
    let mut r = rig(ISOTRAK, |_| {}, 2);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    assert_eq!(
        r.commands(),
        strings(&[
            "c",
            "S",
            "O2,11",
            "x0.2,0.2,0.8,0.8",
            "v0.2,0.2,0.8,0.8",
            "R1",
            "b1",
            "u",
            "S",
            "f",
            "C"
        ])
    );
    // Quiet after the stop, the status, six settings 50 ms apart, the barrier, the first
    // record (C++: 7 s of sleeps, then it blocks for the first record).
    let floor = QUIET + CONFIG_GAP * 6;
    assert!(
        startup > floor && startup < floor + Duration::from_millis(120),
        "{startup:?}"
    );
    assert_eq!(r.texts_with("Resetting the Isotrak (attempt 1)"), 1);
    assert_eq!(r.texts_with("gives status of 21 characters"), 1);
    assert_eq!(r.texts_with("Reset Completed"), 1);
    assert!(r.line.device.is_binary());
}

#[test]
fn the_3space_reset_reinitialises_and_waits_only_as_long_as_the_tracker() {
    let mut r = rig(
        THREESPACE,
        |s| s.reboot_time = Duration::from_millis(800),
        3,
    );
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    // Ctrl-Y; `S` is not heard while the tracker reinitialises, then it is answered.
    assert_eq!(r.commands(), strings(&["^Y", "S", "O2,11", "S", "f", "C"]));
    assert!(
        startup > Duration::from_millis(800) && startup < Duration::from_millis(1400),
        "{startup:?} (C++: 16 s of sleeps)"
    );
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn values_and_first_byte_times_arrive_exactly_in_order() {
    for (seed, text, baud, stations) in [
        (4, ISOTRAK, 19200, vec![1u8]),
        (5, THREESPACE, 19200, vec![1, 2, 3, 4]),
        (
            6,
            "vrpn_Tracker_Isotrak Iso0 /dev/ttyS0 115200\n",
            115200,
            vec![1, 2],
        ),
        (
            7,
            "vrpn_Tracker_3Space T /dev/ttyS0 9600\n",
            9600,
            vec![4, 1],
        ),
    ] {
        let mut r = rig(text, |s| s.stations = stations.clone(), seed);
        assert_eq!(r.line.device.config().baud, baud);
        r.line.split_reads = true;
        r.run_to_streaming();
        r.line.run_for(Duration::from_secs(2));
        assert!(r.poses.borrow().len() >= 40, "{}", r.poses.borrow().len());
        r.assert_all_arrived();
        let sensors: Vec<usize> = r.poses.borrow().iter().map(|p| p.sensor).collect();
        for s in &stations {
            assert!(sensors.contains(&(usize::from(*s) - 1)));
        }
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    }
}

#[test]
fn styluses_report_their_switch_before_the_pose() {
    let text = "vrpn_Tracker_Isotrak Iso0 /dev/ttyS0 38400 /\nStylus Pen0 0 /\nStylus Pen1 1\n";
    let mut r = rig(text, |s| s.stations = vec![1, 2], 8);
    r.run_to_streaming();
    r.line.run_for(Duration::from_secs(2));
    r.assert_all_arrived();
    // Replay the switch per station from the log: a change is reported at its record's time.
    let sent = r.line.device.sent().to_vec();
    let mut state = [None::<bool>; 2];
    let mut want = Vec::new();
    for rec in &sent[..r.poses.borrow().len()] {
        let s = usize::from(rec.sample.station) - 1;
        let pressed = rec.sample.stylus().unwrap();
        if state[s] != Some(pressed) {
            // The first record after `forget` may repeat the state the button already had.
            want.push((format!("Pen{s}"), pressed, r.arrival_wall(rec.first_byte)));
        }
        state[s] = Some(pressed);
    }
    let got = r.buttons.borrow().clone();
    assert!(got.len() >= 10, "{got:?}");
    // Everything heard is a change the records show (the first per pen may be absent: the
    // button already had that state before `forget`).
    let first_two: Vec<_> = want.iter().take(2).cloned().collect();
    let rest: Vec<_> = want
        .iter()
        .filter(|w| !first_two.contains(w))
        .cloned()
        .collect();
    for w in &rest {
        assert!(got.contains(w), "missing {w:?}");
    }
    assert!(got.iter().all(|g| want.contains(g)), "{got:?}");
}

#[test]
fn garbage_between_records_loses_nothing() {
    let mut r = rig(ISOTRAK, |_| {}, 9);
    r.line.split_reads = true;
    r.run_to_streaming();
    let noise: [&[u8]; 4] = [
        &[0x00, 0x7F, 0x41],
        &[0x85, 0x12, 0x33],
        &[0x90, 0x31, 0x31, 0x80, 0x01],
        &[0xFF],
    ];
    for n in noise {
        r.line.run_for(Duration::from_millis(60));
        let now = r.line.now().mono;
        r.line.device.inject(n, now);
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 12);
    assert!(r.texts_with("skipped") >= 1);
}

#[test]
fn a_silent_tracker_is_reopened_reset_and_resumes() {
    let mut r = rig(ISOTRAK, |_| {}, 10);
    r.run_to_streaming();
    r.line.device.mute = true;
    assert!(r.line.run_until(Duration::from_secs(3), |l| l.opens == 2));
    assert_eq!(r.texts_with("Tracker failed to read"), 1);
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 1);
    r.line.device.mute = false;
    r.poses.borrow_mut().clear();
    r.run_to_first_pose(Duration::from_secs(5));
    r.forget();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.stats().resets, 2);
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(THREESPACE, |_| {}, 11);
    r.run_to_streaming();
    r.line.close();
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.poses.borrow_mut().clear();
    r.run_to_first_pose(Duration::from_secs(5));
    r.forget();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.texts_with("Tracker failed"), 0);
}

#[test]
fn failed_status_answers_escalate_the_break_as_c_plus_plus_does() {
    for (reply, needle) in [
        (StatusReply::Silent, "did not answer the status request"),
        (StatusReply::Garbage, "Bad status report from Isotrak (X1S"),
        (StatusReply::Short, "Got 5 of 21 characters for status"),
    ] {
        let mut r = rig(ISOTRAK, |s| s.status_reply = reply, 12);
        r.line.run_for(Duration::from_secs(4));
        assert!(r.poses.borrow().is_empty());
        assert!(
            r.texts_with(needle) >= 2,
            "{reply:?}: {:?}",
            r.texts.borrow()
        );
        // Attempt 2 starts with CR, attempt 3 adds Ctrl-Y before the stop.
        let cmds = r.commands();
        let stops: Vec<usize> = cmds
            .iter()
            .enumerate()
            .filter(|(_, c)| c.as_str() == "c")
            .map(|(i, _)| i)
            .collect();
        assert!(stops.len() >= 2, "{reply:?}: {cmds:?}");
        assert_eq!(cmds[stops[1] - 1], "\\r");
        r.line.device.set_status_reply(StatusReply::Good);
        r.run_to_first_pose(Duration::from_secs(30));
        assert_eq!(r.line.driver.protocol().reset_attempts(), 0);
        let texts = r.texts.borrow().clone();
        assert!(
            texts
                .iter()
                .filter(|(_, t)| t.contains(needle))
                .all(|(s, _)| *s == TextSeverity::Error),
            "{texts:?}"
        );
    }
    // The third attempt's break: CR, Ctrl-Y, `c`, each 100 ms apart.
    let mut r = rig(ISOTRAK, |s| s.status_reply = StatusReply::Garbage, 13);
    assert!(r.line.run_until(Duration::from_secs(10), |l| l
        .device
        .heard()
        .contains(&0x19)));
    r.line.run_for(Duration::from_millis(150));
    let writes: Vec<(Instant, Vec<u8>)> = r.line.written.clone();
    let i = writes.iter().position(|(_, w)| w == &[0x19]).unwrap();
    assert_eq!(writes[i - 1].1, b"\r");
    assert_eq!(writes[i + 1].1, b"c");
    assert_eq!(writes[i].0 - writes[i - 1].0, BREAK_GAP);
    assert_eq!(writes[i + 1].0 - writes[i].0, BREAK_GAP);
}

#[test]
fn extra_reset_commands_and_pauses_go_out_in_order() {
    let text =
        "vrpn_Tracker_Isotrak Iso0 /dev/ttyS0 19200 \\\nH1,0,1,0\\\n*1\\\nN1 /\nStylus S0 0\n";
    let mut r = rig(text, |_| {}, 14);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    let cmds = r.commands();
    let u = cmds.iter().position(|c| c == "u").unwrap();
    assert_eq!(
        cmds[u + 1..],
        strings(&["H1,0,1,0", "N1 ", "S", "f", "C"])[..]
    );
    let writes = r.line.written.clone();
    let h = writes.iter().position(|(_, w)| w == b"H1,0,1,0\r").unwrap();
    assert_eq!(writes[h + 1].1, b"N1 \r");
    assert_eq!(
        writes[h + 1].0 - writes[h].0,
        CONFIG_GAP + Duration::from_secs(1)
    );
    assert!(startup > Duration::from_secs(1), "{startup:?}");
    let cfg: ThreeSpace = parse_one(text);
    assert_eq!(
        cfg.reset_commands,
        [
            ResetStep::Command("H1,0,1,0".into()),
            ResetStep::Pause(1),
            ResetStep::Command("N1 ".into())
        ]
    );
    assert_eq!(
        cfg.styluses,
        [Stylus {
            name: "S0".into(),
            sensor: 0
        }]
    );
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Tracker_3Space Tracker0 /dev/ttyS0 19200\n\
                vrpn_Tracker_Isotrak\tTrackerIsotrak\t/dev/ttyS1\t115200 \\\n\
                H1,0,1,0\n\
                vrpn_Tracker_Isotrak Iso2 /dev/ttyS2 9600 /\n\
                Stylus Stylus0 0 /\n\
                Stylus Stylus1 1\n\
                vrpn_Tracker_Isotrak Iso3 COM1 19200\n";
    let entries = parse_str(text, "3space.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 4);
    assert_eq!(names, ["Tracker0", "TrackerIsotrak", "Iso2", "Iso3"]);
    for (bad, why) in [
        ("vrpn_Tracker_3Space T /dev/ttyS0\n", "baud"),
        ("vrpn_Tracker_3Space T /dev/ttyS0 1234\n", "1234"),
        (
            "vrpn_Tracker_Isotrak T /dev/ttyS0 19200 IS900time\n",
            "IS900time",
        ),
        (
            "vrpn_Tracker_Isotrak T /dev/ttyS0 19200 /\nStylus S 2\n",
            "Stylus sensor",
        ),
        (
            "vrpn_Tracker_Isotrak T /dev/ttyS0 19200 /\nWand W 0\n",
            "Wand",
        ),
        (
            "vrpn_Tracker_Isotrak T /dev/ttyS0 19200 /\nStylus S\n",
            "sensor",
        ),
        (
            "vrpn_Tracker_Isotrak T /dev/ttyS0 19200 /\nStylus S 0 /\nStylus U 0\n",
            "two Stylus",
        ),
        ("vrpn_Tracker_Isotrak T /dev/ttyS0 19200 \\\n*x\n", "pause"),
        (
            "vrpn_Tracker_Isotrak T /dev/ttyS0 19200 \\\n",
            "reset command",
        ),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(e.contains("bad.cfg:") && e.contains(why), "{bad:?}: {e}");
    }
}
