//! The DynaSight driver against the simulator on a virtual serial line, with the driver's
//! tracker and a client's remote on one in-process connection: reset, exact values and
//! timestamps, resynchronisation, the watchdog, reopening, failed resets, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Dyna;
use super::reset::{CONTINUOUS, QUIET, STATUS_LIMIT, STATUS_REQUEST, STOP, STOP_LIMIT};
use super::sim::{DynaSim, SentRecord, SimConfig, StatusReply};
use super::{DynaProtocol, RETRY_DELAY};
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::{Lifecycle, Supervision};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{Connection, Now, SenderFilter, TimeVal, TrackerPose, TrackerRemote};

type Shared<T> = Rc<RefCell<Vec<T>>>;

const LINE: &str = "vrpn_Tracker_Dyna Dyna0 1 /dev/ttyS0 19200\n";

/// The watchdog every tracker has.
const WATCHDOG: Duration = match Supervision::TRACKER.watchdog {
    Some(d) => d,
    None => Duration::ZERO,
};

fn dyna_cfg(text: &str) -> Dyna {
    parse_one(text)
}

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
    line: VirtualLine<Lifecycle<DynaProtocol>, DynaSim>,
    start: Now,
    poses: Shared<TrackerPose>,
    texts: Shared<(TextSeverity, String)>,
    _remote: TrackerRemote,
    _conn: Connection,
}

fn rig(cfg_text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg = dyna_cfg(cfg_text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
    let texts = collect_texts(&conn, &cfg.name);
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, DynaSim::new(sim), start, seed),
        start,
        poses,
        texts,
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

    /// Runs until streaming and a first pose, then forgets what was sent and seen.
    fn run_to_streaming(&mut self) {
        self.run_to_first_pose(Duration::from_secs(10));
        self.forget();
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
        assert_eq!(pose.sensor, 0);
        let want = rec.sample.expected_position_m();
        assert_eq!([pose.pos.x, pose.pos.y, pose.pos.z], want, "{rec:?}");
        let q = pose.quat.into_inner();
        assert_eq!([q.i, q.j, q.k, q.w], [0.0, 0.0, 0.0, 1.0]);
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
            "{} sent, {} arrived",
            sent.len(),
            poses.len()
        );
        for (p, rec) in poses.iter().zip(sent) {
            self.assert_pose(p, rec);
        }
    }
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
fn port_settings_and_identity() {
    let r = rig("vrpn_Tracker_Dyna Dyna1 3 /dev/ttyUSB0 9600\n", |_| {}, 1);
    assert_eq!(r.line.driver.name(), "Dyna1");
    assert_eq!(r.line.driver.protocol().port(), "/dev/ttyUSB0");
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    assert_eq!(r.line.driver.protocol().tracker().num_sensors(), 3);
}

#[test]
fn reset_sends_c_plus_plus_bytes_and_starts_in_a_tenth_of_a_second() {
    let mut r = rig(LINE, |_| {}, 2);
    let startup = r.run_to_first_pose(Duration::from_secs(10));
    // Quiet 100 ms after the last streamed byte, the 8-byte answer (5 ms + 4.2 ms), then the
    // first record 5 ms after the continuous command (C++: 4 s).
    assert!(
        startup > QUIET && startup < QUIET + Duration::from_millis(40),
        "start-up took {startup:?}"
    );
    let written: Vec<&[u8]> = r.line.written.iter().map(|(_, b)| b.as_slice()).collect();
    assert_eq!(written, vec![STOP, &[STATUS_REQUEST][..], CONTINUOUS]);
    assert_eq!(
        r.line.device.heard(),
        [STOP, &[STATUS_REQUEST], CONTINUOUS].concat()
    );
    assert!(r.line.driver.is_streaming());
    assert_eq!(r.line.driver.stats().resets, 1);
    assert_eq!(r.texts_with("continuous output requested"), 1);
    assert_eq!(r.texts_with("kept sending"), 0);
}

#[test]
fn values_and_first_byte_times_arrive_exactly_in_order() {
    for (seed, baud) in [(3, 19200), (4, 9600), (5, 115200)] {
        let mut r = rig(
            &format!("vrpn_Tracker_Dyna Dyna0 1 /dev/ttyS0 {baud}\n"),
            |_| {},
            seed,
        );
        r.line.split_reads = true;
        r.run_to_streaming();
        r.line.run_for(Duration::from_secs(2));
        // 60 Hz for 2 s.
        assert!(r.poses.borrow().len() >= 119, "{}", r.poses.borrow().len());
        r.assert_all_arrived();
        // Every exponent code and both statuses occurred.
        let sent = r.line.device.sent();
        for e in 0..4 {
            assert!(sent.iter().any(|s| s.sample.exponent == e));
        }
        assert!(sent.iter().any(|s| s.sample.status == 1));
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    }
}

#[test]
fn garbage_between_records_loses_nothing() {
    let mut r = rig(LINE, |_| {}, 6);
    r.line.split_reads = true;
    r.run_to_streaming();
    // Plain noise, false starts (header-like bytes each followed by a byte that is not), one
    // byte. (A header-like byte right before a record can pass for its start: the protocol
    // has no checksum. See the framing module.)
    let noise: [&[u8]; 4] = [
        &[0x00, 0x7F, 0xFF, 0x41],
        &[0x85, 0x12, 0x80, 0x33, 0x22],
        &[0x8A, 0x00, 0x8B, 0x7F, 0x9C],
        &[0x55],
    ];
    for n in noise {
        r.line.run_for(Duration::from_millis(50));
        let now = r.line.now().mono;
        r.line.device.inject(n, now);
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
    assert!(r.line.driver.protocol().skipped_bytes() >= 10);
    assert!(r.texts_with("skipped") >= 1);
}

#[test]
fn a_silent_dynasight_is_reset_and_resumes() {
    let mut r = rig(LINE, |_| {}, 7);
    r.run_to_streaming();
    r.line.device.mute = true;
    let muted = r.line.now().mono;
    // The watchdog fires 2 s after the last record's first byte; the port is reopened.
    assert!(r.line.run_until(Duration::from_secs(3), |l| l.opens == 2));
    let reopened = r
        .line
        .written
        .iter()
        .rev()
        .find(|(_, w)| w.as_slice() == STOP);
    let fired = reopened.unwrap().0 - muted;
    assert!(
        fired > WATCHDOG - Duration::from_millis(20) && fired <= WATCHDOG,
        "{fired:?}"
    );
    assert_eq!(r.texts_with("Tracker failed to read"), 1);
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 1);
    // Still silent: a reset attempt gets no data and tries again.
    r.line
        .run_for(QUIET + STATUS_LIMIT + Duration::from_millis(50));
    assert_eq!(r.texts_with("no data"), 1);
    assert!(!r.line.driver.is_streaming());
    r.line.device.mute = false;
    r.forget_after_first_pose();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.stats().resets, 2);
}

impl Rig {
    fn forget_after_first_pose(&mut self) {
        self.poses.borrow_mut().clear();
        self.run_to_first_pose(Duration::from_secs(5));
        self.forget();
    }
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(LINE, |_| {}, 8);
    r.run_to_streaming();
    r.line.close();
    assert!(!r.line.driver.is_streaming());
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.forget_after_first_pose();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    // No time-out texts: the port's failure is the serial layer's to report.
    assert_eq!(r.texts_with("Tracker failed"), 0);
    assert_eq!(r.line.driver.stats().resets, 2);
}

#[test]
fn a_device_left_stopped_starts_the_same_way() {
    let mut r = rig(LINE, |s| s.streaming_at_start = false, 9);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    assert!(startup < QUIET + Duration::from_millis(40), "{startup:?}");
}

#[test]
fn a_stream_that_never_stops_is_reported_and_read_anyway() {
    let mut r = rig(LINE, |s| s.ignores_stop = true, 11);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    // The status request goes out after the longest wait; the stream's next record passes
    // for the answer.
    assert!(
        startup > STOP_LIMIT && startup < STOP_LIMIT + Duration::from_millis(60),
        "{startup:?}"
    );
    assert_eq!(r.texts_with("kept sending after the stop command"), 1);
    r.forget();
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
}

#[test]
fn wrong_status_answers_are_reported_and_retried() {
    for (reply, needle, severity, pause) in [
        (
            StatusReply::Garbage,
            "not a status record",
            TextSeverity::Error,
            RETRY_DELAY,
        ),
        (
            StatusReply::Short,
            "3 of 8 bytes",
            TextSeverity::Error,
            STATUS_LIMIT + RETRY_DELAY,
        ),
        (
            StatusReply::Silent,
            "no data",
            TextSeverity::Warning,
            STATUS_LIMIT,
        ),
    ] {
        let mut r = rig(LINE, |s| s.status_reply = reply, 10);
        r.line.run_for(Duration::from_secs(7));
        assert!(r.poses.borrow().is_empty());
        // Each attempt starts with the stop command; the attempts are paced by the time-out
        // and the retry pause, never faster.
        let stops: Vec<Instant> = r
            .line
            .written
            .iter()
            .filter(|(_, w)| w.as_slice() == STOP)
            .map(|(t, _)| *t)
            .collect();
        assert!(stops.len() >= 3, "{reply:?}: {} attempts", stops.len());
        for w in stops.windows(2) {
            let gap = w[1] - w[0];
            assert!(
                gap >= pause + QUIET && gap < pause + QUIET + Duration::from_millis(30),
                "{reply:?}: {gap:?}"
            );
        }
        let texts = r.texts.borrow().clone();
        let failures: Vec<_> = texts.iter().filter(|(_, t)| t.contains(needle)).collect();
        assert!(
            failures.len() + 1 >= stops.len() && failures.len() <= stops.len(),
            "{reply:?}: {texts:?}"
        );
        assert!(failures.iter().all(|(s, _)| *s == severity));
        assert_eq!(
            r.line.driver.protocol().reset_attempts() as usize,
            stops.len()
        );
        // The device recovers: the next attempt succeeds.
        r.line.device.set_status_reply(StatusReply::Record);
        r.run_to_first_pose(Duration::from_secs(4));
        assert_eq!(r.line.driver.protocol().reset_attempts(), 0);
    }
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Tracker_Dyna Dyna0 1 /dev/ttyS0 19200\n\
                vrpn_Tracker_Dyna\tDyna1\t4\t/dev/ttyUSB1\t115200\n\
                vrpn_Tracker_Dyna Dyna2 1 COM1 9600\n";
    let entries = parse_str(text, "dyna.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["Dyna0", "Dyna1", "Dyna2"]);
    for (bad, why) in [
        ("vrpn_Tracker_Dyna Dyna0 /dev/ttyS0 19200\n", "sensors"),
        ("vrpn_Tracker_Dyna Dyna0 1 /dev/ttyS0 12345\n", "12345"),
        ("vrpn_Tracker_Dyna Dyna0 1 /dev/ttyS0\n", ""),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("bad.cfg") && e.contains('2') && e.contains(why),
            "{e}"
        );
    }
}

#[test]
fn a_reset_never_invents_data() {
    let mut r = rig(LINE, |_| {}, 12);
    r.line.split_reads = true;
    r.run_to_streaming();
    r.line.run_for(Duration::from_millis(300));
    let before = r.poses.borrow().len();
    r.line.device.mute = true;
    // The watchdog, a reopen and failed resets: nothing reported meanwhile.
    r.line.run_for(WATCHDOG + STATUS_LIMIT * 2);
    assert!(r.texts_with("Tracker failed, trying to reset") >= 1);
    assert!(r.line.driver.stats().reset_attempts >= 3);
    // At most the record that was on its way when the device went quiet.
    assert!(r.poses.borrow().len() <= before + 1);
    r.line.device.mute = false;
    r.line.device.clear_log();
    r.poses.borrow_mut().clear();
    r.run_to_first_pose(Duration::from_secs(5));
    r.line.run_for(Duration::from_millis(500));
    // After the reset, the device's first record decides: the poses are exactly the records
    // it streamed since (its first record after waking answered the status request).
    let sent: Vec<[f64; 3]> = r
        .line
        .device
        .sent()
        .iter()
        .map(|s| s.sample.expected_position_m())
        .collect();
    let got: Vec<[f64; 3]> = r
        .poses
        .borrow()
        .iter()
        .map(|p| [p.pos.x, p.pos.y, p.pos.z])
        .collect();
    assert!(got.len() >= 25);
    let runs = crate::sim::rig::runs_in(&got, &sent, 0);
    assert_eq!(
        runs.first(),
        Some(&1),
        "the poses are the records after the status answer"
    );
    assert!(sent.len() - got.len() <= 2, "no record lost");
}
