//! The driver against the simulator on a virtual serial line, with the driver's servers and
//! the remotes of a client on one in-process connection: reset, streaming, exact values and
//! timestamps, resynchronisation, the watchdog, reopening, and every configuration variant.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::{self, WandClip};
use super::record::{is900_offset, joystick_raw, METRES_PER_INCH};
use super::reset::{BREAK_GAP, QUIET};
use super::sim::{self, FastrakSim, SentRecord, SimConfig};
use super::stations::clip;
use super::FastrakProtocol;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::{Lifecycle, Supervision};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::parse_one;
use crate::sim::VirtualLine;
use crate::{
    AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal, TrackerPose, TrackerRemote,
};

type Line = VirtualLine<Lifecycle<FastrakProtocol>, FastrakSim>;

/// The watchdog every tracker has.
const WATCHDOG: Duration = match Supervision::TRACKER.watchdog {
    Some(d) => d,
    None => Duration::ZERO,
};
type Shared<T> = Rc<RefCell<Vec<T>>>;

/// What a client saw, in arrival order across devices.
#[derive(Clone, Debug, PartialEq)]
enum Seen {
    Pose(TrackerPose),
    Button(&'static str, i32, i32, TimeVal),
    Analog(&'static str, [f64; 2], TimeVal),
}

struct Rig {
    line: Line,
    conn: Connection,
    start: Now,
    seen: Shared<Seen>,
    texts: Shared<(TextSeverity, String)>,
    _remotes: (TrackerRemote, Vec<ButtonRemote>, Vec<AnalogRemote>),
}

fn fastrak_cfg(text: &str) -> config::Fastrak {
    parse_one(text)
}

const START_WALL: TimeVal = TimeVal {
    sec: 1_700_000_000,
    usec: 0,
};

/// A rig for the driver `make` builds, with remotes for the station devices `devices`
/// (names leaked to `'static` for the event log; tests only).
fn rig_with(
    make: impl FnOnce(&Connection) -> Lifecycle<FastrakProtocol>,
    devices: &[&str],
    sim: SimConfig,
    seed: u64,
) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = make(&conn);
    let name = driver.name().to_owned();
    let seen: Shared<Seen> = Rc::default();
    let tracker = TrackerRemote::on_connection(&name, &conn).unwrap();
    let s = seen.clone();
    tracker.on_pose(move |p| s.borrow_mut().push(Seen::Pose(*p)));
    let mut buttons = Vec::new();
    let mut analogs = Vec::new();
    for dev in devices {
        let dev: &'static str = Box::leak(dev.to_string().into_boxed_str());
        let b = ButtonRemote::on_connection(dev, &conn).unwrap();
        let s = seen.clone();
        b.on_change(move |c| {
            s.borrow_mut()
                .push(Seen::Button(dev, c.button as i32, c.state.raw(), c.time))
        });
        buttons.push(b);
        let a = AnalogRemote::on_connection(dev, &conn).unwrap();
        let s = seen.clone();
        a.on_report(move |r| {
            let ch = r.channels();
            s.borrow_mut()
                .push(Seen::Analog(dev, [ch[0], ch[1]], r.time))
        });
        analogs.push(a);
    }
    let texts: Shared<(TextSeverity, String)> = Rc::default();
    let sender = conn.register_sender(&name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((sev, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push((sev, text.to_owned()));
        }
    });
    let start = Now {
        mono: Instant::now(),
        wall: START_WALL,
    };
    let line = VirtualLine::new(driver, FastrakSim::new(sim), start, seed);
    Rig {
        line,
        conn,
        start,
        seen,
        texts,
        _remotes: (tracker, buttons, analogs),
    }
}

fn rig(cfg_text: &str, devices: &[&str], sim: SimConfig, seed: u64) -> Rig {
    let cfg = fastrak_cfg(cfg_text);
    rig_with(|conn| cfg.lifecycle(conn).unwrap(), devices, sim, seed)
}

impl Rig {
    fn poses(&self) -> Vec<TrackerPose> {
        self.seen
            .borrow()
            .iter()
            .filter_map(|s| match s {
                Seen::Pose(p) => Some(*p),
                _ => None,
            })
            .collect()
    }

    fn pose_count(&self) -> usize {
        self.seen
            .borrow()
            .iter()
            .filter(|s| matches!(s, Seen::Pose(_)))
            .count()
    }

    fn has_text(&self, severity: TextSeverity, part: &str) -> bool {
        self.texts
            .borrow()
            .iter()
            .any(|(s, t)| *s == severity && t.contains(part))
    }

    /// Host wall time of virtual instant `t`.
    fn wall_at(&self, t: Instant) -> TimeVal {
        self.start.wall.plus(t - self.start.mono)
    }

    /// When the record's first byte reached the host.
    fn arrival(&self, r: &SentRecord) -> TimeVal {
        self.wall_at(r.first_byte_at + self.line.latency)
    }

    /// Runs until the first pose; returns the virtual time from the port opening.
    fn start_up(&mut self) -> Duration {
        let t0 = self.line.now().mono;
        let seen = self.seen.clone();
        assert!(self.line.run_until(Duration::from_secs(60), |_| seen
            .borrow()
            .iter()
            .any(|s| matches!(s, Seen::Pose(_)))));
        self.line.now().mono - t0
    }

    fn run_until_poses(&mut self, n: usize, max: Duration) -> bool {
        let seen = self.seen.clone();
        self.line.run_until(max, |_| {
            seen.borrow()
                .iter()
                .filter(|s| matches!(s, Seen::Pose(_)))
                .count()
                >= n
        })
    }

    fn binary_log(&self) -> Vec<SentRecord> {
        self.line
            .device
            .log
            .iter()
            .filter(|r| r.binary)
            .copied()
            .collect()
    }

    /// The bytes the driver wrote, one entry per write.
    fn writes(&self) -> Vec<Vec<u8>> {
        self.line.written.iter().map(|(_, w)| w.clone()).collect()
    }
}

fn xyzw(p: &TrackerPose) -> [f64; 4] {
    [p.quat.i, p.quat.j, p.quat.k, p.quat.w]
}

/// The pose a client must receive for `r`, stamped `time`.
fn expected_pose(r: &SentRecord, time: TimeVal) -> (i32, [f64; 3], [f64; 4], TimeVal) {
    let (pos, q) = sim::pose(r.station, r.seq);
    (
        i32::from(r.station) - 1,
        pos.map(|v| f64::from(v) * METRES_PER_INCH),
        [q[1], q[2], q[3], q[0]].map(f64::from),
        time,
    )
}

fn actual(p: &TrackerPose) -> (i32, [f64; 3], [f64; 4], TimeVal) {
    (
        p.sensor as i32,
        [p.pos.x, p.pos.y, p.pos.z],
        xyzw(p),
        p.time,
    )
}

/// Finds each pose, in order, among the records of `log`, each stamped with its first
/// byte's arrival (panics on a pose never sent). Returns the records skipped and the index
/// after the last match.
fn walk(rig: &Rig, poses: &[TrackerPose], log: &[SentRecord]) -> (usize, usize) {
    let (mut lost, mut next) = (0, 0);
    for p in poses {
        let at = log[next..]
            .iter()
            .position(|r| expected_pose(r, rig.arrival(r)) == actual(p))
            .unwrap_or_else(|| panic!("pose {p:?} was never sent"));
        lost += at;
        next += at + 1;
    }
    (lost, next)
}

/// Every pose equals the record sent at its position in the log, stamped with its first
/// byte's arrival; at most the last two records (still on the line) are missing.
fn assert_exact_stream(rig: &Rig) -> usize {
    let poses = rig.poses();
    let log = rig.binary_log();
    assert!(
        poses.len() <= log.len() && poses.len() + 2 >= log.len(),
        "{} poses for {} records",
        poses.len(),
        log.len()
    );
    // A slow read's records all carry its wake time: values only.
    let lag = !rig.line.read_lag.is_zero();
    for (i, (p, r)) in poses.iter().zip(&log).enumerate() {
        let (mut got, mut want) = (actual(p), expected_pose(r, rig.arrival(r)));
        if lag {
            (got.3, want.3) = (TimeVal::ZERO, TimeVal::ZERO);
        }
        assert_eq!(got, want, "record {i}");
    }
    poses.len()
}

const PLAIN: &str = "vrpn_Tracker_Fastrak Fastrak0 /dev/ttyS0 19200\n";

#[test]
fn serves_the_port_and_names_of_its_entry() {
    let cfg = fastrak_cfg(PLAIN);
    let conn = Connection::new_loopback();
    let d = cfg.lifecycle(&conn).unwrap();
    assert_eq!(d.name(), "Fastrak0");
    assert_eq!(d.protocol().port(), "/dev/ttyS0");
    assert_eq!(d.port_kind(), PortKind::Serial(PortSettings::n81(19200)));
    assert_eq!(d.protocol().tracker().num_sensors(), 4);
    assert!(
        d.next_deadline().is_none(),
        "nothing happens before the port opens"
    );
}

#[test]
fn reset_reaches_streaming_in_half_a_second() {
    let mut rig = rig(PLAIN, &[], SimConfig::new(19200), 1);
    let startup = rig.start_up();
    // Quiet wait, status, six commands 50 ms apart, barrier status, first cycle at 19200 baud.
    assert!(
        startup > Duration::from_millis(400) && startup < Duration::from_millis(600),
        "start-up took {startup:?} (C++: at least 7.2 s)"
    );
    assert!(rig.line.driver.is_streaming());
    assert!(rig.line.device.is_streaming());
    let writes = rig.writes();
    let expected: Vec<&[u8]> = vec![
        b"c",
        b"S",
        b"O1,2,11,0\r",
        b"O2,2,11,0\r",
        b"O3,2,11,0\r",
        b"O4,2,11,0\r",
        b"x0.2,0.2,0.8,0.8\r",
        b"v0.2,0.2,0.8,0.8\r",
        b"S",
        b"f",
        b"C",
    ];
    assert_eq!(writes, expected);
    // The configuration commands are 50 ms apart, as C++ sends them.
    let times: Vec<Instant> = rig.line.written.iter().map(|(t, _)| *t).collect();
    assert_eq!(times[3] - times[2], Duration::from_millis(50));
    assert_eq!(times[1] - times[0], QUIET);
    for (sev, text) in [
        (TextSeverity::Warning, "Resetting the tracker (attempt 1)"),
        (
            TextSeverity::Warning,
            "Fastrak/Isense gives status (this is good)",
        ),
        (TextSeverity::Warning, "Reset Completed (this is good)"),
    ] {
        assert!(rig.has_text(sev, text), "missing text {text:?}");
    }
    assert_eq!(rig.line.opens, 1);
    assert_eq!(rig.line.driver.protocol().reset_attempts(), 0);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers or records at once: the reset
    // still completes, and every record is reported from the first (the reset ends by asking
    // for records: none can share a read with its last answer).
    let mut sim = SimConfig::new(115_200);
    sim.stations = 4;
    let mut rig = rig(
        "vrpn_Tracker_Fastrak Fastrak0 /dev/ttyUSB0 115200\n",
        &[],
        sim,
        21,
    );
    rig.line.read_lag = Duration::from_millis(12);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(2));
    let n = assert_exact_stream(&rig);
    assert!(n > 2 * 60 * 4 - 8, "{n} poses");
}

#[test]
fn streamed_values_arrive_exactly_and_in_order() {
    let mut sim = SimConfig::new(115_200);
    sim.stations = 4;
    let mut rig = rig(
        "vrpn_Tracker_Fastrak Fastrak0 /dev/ttyUSB0 115200\n",
        &[],
        sim,
        2,
    );
    rig.start_up();
    rig.line.run_for(Duration::from_secs(3));
    let n = assert_exact_stream(&rig);
    // 60 cycles a second of four stations.
    assert!(n > 3 * 60 * 4 - 8, "{n} poses");
    let sensors: Vec<i32> = rig
        .poses()
        .iter()
        .take(8)
        .map(|p| p.sensor as i32)
        .collect();
    assert_eq!(sensors, [0, 1, 2, 3, 0, 1, 2, 3]);
    assert_eq!(rig.line.driver.protocol().skipped_bytes(), 0);
    assert_eq!(rig.line.driver.stats().records as usize, n);
}

#[test]
fn timestamps_are_first_byte_arrivals_with_split_reads() {
    for (baud, chunk, seed) in [(9600, 16, 3), (19200, 4, 4), (115_200, 1, 5)] {
        let mut sim = SimConfig::new(baud);
        sim.chunk = chunk;
        sim.stations = 2;
        let mut rig = rig(
            &format!("vrpn_Tracker_Fastrak T /dev/ttyS0 {baud}\n"),
            &[],
            sim,
            seed,
        );
        rig.line.split_reads = true;
        rig.start_up();
        rig.line.run_for(Duration::from_secs(2));
        let n = assert_exact_stream(&rig);
        assert!(n > 40, "{n} poses at {baud} baud");
    }
}

#[test]
fn garbage_between_records_loses_nothing() {
    let mut rig = rig(
        "vrpn_Tracker_Fastrak F /dev/ttyS0 115200\n",
        &[],
        SimConfig::new(115_200),
        6,
    );
    rig.start_up();
    let junk: [&[u8]; 6] = [
        b"0",
        b"01 ",
        b"\x00\xff0",
        b"05",
        b"01\x01",
        b"01 \x11\x12\x13\x14\x15\x16\x17\x18\x19\x1a",
    ];
    for (i, g) in junk.iter().cycle().take(24).enumerate() {
        // Wait until a whole cycle (four stations) has arrived: the line is idle.
        let target = rig.pose_count().div_ceil(4) * 4 + 4;
        assert!(
            rig.run_until_poses(target, Duration::from_secs(1)),
            "round {i}"
        );
        rig.line.inject(g);
    }
    rig.line.run_for(Duration::from_millis(500));
    let n = assert_exact_stream(&rig);
    assert!(n >= 24 * 4);
    assert!(rig.line.driver.protocol().skipped_bytes() >= 24);
    assert!(rig.has_text(TextSeverity::Normal, "While syncing (looking for '0', got"));
    assert!(rig.has_text(TextSeverity::Normal, "Bad sensor # (4) in record"));
    assert!(rig.has_text(TextSeverity::Normal, "Bad 3rd char in record"));
    assert!(rig.has_text(TextSeverity::Normal, "No space character at end of report"));
    assert!(
        rig.line.driver.is_streaming(),
        "garbage alone does not reset"
    );
    assert_eq!(rig.line.opens, 1);
}

#[test]
fn garbage_inside_records_costs_at_most_the_record_it_hits() {
    let mut sim = SimConfig::new(38_400);
    sim.stations = 3;
    let mut rig = rig("vrpn_Tracker_Fastrak F /dev/ttyS0 38400\n", &[], sim, 7);
    rig.line.split_reads = true;
    rig.start_up();
    let mut rng = crate::sim::Rng::new(99);
    let injections = 40;
    for _ in 0..injections {
        rig.line
            .run_for(Duration::from_micros(20_000 + rng.below(40_000)));
        let len = 1 + rng.below(6) as usize;
        let g: Vec<u8> = (0..len)
            .map(|_| match rng.below(3) {
                0 => b'0',
                1 => b'1' + rng.below(4) as u8,
                _ => rng.below(256) as u8,
            })
            .collect();
        rig.line.inject(&g);
    }
    rig.line.run_for(Duration::from_millis(300));
    // Every pose is a record the tracker sent, unaltered and stamped right.
    let (lost, next) = walk(&rig, &rig.poses(), &rig.binary_log());
    let log = rig.binary_log();
    assert!(
        lost <= injections,
        "{lost} records lost to {injections} injections"
    );
    assert!(log.len() - next <= 2);
    assert!(rig.line.driver.is_streaming());
}

#[test]
fn silent_tracker_trips_the_watchdog_and_resumes_after_a_new_reset() {
    let mut rig = rig(PLAIN, &[], SimConfig::new(19200), 8);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(1));
    let before = rig.pose_count();
    rig.line.device.set_silent(true);
    let silent_at = rig.line.now().mono;
    rig.line.run_for(WATCHDOG + Duration::from_millis(200));
    assert!(rig.has_text(
        TextSeverity::Error,
        "Tracker failed to read... current_time="
    ));
    assert!(rig.has_text(
        TextSeverity::Error,
        "Tracker failed, trying to reset (Try power cycle if more than 4 attempts made)"
    ));
    assert_eq!(rig.line.opens, 2, "the port was reopened");
    assert!(!rig.line.driver.is_streaming());
    // Still silent: attempts escalate (CR, then Ctrl-Y) and keep failing.
    rig.line.run_for(Duration::from_secs(4));
    assert!(rig.has_text(TextSeverity::Error, "Bad status report from Fastrak"));
    assert!(rig.has_text(TextSeverity::Warning, "Resetting the tracker (attempt 3)"));
    assert!(rig.writes().iter().any(|w| w == b"\x19"), "Ctrl-Y was sent");
    assert_eq!(rig.pose_count(), before);
    rig.line.device.set_silent(false);
    let woke = rig.line.now().mono;
    assert!(rig.run_until_poses(before + 8, Duration::from_secs(10)));
    let back = rig.line.now().mono - woke;
    assert!(
        back < Duration::from_secs(3),
        "resumed {back:?} after waking"
    );
    assert!(rig.line.driver.is_streaming());
    assert_eq!(rig.line.driver.protocol().reset_attempts(), 0);
    // The watchdog fired 2 s after the first byte of the last good record, not earlier.
    let last_good = rig.poses()[before - 1].time;
    let reopen = rig
        .line
        .written
        .iter()
        .find(|(t, w)| *t > silent_at && w == b"c")
        .unwrap()
        .0;
    assert_eq!(rig.wall_at(reopen), last_good.plus(WATCHDOG));
    let log = rig.binary_log();
    // Poses after the silence are exact again; the only records lost are those the tracker
    // sent on waking, while the reset was under way.
    let after: Vec<SentRecord> = log
        .into_iter()
        .filter(|r| r.first_byte_at >= woke)
        .collect();
    let poses = rig.poses();
    let (lost, next) = walk(&rig, &poses[before..], &after);
    let during_reset = after
        .iter()
        .filter(|r| r.first_byte_at < rig.line.written.last().unwrap().0)
        .count();
    assert_eq!(lost, during_reset);
    assert!(after.len() - next <= 2);
}

#[test]
fn closed_port_is_reopened_and_streaming_resumes() {
    let mut rig = rig(PLAIN, &[], SimConfig::new(19200), 9);
    rig.start_up();
    rig.line.run_for(Duration::from_millis(700));
    let before = rig.pose_count();
    rig.line.close();
    assert_eq!(rig.line.driver.next_deadline(), None);
    rig.line.run_for(Duration::from_millis(400));
    assert_eq!(rig.pose_count(), before, "nothing while closed");
    assert!(rig.run_until_poses(before + 4, Duration::from_secs(3)));
    assert_eq!(rig.line.opens, 2);
    assert!(rig.line.driver.is_streaming());
    let resets = rig
        .texts
        .borrow()
        .iter()
        .filter(|(_, t)| t == "Reset Completed (this is good)")
        .count();
    assert_eq!(resets, 2);
}

#[test]
fn reset_escalates_through_ctrl_y_until_the_tracker_answers() {
    let mut sim = SimConfig::new(9600);
    // The first three status requests go unanswered: attempts 1 and 2 fail, attempt 3 sends
    // Ctrl-Y and keeps asking while the tracker reboots.
    sim.ignore_status = 3;
    let mut rig = rig("vrpn_Tracker_Fastrak F /dev/ttyS0 9600\n", &[], sim, 10);
    let startup = rig.start_up();
    let writes = rig.writes();
    let head: Vec<&[u8]> = writes.iter().take(7).map(Vec::as_slice).collect();
    assert_eq!(
        head,
        [&b"c"[..], b"S", b"\r", b"c", b"S", b"\r", b"\x19"],
        "attempt 1: c S; attempt 2: CR c S; attempt 3: CR ^Y …"
    );
    assert_eq!(rig.line.device.reboots(), 1);
    assert!(rig.has_text(TextSeverity::Warning, "Resetting the tracker (attempt 3)"));
    assert!(!rig.has_text(TextSeverity::Warning, "Resetting the tracker (attempt 4)"));
    assert_eq!(rig.line.driver.protocol().reset_attempts(), 0);
    // Attempts 1 and 2 time out (1.157 s and 1.257 s); attempt 3's probes go unanswered
    // during the 1.5 s reboot and once after it, then succeed: no fixed 20 s wait.
    assert!(
        startup < Duration::from_secs(7),
        "start-up took {startup:?}"
    );
    assert!(rig.line.device.status_requests() >= 4);
    assert!(startup > 2 * BREAK_GAP + Duration::from_millis(1500));
}

#[test]
fn extra_reset_commands_run_in_order_with_their_pauses() {
    let text = "vrpn_Tracker_Fastrak Isense600 /dev/ttyS0 19200 \\\n\
                MCc\\\n\
                *1\\\n\
                MCM1,1,0.0900,0.0000,-0.2210,0.00,0.00,-1.00,89\\\n\
                MCe\\\n\
                *2\n";
    let mut sim = SimConfig::new(19200);
    // The tracker answers the extra commands: the barrier must skip those lines.
    sim.echo_commands = true;
    let mut rig = rig(text, &[], sim, 11);
    let startup = rig.start_up();
    let commands = rig.line.device.commands.clone();
    assert_eq!(
        commands,
        [
            "O1,2,11,0",
            "O2,2,11,0",
            "O3,2,11,0",
            "O4,2,11,0",
            "x0.2,0.2,0.8,0.8",
            "v0.2,0.2,0.8,0.8",
            "MCc",
            "MCM1,1,0.0900,0.0000,-0.2210,0.00,0.00,-1.00,89",
            "MCe",
        ]
    );
    let at = |cmd: &[u8]| {
        rig.line
            .written
            .iter()
            .find(|(_, w)| w == cmd)
            .unwrap_or_else(|| panic!("{:?} not written", String::from_utf8_lossy(cmd)))
            .0
    };
    assert_eq!(
        at(b"MCM1,1,0.0900,0.0000,-0.2210,0.00,0.00,-1.00,89\r") - at(b"MCc\r"),
        Duration::from_secs(1)
    );
    let barrier = rig
        .line
        .written
        .iter()
        .filter(|(_, w)| w == b"S")
        .nth(1)
        .unwrap()
        .0;
    assert_eq!(barrier - at(b"MCe\r"), Duration::from_secs(2));
    assert!(startup > Duration::from_secs(3) && startup < Duration::from_millis(3600));
    rig.line.run_for(Duration::from_secs(1));
    assert_exact_stream(&rig);
}

const IS900: &str = "vrpn_Tracker_Fastrak Isense900 /dev/ttyS1 115200 IS900time /\n\
                     Wand Wand0 0 -1.0 0.0 0.0 1.0 -1.0 0.0 0.0 1.0 /\n\
                     Stylus Stylus0 2\n";

mod stations;

#[test]
fn a_reset_never_invents_data() {
    let mut rig = rig(IS900, &["Wand0", "Stylus0"], SimConfig::new(115_200), 23);
    rig.start_up();
    rig.line.run_for(Duration::from_millis(500));
    let (poses, events) = (rig.pose_count(), rig.seen.borrow().len());
    rig.line.device.set_silent(true);
    rig.line.run_for(WATCHDOG + Duration::from_secs(3));
    assert!(rig.line.opens >= 2, "the watchdog reopened the port");
    // Nothing reported while the tracker is silent: no pose, no button, no channel.
    assert_eq!(rig.seen.borrow().len(), events);
    rig.line.device.set_silent(false);
    let woke = rig.line.now().mono;
    assert!(rig.run_until_poses(poses + 40, Duration::from_secs(10)));
    // Every pose after the reset is a record the tracker sent after waking, in order (the
    // times are the tracker's own clock: compared apart).
    let after: Vec<SentRecord> = rig
        .binary_log()
        .into_iter()
        .filter(|r| r.first_byte_at >= woke)
        .collect();
    let zero = rig.line.driver.protocol().clock_zero().unwrap();
    let mut next = 0;
    for p in &rig.poses()[poses..] {
        let at = after[next..]
            .iter()
            .position(|r| {
                let t =
                    TimeVal::from_micros(zero.as_micros() + is900_offset(r.device_ms).as_micros());
                expected_pose(r, t) == actual(p)
            })
            .unwrap_or_else(|| panic!("pose {p:?} was never sent"));
        next += at + 1;
    }
    // And the buttons and channels after it are the records' (no release at the reset).
    let later: Vec<Seen> = rig.seen.borrow()[events..].to_vec();
    assert!(later.iter().any(|s| matches!(s, Seen::Pose(_))));
    for s in &later {
        if let Seen::Button(_, _, _, t) | Seen::Analog(_, _, t) = s {
            assert!(rig.poses()[poses..].iter().any(|p| p.time == *t), "{s:?}");
        }
    }
}

#[test]
fn the_is900_keyword_is_explained_and_odd_continuations_never_panic() {
    // C++ has no vrpn_Tracker_IS900: the unknown-keyword error says what to write instead.
    let entries =
        crate::server::config::parse_str("vrpn_Tracker_IS900 T0 /dev/ttyUSB0 115200\n", "x")
            .unwrap();
    let error = entries[0]
        .unknown_error()
        .expect("an unknown keyword")
        .to_string();
    assert!(error.contains("IS900time"), "{error}");
    for text in [
        "vrpn_Tracker_Fastrak\\",
        "vrpn_Tracker_Fastrak a b 9600 \\",
        "vrpn_Tracker_Fastrak a b 9600 /\n/\n",
    ] {
        let _ = crate::server::config::parse_str_lenient(text, "x");
    }
}
