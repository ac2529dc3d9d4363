//! The Polaris driver against the simulator on a virtual serial line, with the driver's
//! server and a client's remote on one in-process connection: the reset's commands and the
//! tool images, exact values and stamps, missing tools, a refused tool, a tracker already
//! fast, garbage, the watchdog, configurations.

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Polaris;
use super::sim::{PolarisSim, SimConfig};
use super::PolarisProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{Connection, Now, SenderFilter, TimeVal, TrackerPose, TrackerRemote};

type Shared<T> = Rc<RefCell<Vec<T>>>;

/// A `.rom` file of `len` bytes in the temporary directory.
pub fn rom_file(tag: &str, len: usize) -> PathBuf {
    let path = std::env::temp_dir().join(format!("vrpn-polaris-{}-{tag}.rom", std::process::id()));
    let bytes: Vec<u8> = (0..len).map(|i| (i * 7 + tag.len()) as u8).collect();
    std::fs::write(&path, bytes).unwrap();
    path
}

fn line_with(tools: &[(&str, usize)]) -> String {
    let mut s = format!(
        "vrpn_Tracker_NDI_Polaris Polaris /dev/ttyUSB0 {}\n",
        tools.len()
    );
    for (tag, len) in tools {
        s.push_str(&format!("{}\n", rom_file(tag, *len).display()));
    }
    s
}

struct Rig {
    line: VirtualLine<Lifecycle<PolarisProtocol>, PolarisSim>,
    start: Now,
    poses: Shared<TrackerPose>,
    texts: Shared<(TextSeverity, String)>,
    cfg: Polaris,
    _remote: TrackerRemote,
    _conn: Connection,
}

fn rig(text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Polaris = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
    let texts: Shared<(TextSeverity, String)> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((sev, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push((sev, text.to_owned()));
        }
    });
    let mut sim = SimConfig::new();
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, PolarisSim::new(sim), start, seed),
        start,
        poses,
        texts,
        cfg,
        _remote: remote,
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

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.texts.borrow();
        t.iter().filter(|(_, t)| t.contains(needle)).count()
    }

    /// Every pose the client received is the simulator's, in order, stamped with the
    /// arrival of its reply's first byte.
    fn assert_all_arrived(&self, from_pose: usize, from_log: usize) {
        let sent = &self.line.device.sent()[from_log..];
        let poses = &self.poses.borrow()[from_pose..];
        assert!(!poses.is_empty());
        assert!(
            sent.len() - poses.len() <= self.cfg.tools.len(),
            "{} sent, {} arrived; texts {:?}",
            sent.len(),
            poses.len(),
            self.texts.borrow()
        );
        for (p, rec) in poses.iter().zip(sent) {
            let (sensor, pos, quat) = rec.values;
            assert_eq!(p.sensor, sensor, "{rec:?}");
            assert_eq!([p.pos.x, p.pos.y, p.pos.z], pos, "{rec:?}");
            let q = p.quat.into_inner();
            assert_eq!([q.i, q.j, q.k, q.w], quat, "{rec:?}");
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                let arrived = self
                    .start
                    .wall
                    .plus(rec.first_byte + self.line.latency - self.start.mono);
                assert_eq!(p.time, arrived, "{rec:?}");
            }
        }
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several replies at once: the reset still
    // completes, and every frame is reported, from the first (the reset ends by asking for
    // one: none can share a read with its last reply).
    let mut r = rig(&line_with(&[("m1", 64), ("m2", 64)]), |_| {}, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.run_to_first_pose(Duration::from_secs(5));
    r.line.run_for(Duration::from_secs(2));
    assert!(r.poses.borrow().len() > 40, "{}", r.poses.borrow().len());
    r.assert_all_arrived(0, 0);
}

#[test]
fn port_settings_and_what_is_served() {
    let r = rig(&line_with(&[("a", 100), ("b", 64)]), |_| {}, 1);
    assert_eq!(r.line.driver.name(), "Polaris");
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    assert_eq!(r.line.driver.protocol().tracker().num_sensors(), 2);
    assert_eq!(r.cfg.tools[0].read().unwrap().len(), 128);
    assert_eq!(r.cfg.tools[1].read().unwrap().len(), 64);
}

#[test]
fn the_reset_loads_every_tool_and_values_arrive_exactly() {
    let mut r = rig(&line_with(&[("one", 200), ("two", 64)]), |_| {}, 2);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    // Pulse 100 ms, settle 100 ms, switch 100 ms, and the replies.
    assert!(startup < Duration::from_millis(600), "{startup:?}");
    let c = r.line.device.commands().to_vec();
    let head: Vec<&str> = c
        .iter()
        .take(17)
        .map(|s| s.split_at(s.len().min(11)).0)
        .collect();
    assert_eq!(
        head,
        [
            "<RTS reset>",
            "COMM 50000",
            "INIT",
            "IRATE 0",
            "PHRQ ******",
            "PVWR 0A0000",
            "PVWR 0A0040",
            "PVWR 0A0080",
            "PVWR 0A00c0",
            "PINIT 0A",
            "PENA 0AD",
            "PHRQ ******",
            "PVWR 0B0000",
            "PINIT 0B",
            "PENA 0BD",
            "TSTART 80",
            "TX",
        ]
    );
    assert_eq!(r.line.device.baud(), 115_200);
    let roms = r.line.device.roms();
    assert_eq!(roms[0], r.cfg.tools[0].read().unwrap());
    assert_eq!(roms[1], r.cfg.tools[1].read().unwrap());
    assert_eq!(roms[0][..200], std::fs::read(&r.cfg.tools[0].file).unwrap());
    assert_eq!(r.line.driver.protocol().handles(), [Some(0x0A), Some(0x0B)]);
    r.line.run_for(Duration::from_secs(2));
    // 60 frames a second, two tools each, each frame once.
    let n = r.poses.borrow().len();
    assert!((230..=250).contains(&n), "{n} poses");
    r.assert_all_arrived(0, 0);
    let frames: Vec<u64> = r.line.device.sent().iter().map(|s| s.frame).collect();
    assert!(frames.windows(2).all(|w| w[0] <= w[1]));
}

#[test]
fn missing_tools_send_nothing_and_the_others_go_on() {
    let mut r = rig(
        &line_with(&[("m1", 64), ("m2", 64)]),
        |s| s.missing_every = Some(3),
        3,
    );
    r.run_to_first_pose(Duration::from_secs(5));
    r.line.run_for(Duration::from_secs(2));
    r.assert_all_arrived(0, 0);
    let sensors: Vec<usize> = r.poses.borrow().iter().map(|p| p.sensor).collect();
    assert!(sensors.contains(&0) && sensors.contains(&1));
    // A third of the frames of each tool are missing.
    let n = sensors.len();
    assert!((140..=180).contains(&n), "{n} poses");
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn a_refused_tool_is_reported_and_the_others_track() {
    let mut r = rig(
        &line_with(&[("r1", 64), ("r2", 64)]),
        |s| s.refuse_tools = vec![0],
        4,
    );
    r.run_to_first_pose(Duration::from_secs(5));
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.texts_with("didn't init properly"), 1, "{:?}", r.texts);
    assert!(r.poses.borrow().iter().all(|p| p.sensor == 1));
    r.assert_all_arrived(0, 0);
}

#[test]
fn a_tracker_left_fast_without_rts_is_found_at_115200() {
    let mut r = rig(
        &line_with(&[("f1", 64)]),
        |s| {
            s.tracking_at = Some(115_200);
            s.hears_rts = false;
        },
        5,
    );
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    assert!(startup < Duration::from_secs(1), "{startup:?}");
    assert_eq!(r.texts_with("trying 115200"), 1);
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived(0, 0);
}

#[test]
fn garbage_costs_no_pose_and_silence_resets_the_tracker() {
    let mut r = rig(&line_with(&[("g", 64)]), |_| {}, 6);
    r.run_to_first_pose(Duration::from_secs(5));
    for junk in [&b"xx\r"[..], b"01zz", b"\x00\xFFOKAY", b"0A+0"] {
        r.line.run_for(Duration::from_millis(100));
        r.line.inject(junk);
    }
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived(0, 0);
    assert!(r.line.driver.stats().skipped_bytes >= 10);
    // Silence: the tracker stops answering (a cut wire); the watchdog resets it.
    let before = r.line.driver.stats().resets;
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(3));
    assert!(r.line.driver.stats().watchdog_fired >= 1);
    assert!(r.texts_with("Tracker failed, trying to reset") >= 1);
    r.line.silent = false;
    let from_pose = r.poses.borrow().len();
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(10), |_| poses.borrow().len()
            > from_pose + 20));
    assert!(r.line.driver.stats().resets > before);
    // The poses after the reset are the tracker's, in order.
    let sent = r.line.device.sent();
    let first = r.poses.borrow()[from_pose];
    let at = sent
        .iter()
        .rposition(|s| {
            s.values
                == (first.sensor, [first.pos.x, first.pos.y, first.pos.z], {
                    let q = first.quat.into_inner();
                    [q.i, q.j, q.k, q.w]
                })
        })
        .unwrap();
    r.assert_all_arrived(from_pose, at);
}

#[test]
fn configuration_lines_and_their_errors() {
    let a = rom_file("cfg", 10);
    let text = format!(
        "vrpn_Tracker_NDI_Polaris T COM1 2\n{}\n  {}  \n",
        a.display(),
        a.display()
    );
    let p: Polaris = parse_one(&text);
    assert_eq!(p.tools.len(), 2);
    assert_eq!(p.tools[1].file, a.display().to_string());
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err();
    let conn = Connection::new_loopback();
    let missing: Polaris = parse_one("vrpn_Tracker_NDI_Polaris T COM1 1\n/nonexistent/x.rom\n");
    assert_eq!(missing.tools[0].line, 2);
    let e = missing.lifecycle(&conn).err().unwrap().to_string();
    assert!(
        e.contains("/nonexistent/x.rom") && e.contains("line 2"),
        "{e}"
    );
    let e = err(&format!(
        "vrpn_Tracker_NDI_Polaris T COM1 2\n{}\n",
        a.display()
    ));
    assert_eq!(e.kind(), ConfigErrorKind::UnclosedBlock);
    assert_eq!(
        err("vrpn_Tracker_NDI_Polaris T COM1 0\n").kind(),
        ConfigErrorKind::OutOfRange
    );
    assert_eq!(
        err("vrpn_Tracker_NDI_Polaris T COM1\n").kind(),
        ConfigErrorKind::MissingArguments
    );
    let big = rom_file("big", 1025);
    let big: Polaris = parse_one(&format!(
        "vrpn_Tracker_NDI_Polaris T COM1 1\n{}\n",
        big.display()
    ));
    let e = big.lifecycle(&conn).err().unwrap().to_string();
    assert!(e.contains("1025 bytes"), "{e}");
}
