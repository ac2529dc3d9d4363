//! The Liberty driver against the simulator on a virtual serial line, with the driver's
//! servers and a client's remotes on one in-process connection: reset bytes and timing, exact
//! values and stamps, styluses, Patriot and Latus records, resynchronisation, the watchdog,
//! reopening, failed resets, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::{Liberty, Stylus};
use super::reset::{BREAK_GAP, CONFIG_GAP, CTRL_Y, QUIET};
use super::sim::{Kind, LibertySim, SentRecord, SimConfig, WhoAmI};
use super::LibertyProtocol;
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

const LINE: &str = "vrpn_Tracker_Liberty Liberty /dev/ttyS0 115200\n";

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
    line: VirtualLine<Lifecycle<LibertyProtocol>, LibertySim>,
    start: Now,
    poses: Shared<TrackerPose>,
    buttons: Shared<(String, usize, bool, TimeVal)>,
    texts: Shared<(TextSeverity, String)>,
    _remotes: (TrackerRemote, Vec<ButtonRemote>),
    _conn: Connection,
}

fn rig(cfg_text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Liberty = parse_one(cfg_text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
    let buttons: Shared<(String, usize, bool, TimeVal)> = Rc::default();
    let mut button_remotes = Vec::new();
    for s in &cfg.styluses {
        let r = ButtonRemote::on_connection(&s.name, &conn).unwrap();
        let (b, name) = (buttons.clone(), s.name.clone());
        r.on_change(move |c| {
            b.borrow_mut()
                .push((name.clone(), c.button, c.state.is_pressed(), c.time))
        });
        button_remotes.push(r);
    }
    let texts = collect_texts(&conn, &cfg.name);
    let mut sim = SimConfig::new(Kind::Liberty, cfg.baud);
    sim.keep_log = true;
    sim.whoami_len = cfg.whoami_len;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, LibertySim::new(sim), start, seed),
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

    fn forget(&mut self) {
        let poses = self.poses.clone();
        let n = poses.borrow().len();
        assert!(self
            .line
            .run_until(Duration::from_secs(1), |_| poses.borrow().len() > n));
        // Run to the end of the frame: the log starts with a frame's first record.
        let stations = self.line.device.config().stations.len();
        let poses = self.poses.clone();
        assert!(self
            .line
            .run_until(Duration::from_secs(1), |_| poses.borrow().len() % stations
                == 0));
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

    fn assert_all_arrived(&self) {
        let sent = self.line.device.sent();
        let poses = self.poses.borrow();
        assert!(!poses.is_empty());
        let stations = self.line.device.config().stations.len();
        assert!(
            sent.len() - poses.len() <= stations,
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
    let mut r = rig(LINE, |_| {}, 21);
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
        "vrpn_Tracker_Liberty L /dev/ttyUSB0 9600 247 /\nStylus S 3\n",
        |_| {},
        1,
    );
    assert_eq!(r.line.driver.name(), "L");
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    assert_eq!(r.line.driver.protocol().tracker().num_sensors(), 8);
}

#[test]
fn the_reset_sends_c_plus_plus_commands_and_starts_in_about_a_second() {
    let mut r = rig(LINE, |_| {}, 2);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    assert_eq!(
        r.commands(),
        strings(&[
            "F0",
            "P",
            "^V",
            "O1,2,7,8,0",
            "O2,2,7,8,0",
            "O3,2,7,8,0",
            "O4,2,7,8,0",
            "O5,2,7,8,0",
            "O6,2,7,8,0",
            "O7,2,7,8,0",
            "O8,2,7,8,0",
            "X0,1,0,0",
            "Y0,1,0,0",
            "F1",
            "C",
            "Q0"
        ])
    );
    // Four gaps in the break, quiet, the WhoAmI answer (195 bytes), ten settings 50 ms apart,
    // quiet, the first frame (C++: about 15 s of sleeps).
    let floor = BREAK_GAP * 4 + QUIET * 2 + CONFIG_GAP * 10;
    assert!(
        startup > floor && startup < floor + Duration::from_millis(150),
        "{startup:?}"
    );
    assert_eq!(r.texts_with("Resetting the tracker (attempt 1)"), 1);
    assert_eq!(
        r.texts_with("Liberty/Isense gives status (this is good)"),
        1
    );
    assert_eq!(r.texts_with("Got >=1 characters after reset"), 0);
    assert_eq!(r.texts_with("Reset Completed (this is good)"), 1);
    assert!(r.line.device.is_streaming_binary());
}

#[test]
fn values_and_first_byte_times_arrive_exactly_in_order() {
    for (seed, text, kind, stations) in [
        (3, LINE, Kind::Liberty, vec![1u8]),
        (
            4,
            "vrpn_Tracker_Liberty L /dev/ttyS0 38400\n",
            Kind::Liberty,
            vec![1, 2, 5, 8],
        ),
        (
            5,
            "vrpn_Tracker_Liberty P /dev/ttyS0 115200\n",
            Kind::Patriot,
            vec![1, 2],
        ),
        (
            6,
            "vrpn_Tracker_Liberty L /dev/ttyS0 115200\n",
            Kind::Latus,
            vec![3],
        ),
    ] {
        let mut r = rig(
            text,
            |s| {
                s.kind = kind;
                s.stations = stations.clone();
            },
            seed,
        );
        r.line.split_reads = true;
        r.run_to_streaming();
        r.line.run_for(Duration::from_secs(2));
        assert!(r.poses.borrow().len() >= 60, "{}", r.poses.borrow().len());
        r.assert_all_arrived();
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0, "{kind:?}");
    }
}

#[test]
fn a_patriots_complaints_about_stations_it_lacks_are_dropped() {
    let mut r = rig(LINE, |s| s.kind = Kind::Patriot, 7);
    r.run_to_streaming();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.texts_with("skipped"), 0);
}

#[test]
fn styluses_report_their_switch_before_the_pose() {
    let text = "vrpn_Tracker_Liberty L /dev/ttyS0 115200 /\nStylus Pen 1\n";
    let mut r = rig(text, |s| s.stations = vec![1, 2], 8);
    r.run_to_streaming();
    assert!(r.commands().contains(&"O2,2,7,8,10,0".to_string()));
    r.line.run_for(Duration::from_secs(2));
    r.assert_all_arrived();
    let sent = r.line.device.sent().to_vec();
    let n = r.poses.borrow().len();
    let mut state: Option<bool> = None;
    let mut want = Vec::new();
    for rec in &sent[..n] {
        if let Some(s) = rec.sample.stylus {
            let pressed = s != 0;
            if state.is_some() && state != Some(pressed) {
                want.push((
                    "Pen".to_string(),
                    0,
                    pressed,
                    r.arrival_wall(rec.first_byte),
                ));
            }
            state = Some(pressed);
        }
    }
    let got = r.buttons.borrow().clone();
    assert!(want.len() >= 5, "{want:?}");
    // The first change heard may be the state at the start of the log.
    assert!(got.ends_with(&want), "got {got:?}, want {want:?}");
}

#[test]
fn garbage_between_records_loses_nothing() {
    let mut r = rig(LINE, |s| s.stations = vec![1, 2], 9);
    r.line.split_reads = true;
    r.run_to_streaming();
    let noise: [&[u8]; 4] = [b"LYxx", b"PA\x09junk ", b"L", &[0x00, 0xFF, b' ']];
    for n in noise {
        r.line.run_for(Duration::from_millis(60));
        let now = r.line.now().mono;
        r.line.device.inject(n, now);
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 16);
    assert!(r.texts_with("skipped") >= 1);
}

#[test]
fn a_silent_tracker_is_reopened_reset_and_resumes() {
    let mut r = rig(LINE, |_| {}, 10);
    r.run_to_streaming();
    r.line.silent = true;
    assert!(r.line.run_until(Duration::from_secs(3), |l| l.opens == 2));
    assert_eq!(r.texts_with("Tracker failed to read"), 1);
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 1);
    r.line.silent = false;
    r.poses.borrow_mut().clear();
    r.run_to_first_pose(Duration::from_secs(10));
    r.forget();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.stats().resets, 2);
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(LINE, |_| {}, 11);
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
fn failed_whoami_answers_escalate_to_a_reinitialisation() {
    for (w, needle) in [
        (WhoAmI::Silent, "did not answer WhoAmI"),
        (WhoAmI::Wrong, "Bad status report from Liberty (?  Polhemus"),
    ] {
        let mut r = rig(LINE, |s| s.whoami = w, 12);
        assert!(r.line.run_until(Duration::from_secs(10), |l| l
            .device
            .commands()
            .contains(&"^Y".into())));
        r.line.run_for(Duration::from_millis(250));
        assert!(r.poses.borrow().is_empty());
        assert_eq!(r.texts_with(needle), 2, "{w:?}: {:?}", r.texts.borrow());
        assert_eq!(r.texts_with("Resetting the tracker (attempt 3)"), 1);
        // The third break: CR F 0 CR Ctrl-Y CR P, each 100 ms apart.
        let writes = r.line.written.clone();
        let y = writes.iter().rposition(|(_, b)| b == &[CTRL_Y]).unwrap();
        let bytes: Vec<u8> = writes[y - 4..y + 3].iter().map(|(_, b)| b[0]).collect();
        assert_eq!(bytes, b"\rF0\r\x19\rP");
        assert_eq!(writes[y].0 - writes[y - 1].0, BREAK_GAP);
        r.line.device.set_whoami(WhoAmI::Good);
        // The tracker reinitialises (0.5 s); WhoAmI is asked again until it answers.
        r.run_to_first_pose(Duration::from_secs(10));
        assert_eq!(r.line.driver.protocol().reset_attempts(), 0);
    }
}

#[test]
fn extra_reset_commands_and_pauses_go_out_before_streaming() {
    let text = "vrpn_Tracker_Liberty L /dev/ttyS0 115200 \\\nH1,0,0,1\\\n*1\\\nU1/\nStylus S 0\n";
    let mut r = rig(text, |_| {}, 13);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    let cmds = r.commands();
    let y = cmds.iter().position(|c| c == "Y0,1,0,0").unwrap();
    assert_eq!(
        cmds[y + 1..],
        strings(&["H1,0,0,1", "U1", "F1", "C", "Q0"])[..]
    );
    assert_eq!(cmds[3], "O1,2,7,8,10,0");
    assert!(startup > Duration::from_secs(2), "{startup:?}");
    let cfg: Liberty = parse_one(text);
    assert_eq!(
        cfg.reset_commands,
        [
            ResetStep::Command("H1,0,0,1".into()),
            ResetStep::Pause(1),
            ResetStep::Command("U1".into())
        ]
    );
    assert_eq!(
        cfg.styluses,
        [Stylus {
            name: "S".into(),
            sensor: 0
        }]
    );
}

#[test]
fn a_longer_whoami_is_read_whole_and_a_shorter_one_noted() {
    for (cfg_len, sim_len, note) in [(247, 247, 0), (195, 120, 1), (100, 195, 0)] {
        let text = format!("vrpn_Tracker_Liberty L /dev/ttyS0 115200 {cfg_len}\n");
        let mut r = rig(&text, |s| s.whoami_len = sim_len, 14);
        r.run_to_first_pose(Duration::from_secs(5));
        assert_eq!(
            r.texts_with("characters for status"),
            note,
            "{cfg_len} {sim_len}"
        );
        r.forget();
        r.line.run_for(Duration::from_millis(300));
        r.assert_all_arrived();
        assert_eq!(r.texts_with("skipped"), 0);
    }
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Tracker_Liberty\tLiberty\t/dev/usb/ttyUSB0\t115200\n\
                vrpn_Tracker_Liberty   Liberty1 /dev/ttyS0        115200\n\
                vrpn_Tracker_Liberty   Liberty2 /dev/ttyS1        115200\t247\n\
                vrpn_Tracker_Liberty\tTracker0\t/dev/ttyS2\t115200 /\n\
                Stylus Stylus0 0 /\n\
                Stylus Stylus1 3\n";
    let entries = parse_str(text, "liberty.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 4);
    assert_eq!(names, ["Liberty", "Liberty1", "Liberty2", "Tracker0"]);
    for (bad, why) in [
        ("vrpn_Tracker_Liberty L /dev/ttyS0\n", "baud"),
        ("vrpn_Tracker_Liberty L /dev/ttyS0 115200 0\n", "whoami"),
        ("vrpn_Tracker_Liberty L /dev/ttyS0 115200 2000\n", "whoami"),
        ("vrpn_Tracker_Liberty L /dev/ttyS0 115200 195 x\n", "'x'"),
        (
            "vrpn_Tracker_Liberty L /dev/ttyS0 115200 /\nStylus S 8\n",
            "Stylus sensor",
        ),
        (
            "vrpn_Tracker_Liberty L /dev/ttyS0 115200 /\nWand W 0\n",
            "Wand",
        ),
        ("vrpn_Tracker_Liberty L /dev/ttyS0 115200 /\n", "Stylus"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(e.contains("bad.cfg:") && e.contains(why), "{bad:?}: {e}");
    }
    // The USB-only Liberty Latus keyword is unknown here, with a word on why.
    let entries = parse_str("vrpn_Tracker_LibertyHS L 3 115200\n", "hs.cfg").unwrap();
    let e = entries[0].unknown_error().unwrap().to_string();
    assert!(e.contains("hs.cfg:1") && e.contains("libusb"), "{e}");
}
