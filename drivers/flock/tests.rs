//! The one-line Flock driver against the simulator on a virtual serial line, with the
//! driver's tracker and a client's remote on one in-process connection: reset, exact values
//! and timestamps, resynchronisation, the watchdog, reopening, failures, every configuration
//! variant.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config;
use super::record::Transmitter;
use super::reset::{self, AUTOCONFIG_LIMIT, BOOT_LIMIT};
use super::sim::{pose, FlockSim, SentRecord, SimConfig};
use super::{FlockProtocol, RETRY_PAUSE, WATCHDOG};
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::parse_one;
use crate::sim::VirtualLine;
use crate::{Connection, Now, SenderFilter, TimeVal, TrackerPose, TrackerRemote};

type Line = VirtualLine<Lifecycle<FlockProtocol>, FlockSim>;
type Shared<T> = Rc<RefCell<Vec<T>>>;

const START_WALL: TimeVal = TimeVal {
    sec: 1_700_000_000,
    usec: 0,
};

pub(super) fn start_now() -> Now {
    Now {
        mono: Instant::now(),
        wall: START_WALL,
    }
}

fn flock_cfg(text: &str) -> config::Flock {
    parse_one(text)
}

/// Collects the text messages `name` sends on `conn`.
pub(super) fn collect_texts(conn: &Connection, name: &str) -> Shared<(TextSeverity, String)> {
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
    line: Line,
    start: Now,
    cfg: config::Flock,
    poses: Shared<TrackerPose>,
    texts: Shared<(TextSeverity, String)>,
    _remote: TrackerRemote,
    _conn: Connection,
}

fn rig(cfg_text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg = flock_cfg(cfg_text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
    let texts = collect_texts(&conn, &cfg.name);
    let mut sim = SimConfig::for_flock(&cfg);
    sim.keep_log = true;
    tweak(&mut sim);
    let start = start_now();
    let line = VirtualLine::new(driver, FlockSim::new(sim), start, seed);
    Rig {
        line,
        start,
        cfg,
        poses,
        texts,
        _remote: remote,
        _conn: conn,
    }
}

impl Rig {
    /// Runs until the first pose; returns the time since the port opened.
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

    /// Runs until the driver streams, then forgets everything sent and seen so far.
    fn run_to_streaming(&mut self, max: Duration) {
        assert!(
            self.line.run_until(max, |l| l.driver.is_streaming()),
            "not streaming within {max:?}; texts: {:?}",
            self.texts.borrow()
        );
        self.line.device.flock_mut().clear_log();
        self.poses.borrow_mut().clear();
    }

    /// Waits for a moment the line is idle, then forgets everything sent and seen so far.
    fn forget_seen(&mut self) {
        run_to_idle_line(self);
        self.line.device.flock_mut().clear_log();
        self.poses.borrow_mut().clear();
    }

    fn texts_with(&self, needle: &str) -> usize {
        self.texts
            .borrow()
            .iter()
            .filter(|(_, t)| t.contains(needle))
            .count()
    }

    fn sent(&self) -> Vec<SentRecord> {
        self.line.device.flock().sent().to_vec()
    }

    fn transmitter(&self) -> Transmitter {
        Transmitter::from_ert(self.cfg.use_ert)
    }

    /// The time a record whose first byte left the device at `t` must carry.
    fn arrival_wall(&self, t: Instant) -> TimeVal {
        self.start
            .wall
            .plus(t + self.line.latency - self.start.mono)
    }

    /// Asserts `pose` is exactly what `rec` must become.
    fn assert_pose(&self, pose: &TrackerPose, rec: &SentRecord) {
        let sensor =
            i32::from(rec.address) - i32::from(self.transmitter().first_receiver_address());
        assert_eq!(pose.sensor as i32, sensor, "sensor of {rec:?}");
        let pos = rec.pose.expected_position_m(self.transmitter());
        assert_eq!(
            [pose.pos.x, pose.pos.y, pose.pos.z],
            pos,
            "position of {rec:?}"
        );
        let q = rec.pose.expected_quat_xyzw(self.cfg.invert_quaternion);
        let got = pose.quat.into_inner();
        assert_eq!([got.i, got.j, got.k, got.w], q, "quaternion of {rec:?}");
        // A slow read's records all carry its wake time: values only.
        if self.line.read_lag.is_zero() {
            assert_eq!(
                pose.time,
                self.arrival_wall(rec.first_byte_at),
                "time of {rec:?}"
            );
        }
    }

    /// Asserts the poses seen are exactly the records sent, in order, but for at most one
    /// cycle still on the line.
    fn assert_all_arrived(&self) {
        let sent = self.sent();
        let poses = self.poses.borrow();
        assert!(!poses.is_empty());
        assert!(poses.len() <= sent.len());
        assert!(
            sent.len() - poses.len() <= usize::from(self.line.device.flock().config().receivers),
            "{} sent, {} arrived",
            sent.len(),
            poses.len()
        );
        for (p, rec) in poses.iter().zip(&sent) {
            self.assert_pose(p, rec);
        }
    }
}

const FOUR_ERT: &str = "vrpn_Tracker_Flock Tracker0 4 /dev/ttyS0 115200 0\n";

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers or records at once: the reset
    // still completes, and every record from the first after it is reported, in order. (The
    // reset ends by asking for records: none can share a read with its last answer.)
    let mut r = rig(FOUR_ERT, |_| {}, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.run_to_streaming(Duration::from_secs(10));
    r.line.run_for(Duration::from_secs(2));
    assert!(r.poses.borrow().len() > 40, "{}", r.poses.borrow().len());
    r.assert_all_arrived();
}

#[test]
fn port_settings_and_identity() {
    let r = rig(FOUR_ERT, |_| {}, 1);
    assert_eq!(r.line.driver.name(), "Tracker0");
    assert_eq!(r.line.driver.protocol().port(), "/dev/ttyS0");
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(115_200))
    );
    assert_eq!(r.line.driver.protocol().tracker().num_sensors(), 4);
}

#[test]
fn reset_reaches_streaming_and_first_report() {
    let mut r = rig(FOUR_ERT, |_| {}, 1);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    // RTS 0.1 s, boot 0.5 s (probing), 0.3 s + 0.3 s around the auto-configuration, answers,
    // the next measurement cycle and one record: about 1.2 s (C++: about 19 s).
    assert!(
        startup > Duration::from_millis(1150) && startup < Duration::from_millis(1300),
        "start-up took {startup:?}"
    );
    // The bytes written, in order (probes repeat while the bird boots).
    let written: Vec<Vec<u8>> = r.line.written.iter().map(|(_, b)| b.clone()).collect();
    assert_eq!(written[0], b"B");
    let probes = written.iter().filter(|w| w.as_slice() == b"O\x00").count();
    assert!(probes >= 2, "{written:?}");
    let tail: Vec<&[u8]> = written[1 + probes..].iter().map(Vec::as_slice).collect();
    let mut modes = vec![b'P', 35, 1];
    for a in 2..=5u8 {
        modes.extend_from_slice(&[0xF0 + a, b']']);
    }
    for a in 2..=5u8 {
        modes.extend_from_slice(&[0xF0 + a, b'L', 0x0C, 0x00]);
    }
    assert_eq!(
        tail,
        vec![
            &[b'P', 50, 5][..],
            &[b'O', 36][..],
            &modes[..],
            &[b'O', 2, b'O', 6][..],
            &[b'@'][..],
        ]
    );
    // The device got what it needed: one RTS reset, one auto-configuration of five units.
    let f = r.line.device.flock();
    assert_eq!(
        (f.resets(), f.autoconfigs(), f.configured_units()),
        (1, 1, 5)
    );
    assert!(f.group_mode());
    for a in 2..=5 {
        assert!(f.pos_quat_format(a));
        assert_eq!(f.hemisphere(a), Some([0x0C, 0x00]));
    }
    drop(f);
    let (mhz, hz) = r.line.driver.protocol().measurement_rate().unwrap();
    assert_eq!(mhz, 25);
    assert!((hz - 100.0).abs() < 0.01, "{hz}");
    assert_eq!(r.texts_with("measurement rate 100.00 Hz"), 1);
    assert_eq!(r.texts_with("failed"), 0);
}

#[test]
fn device_ready_at_once_starts_in_under_a_second() {
    // No RTS (three-wire cable, pseudo-terminal): the bird answers the first probe.
    let mut r = rig(FOUR_ERT, |s| s.rts_wired = false, 2);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    assert!(
        startup > Duration::from_millis(800) && startup < Duration::from_millis(850),
        "start-up took {startup:?}"
    );
    let probes = r
        .line
        .written
        .iter()
        .filter(|(_, w)| w.as_slice() == b"O\x00")
        .count();
    assert_eq!(probes, 1);
}

#[test]
fn values_arrive_exactly_and_in_order() {
    let mut r = rig(FOUR_ERT, |_| {}, 3);
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_secs(2));
    // 100 Hz × 4 receivers × 2 s.
    assert!(r.poses.borrow().len() >= 795, "{}", r.poses.borrow().len());
    r.assert_all_arrived();
    // Every sensor, round robin, from consecutive measurement cycles.
    let sent = r.sent();
    for (i, rec) in sent.iter().enumerate() {
        assert_eq!(rec.address, 2 + (i % 4) as u8);
        assert_eq!(rec.cycle, sent[0].cycle + (i / 4) as u64);
        assert!(rec.pos_quat);
    }
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    assert_eq!(r.line.driver.stats().records, r.poses.borrow().len() as u64);
}

#[test]
fn timestamps_are_first_byte_arrivals_with_split_reads() {
    // At 9600 baud a 15-byte record takes 15.6 ms on the line, so its first and last bytes
    // arrive far apart; reads are cut at random points.
    for seed in [4, 5, 6] {
        let mut r = rig(
            "vrpn_Tracker_Flock Tracker0 2 /dev/ttyS0 9600 0\n",
            |_| {},
            seed,
        );
        r.line.split_reads = true;
        r.run_to_streaming(Duration::from_secs(5));
        r.line.run_for(Duration::from_secs(1));
        // Two records take 31 ms at 9600 baud: the Flock sends every fourth cycle.
        assert!(r.poses.borrow().len() >= 45, "{}", r.poses.borrow().len());
        r.assert_all_arrived();
        let sent = r.sent();
        let p = &r.poses.borrow()[1];
        // Not the time the record completed.
        assert!(p.time < r.arrival_wall(sent[1].first_byte_at + Duration::from_millis(10)));
    }
}

/// Runs until a whole measurement cycle has arrived and nothing more is on the line: the line
/// is idle until the next cycle.
fn run_to_idle_line(r: &mut Rig) {
    let poses = r.poses.clone();
    let n = poses.borrow().len();
    let latency = r.line.latency;
    assert!(r.line.run_until(Duration::from_secs(3), |l| {
        let before = l.now().mono - latency - Duration::from_micros(1);
        poses.borrow().len() > n
            && l.device.is_quiet_at(before)
            && !l.driver.protocol().framer.in_record()
    }));
}

#[test]
fn garbage_between_records_loses_nothing() {
    let mut r = rig(FOUR_ERT, |_| {}, 7);
    r.line.split_reads = true;
    r.run_to_streaming(Duration::from_secs(5));
    let garbage: [&[u8]; 4] = [
        // Bytes without the phasing bit.
        &[0x01, 0x02, 0x7F, 0x00, 0x55],
        // A phasing byte and part of a record, cut by the next real record.
        &[0x80, 0x10, 0x20, 0x30],
        // Whole records with addresses no receiver has (9; 1 is the controller).
        &[0x80, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 0x09],
        &[0x81, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 0x01],
    ];
    let mut skipped = 0;
    for g in garbage {
        run_to_idle_line(&mut r);
        r.line.inject(g);
        skipped += g.len() as u64;
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.stats().skipped_bytes, skipped);
    // Reported, at most once a second.
    assert_eq!(r.texts_with("skipped"), 1, "{:?}", r.texts.borrow());
    assert_eq!(r.texts_with("failed"), 0);
}

#[test]
fn garbage_inside_a_record_costs_only_that_record() {
    let mut r = rig(
        "vrpn_Tracker_Flock Tracker0 2 /dev/ttyS0 9600 0\n",
        |_| {},
        8,
    );
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_millis(200));
    // A phasing byte into the middle of a record in flight (15.6 ms long at 9600 baud).
    let hit = loop {
        r.line.run_for(Duration::from_millis(1));
        let now = r.line.now().mono;
        let sent = r.sent();
        if let Some(i) = sent.iter().position(|rec| {
            rec.first_byte_at + Duration::from_millis(3) <= now
                && now <= rec.first_byte_at + Duration::from_millis(12)
        }) {
            break i;
        }
    };
    r.line.inject(&[0x83]);
    r.line.run_for(Duration::from_millis(500));
    let mut sent = r.sent();
    sent.remove(hit);
    let poses = r.poses.borrow();
    assert!(poses.len() <= sent.len() && sent.len() - poses.len() <= 2);
    for (p, rec) in poses.iter().zip(&sent) {
        r.assert_pose(p, rec);
    }
    assert!(poses.len() > hit + 20);
}

#[test]
fn silent_device_is_reset_by_the_watchdog_and_resumes() {
    let mut r = rig(FOUR_ERT, |_| {}, 9);
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_millis(300));
    r.line.device.stall();
    let stalled_at = r.line.now().mono;
    // A record already on its way still arrives.
    r.line.run_for(Duration::from_millis(50));
    let before = r.poses.borrow().len();
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(10), |_| poses.borrow().len() > before));
    let resumed = r.line.now().mono - stalled_at;
    // The watchdog fires 2 s after the last record, then a fresh reset (≈ 1.2 s).
    assert!(
        resumed > WATCHDOG && resumed < WATCHDOG + Duration::from_millis(1400),
        "{resumed:?}"
    );
    assert_eq!(r.texts_with("Tracker failed to read... current_time="), 1);
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 1);
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.line.device.flock().resets(), 2);
    assert_eq!(r.line.driver.stats().failures_in_a_row, 0);
    // And it keeps streaming.
    r.forget_seen();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert!(r.poses.borrow().len() >= 395);
}

#[test]
fn closed_port_reopens_and_resumes() {
    let mut r = rig(FOUR_ERT, |_| {}, 10);
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_millis(300));
    r.line.close();
    assert!(!r.line.driver.is_streaming());
    assert_eq!(r.line.driver.next_deadline(), None);
    let n = r.poses.borrow().len();
    r.line
        .run_for(r.line.reopen_delay - Duration::from_millis(1));
    assert_eq!(r.poses.borrow().len(), n, "poses while closed");
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(5), |_| poses.borrow().len() > n));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.line.device.flock().resets(), 2);
    r.forget_seen();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.texts_with("failed"), 0);
}

#[test]
fn stream_left_running_is_stopped_before_the_reset() {
    // A three-wire cable (no RTS reset) and a Flock left streaming at 9600 baud: the 'B'
    // stops it, its last point record is discarded, and the reset proceeds.
    let mut r = rig(
        "vrpn_Tracker_Flock Tracker0 3 /dev/ttyS0 9600 0\n",
        |s| {
            s.rts_wired = false;
            s.streaming_at_start = true;
        },
        11,
    );
    r.line.split_reads = true;
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    assert!(startup < Duration::from_secs(1), "{startup:?}");
    assert_eq!(r.line.device.flock().resets(), 0);
    r.forget_seen();
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn slow_device_still_starts() {
    let mut r = rig(
        FOUR_ERT,
        |s| {
            s.boot_time = Duration::from_secs(3);
            s.autoconfig_time = Duration::from_secs(4);
        },
        12,
    );
    let startup = r.run_to_first_pose(Duration::from_secs(15));
    assert!(startup < Duration::from_secs(8), "{startup:?}");
    assert_eq!(r.texts_with("failed"), 0);
    assert_eq!(r.line.device.flock().autoconfigs(), 1);
}

#[test]
fn dead_device_fails_pauses_and_recovers_when_powered() {
    let mut r = rig(FOUR_ERT, |_| {}, 13);
    let t0 = r.line.now();
    r.line.device.flock_mut().set_powered(false, t0);
    // Each attempt: 0.1 s RTS, then probes for the boot limit.
    r.line
        .run_for((Duration::from_millis(100) + BOOT_LIMIT) * 4 + Duration::from_millis(500));
    assert_eq!(r.texts_with("the master bird does not answer"), 4);
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 4);
    assert_eq!(r.texts_with("Next attempt in 15 seconds"), 1);
    assert_eq!(r.line.opens, 4);
    // Paused: nothing written for 15 s.
    let writes = r.line.written.len();
    r.line.run_for(RETRY_PAUSE - Duration::from_secs(1));
    assert_eq!(r.line.written.len(), writes);
    let now = r.line.now();
    r.line.device.flock_mut().set_powered(true, now);
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(5), |_| !poses.borrow().is_empty()));
    assert_eq!(r.line.opens, 5);
    assert_eq!(r.line.driver.stats().failures_in_a_row, 0);
}

#[test]
fn missing_receiver_fails_the_status_check() {
    // Four receivers configured, three attached: address 5 never answers on the bus.
    let mut r = rig(FOUR_ERT, |s| s.receivers = 3, 14);
    r.line
        .run_for(Duration::from_millis(1500) + AUTOCONFIG_LIMIT);
    assert_eq!(
        r.texts_with("address 5 not accessible"),
        1,
        "{:?}",
        r.texts.borrow()
    );
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 1);
    assert!(r.poses.borrow().is_empty());
    assert_eq!(r.line.opens, 2);
}

#[test]
fn without_ert_receivers_start_at_address_one_with_short_range() {
    let mut r = rig(
        "vrpn_Tracker_Flock Tracker0 2 COM1 38400 1 N -x\n",
        |_| {},
        15,
    );
    assert!(!r.cfg.use_ert && r.cfg.invert_quaternion);
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    let f = r.line.device.flock();
    assert_eq!(f.configured_units(), 2);
    assert_eq!(f.hemisphere(1), Some([0x00, 0x01]));
    assert_eq!(f.hemisphere(2), Some([0x00, 0x01]));
    drop(f);
    let written: Vec<&[u8]> = r.line.written.iter().map(|(_, w)| w.as_slice()).collect();
    assert!(written.contains(&&[b'P', 50, 2][..]));
    assert!(written
        .contains(&&[b'P', 35, 1, 0xF1, b']', 0xF2, b']', 0xF1, b'L', 0, 1, 0xF2, b'L', 0, 1][..]));
    // Inverted quaternions: the conjugate of what the bird sends.
    let p = r.poses.borrow()[0];
    let rec = r.sent()[0];
    let q = rec.pose.expected_quat_xyzw(false);
    let got = p.quat.into_inner();
    assert!((got.i + q[0]).abs() < 1e-3 && (got.w - q[3]).abs() < 1e-3);
}

#[test]
fn every_hemisphere_reaches_every_receiver() {
    let cases = [
        ("+x", [0x00, 0x00]),
        ("-x", [0x00, 0x01]),
        ("+Y", [0x06, 0x00]),
        ("-y", [0x06, 0x01]),
        ("+z", [0x0C, 0x00]),
        ("-Z", [0x0C, 0x01]),
    ];
    for (i, (h, bytes)) in cases.into_iter().enumerate() {
        let text = format!("vrpn_Tracker_Flock T 3 /dev/ttyS0 19200 0 y {h}\n");
        let mut r = rig(&text, |_| {}, 20 + i as u64);
        r.run_to_streaming(Duration::from_secs(5));
        r.line.run_for(Duration::from_millis(200));
        r.assert_all_arrived();
        let f = r.line.device.flock();
        for a in 2..=4 {
            assert_eq!(f.hemisphere(a), Some(bytes), "{h}");
        }
    }
}

#[test]
fn one_and_thirteen_receivers_at_several_speeds() {
    for (text, receivers) in [
        ("vrpn_Tracker_Flock One 1 /dev/ttyS0 2400 0\n", 1u8),
        ("vrpn_Tracker_Flock Many 13 /dev/ttyS0 115200 0\n", 13),
        ("vrpn_Tracker_Flock Mid 6 /dev/ttyS0 57600 1 yes +z\n", 6),
    ] {
        let mut r = rig(text, |_| {}, 30);
        r.line.split_reads = true;
        r.run_to_streaming(Duration::from_secs(5));
        r.line.run_for(Duration::from_secs(1));
        r.assert_all_arrived();
        let sensors: std::collections::BTreeSet<i32> =
            r.poses.borrow().iter().map(|p| p.sensor as i32).collect();
        assert_eq!(sensors.len(), usize::from(receivers), "{text}");
        assert_eq!(
            r.line.device.flock().configured_units(),
            receivers + 1,
            "{text}"
        );
    }
}

#[test]
fn sim_poses_cover_the_range() {
    // The simulator's numbers reach both extremes of the 14-bit range.
    let values: Vec<i16> = (0..20_000).map(|k| pose(2, k).position[0]).collect();
    assert_eq!(*values.iter().min().unwrap(), -8192);
    assert_eq!(*values.iter().max().unwrap(), 8191);
    let q = pose(3, 7).quat_wxyz;
    let len: f64 = q.iter().map(|&v| (f64::from(v) / 8191.0).powi(2)).sum();
    assert!((len - 1.0).abs() < 1e-3);
    assert_eq!(reset::measurement_rate(0, 100), None);
}

#[test]
fn records_cut_anywhere_carry_the_time_of_their_first_read() {
    let mut r = rig(FOUR_ERT, |s| s.rts_wired = false, 40);
    r.run_to_streaming(Duration::from_secs(5));
    // From here the test feeds the driver itself: silence the simulator.
    r.line.device.stall();
    r.line.run_for(Duration::from_millis(30));
    r.poses.borrow_mut().clear();
    let mut bytes = Vec::new();
    for (address, cycle) in [(2u8, 1u64), (3, 1), (4, 1)] {
        pose(address, cycle).encode_pos_quat(&mut bytes);
        bytes.push(address);
    }
    // Reads: [garbage, 3 bytes of A] [rest of A, 7 bytes of B] [rest of B, all of C].
    let t0 = r.line.now();
    let reads: [(&[u8], Now); 3] = [
        (&[&[0x11u8, 0x22][..], &bytes[..3]].concat(), t0),
        (&bytes[3..22], t0.plus(Duration::from_millis(3))),
        (&bytes[22..], t0.plus(Duration::from_millis(5))),
    ];
    let mut ops = crate::serial::PortOps::new();
    for (chunk, at) in reads {
        r.line.driver.received(chunk, at, &mut ops);
    }
    assert!(ops.is_empty());
    let poses = r.poses.borrow();
    let times: Vec<(i32, TimeVal)> = poses.iter().map(|p| (p.sensor as i32, p.time)).collect();
    assert_eq!(
        times,
        vec![
            (0, t0.wall),
            (1, t0.plus(Duration::from_millis(3)).wall),
            (2, t0.plus(Duration::from_millis(5)).wall),
        ]
    );
    let expected = pose(3, 1).expected_position_m(Transmitter::ExtendedRange);
    assert_eq!([poses[1].pos.x, poses[1].pos.y, poses[1].pos.z], expected);
}

#[test]
fn line_gone_quiet_fails_resets_until_it_returns() {
    // Everything the device sends is lost for 4 s (a loose connector): the watchdog fires,
    // the resets find no answer, and once the line works again the Flock streams.
    let mut r = rig(FOUR_ERT, |_| {}, 41);
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_millis(100));
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(4));
    assert_eq!(r.texts_with("Tracker failed to read"), 1);
    assert!(!r.line.driver.is_streaming());
    r.line.silent = false;
    let poses = r.poses.clone();
    let n = poses.borrow().len();
    assert!(r
        .line
        .run_until(Duration::from_secs(10), |_| poses.borrow().len() > n));
    // The reset that began when the watchdog fired was still probing (for up to 5 s) when
    // the line came back, and went on from the first answer.
    assert_eq!(r.texts_with("the master bird does not answer"), 0);
    assert_eq!(r.line.opens, 2);
    r.forget_seen();
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
}

#[test]
fn a_reset_never_invents_data() {
    let mut r = rig(FOUR_ERT, |_| {}, 42);
    r.run_to_streaming(Duration::from_secs(5));
    r.line.run_for(Duration::from_millis(300));
    r.line.device.stall();
    // A record already on its way still arrives; then nothing is reported until the
    // device's first record after the reset, and from that one on exactly its records.
    r.line.run_for(Duration::from_millis(50));
    r.line.device.flock_mut().clear_log();
    r.poses.borrow_mut().clear();
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(10), |_| !poses.borrow().is_empty()));
    assert_eq!(r.line.opens, 2, "reopened and reset");
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
}
