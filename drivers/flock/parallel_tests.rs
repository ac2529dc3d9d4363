//! The parallel Flock's drivers (a master line and a line per receiver) against the
//! simulator's lines on one virtual clock: start-up, exact values and timestamps, garbage,
//! a silent receiver, closed lines, failures, sizes.

use std::time::Duration;

use super::config;
use super::parallel::{FlockParallelPort, Role};
use super::record::Transmitter;
use super::sim::{FlockSim, SentRecord, SimConfig};
use super::tests::{collect_texts, start_now};
use super::{RETRY_PAUSE, WATCHDOG};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::parse_one;
use crate::sim::VirtualLines;
use crate::{Connection, Now, SenderId, TimeVal, TrackerPose, TrackerRemote};

type Lines = VirtualLines<FlockParallelPort, FlockSim>;
type Shared<T> = std::rc::Rc<std::cell::RefCell<Vec<T>>>;

struct Rig {
    lines: Lines,
    start: Now,
    receivers: usize,
    poses: Shared<TrackerPose>,
    texts: Shared<(TextSeverity, String)>,
    conn: Connection,
    _remote: TrackerRemote,
}

fn parallel_cfg(text: &str) -> config::FlockParallel {
    parse_one(text)
}

fn rig(cfg_text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg = parallel_cfg(cfg_text);
    let conn = Connection::new_loopback();
    let ports = FlockParallelPort::new_group(&cfg, &conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Default::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
    let texts = collect_texts(&conn, &cfg.name);
    let mut sim = SimConfig::for_parallel(&cfg);
    sim.keep_log = true;
    tweak(&mut sim);
    let start = start_now();
    let lines = VirtualLines::new(ports.into_iter().zip(FlockSim::parallel(sim)), start, seed);
    Rig {
        lines,
        start,
        receivers: cfg.slave_ports.len(),
        poses,
        texts,
        conn,
        _remote: remote,
    }
}

const TWO: &str =
    "vrpn_Tracker_Flock_Parallel Tracker0 2 /dev/ttyS0 115200 1 /dev/ttyS1 /dev/ttyS2\n";

impl Rig {
    fn master(&self) -> &FlockParallelPort {
        &self.lines.lines[0].driver
    }

    fn sim(&self) -> std::cell::Ref<'_, super::sim::SimFlock> {
        self.lines.lines[0].device.flock()
    }

    fn texts_with(&self, needle: &str) -> usize {
        self.texts
            .borrow()
            .iter()
            .filter(|(_, t)| t.contains(needle))
            .count()
    }

    fn written(&self, line: usize) -> Vec<Vec<u8>> {
        self.lines.lines[line]
            .written
            .iter()
            .map(|(_, w)| w.clone())
            .collect()
    }

    fn run_to_first_pose(&mut self, max: Duration) -> Duration {
        let poses = self.poses.clone();
        let t0 = self.lines.now().mono;
        assert!(
            self.lines.run_until(max, |_| !poses.borrow().is_empty()),
            "no pose; texts: {:?}",
            self.texts.borrow()
        );
        self.lines.now().mono - t0
    }

    /// Runs until every receiver streams and every line is idle, then forgets what was sent
    /// and seen.
    fn forget_seen(&mut self) {
        let latency = self.lines.lines[0].latency;
        assert!(
            self.lines.run_until(Duration::from_secs(10), |ls| {
                let before = ls.now().mono - latency - Duration::from_micros(1);
                ls.lines[0].driver.is_streaming()
                    && ls
                        .lines
                        .iter()
                        .all(|l| l.is_open() && l.device.is_quiet_at(before))
                    && (0..ls.lines.len() - 1).all(|i| ls.lines[0].driver.receiver_streaming(i))
            }),
            "texts: {:?}",
            self.texts.borrow()
        );
        self.lines.lines[0].device.flock_mut().clear_log();
        self.poses.borrow_mut().clear();
    }

    fn arrival_wall(&self, rec: &SentRecord) -> TimeVal {
        let latency = self.lines.lines[rec.line].latency;
        self.start
            .wall
            .plus(rec.first_byte_at + latency - self.start.mono)
    }

    /// Each receiver's poses are exactly the records its line sent, in order (but for one
    /// still on the line), as sensor = the line's index, extended range, never inverted.
    fn assert_all_arrived(&self) {
        let sent = self.sim().sent().to_vec();
        let poses = self.poses.borrow();
        for i in 0..self.receivers {
            let recs: Vec<&SentRecord> = sent.iter().filter(|r| r.line == i + 1).collect();
            let got: Vec<&TrackerPose> = poses.iter().filter(|p| p.sensor == i).collect();
            assert!(!got.is_empty(), "nothing from receiver {i}");
            assert!(
                got.len() <= recs.len() && recs.len() - got.len() <= 1,
                "receiver {i}: {} sent, {} arrived",
                recs.len(),
                got.len()
            );
            for (p, rec) in got.iter().zip(&recs) {
                assert!(rec.pos_quat);
                let pos = rec.pose.expected_position_m(Transmitter::ExtendedRange);
                assert_eq!([p.pos.x, p.pos.y, p.pos.z], pos, "{rec:?}");
                let q = p.quat.into_inner();
                assert_eq!(
                    [q.i, q.j, q.k, q.w],
                    rec.pose.expected_quat_xyzw(false),
                    "{rec:?}"
                );
                assert_eq!(p.time, self.arrival_wall(rec), "{rec:?}");
            }
        }
        assert!(poses.iter().all(|p| p.sensor < self.receivers));
    }
}

#[test]
fn group_gives_a_driver_per_port() {
    let r = rig(TWO, |_| {}, 1);
    let roles: Vec<(Role, &str)> = r
        .lines
        .lines
        .iter()
        .map(|l| (l.driver.role(), l.driver.port()))
        .collect();
    assert_eq!(
        roles,
        vec![
            (Role::Master, "/dev/ttyS0"),
            (Role::Receiver(0), "/dev/ttyS1"),
            (Role::Receiver(1), "/dev/ttyS2"),
        ]
    );
    for l in &r.lines.lines {
        assert_eq!(l.driver.name(), "Tracker0");
        assert_eq!(
            l.driver.port_kind(),
            PortKind::Serial(PortSettings::n81(115_200))
        );
    }
    // The receivers' internal senders, registered after the tracker's as in C++ (sender 0
    // is the connection's own).
    let names: Vec<Option<String>> = (1..4).map(|i| r.conn.sender_name(SenderId(i))).collect();
    assert_eq!(
        names,
        ["Tracker0", "flockSlave0", "flockSlave1"].map(|n| Some(n.to_owned()))
    );
}

#[test]
fn master_resets_the_flock_then_every_receiver_streams() {
    let mut r = rig(TWO, |_| {}, 2);
    let startup = r.run_to_first_pose(Duration::from_secs(5));
    // The master's reset (≈ 1.2 s with a 0.5 s boot), 0.1 s for the receivers' lines, then
    // the next cycle.
    assert!(
        startup > Duration::from_millis(1250) && startup < Duration::from_millis(1400),
        "start-up took {startup:?}"
    );
    let master = r.written(0);
    let probes = master.iter().filter(|w| w.as_slice() == b"O\x00").count();
    assert!(probes >= 1);
    let tail: Vec<&[u8]> = master[1 + probes..].iter().map(Vec::as_slice).collect();
    assert_eq!(
        tail,
        vec![
            &[b'P', 50, 3][..],
            &[b'O', 36][..],
            &[b'P', 35, 1, 0xF2, b']', 0xF3, b']', 0xF2, b'L', 0x0C, 0, 0xF3, b'L', 0x0C, 0][..],
            &[b'O', 2, b'O', 6][..],
        ],
        "the master stays in point mode"
    );
    for line in [1, 2] {
        assert_eq!(r.written(line), vec![b"B".to_vec(), b"@".to_vec()]);
    }
    r.forget_seen();
    r.lines.run_for(Duration::from_secs(2));
    r.assert_all_arrived();
    // 100 Hz on each receiver's line.
    assert!(r.poses.borrow().len() >= 398, "{}", r.poses.borrow().len());
    let sim = r.sim();
    assert_eq!(
        (sim.resets(), sim.autoconfigs(), sim.configured_units()),
        (1, 1, 3)
    );
    drop(sim);
    assert!(r.master().is_streaming());
    assert_eq!(r.master().failures(), 0);
    assert_eq!(r.texts_with("failed"), 0);
    assert!(r.master().measurement_rate().is_some());
}

#[test]
fn timestamps_are_first_byte_arrivals_on_every_line() {
    for seed in [3, 4] {
        let mut r = rig(
            "vrpn_Tracker_Flock_Parallel T 3 /dev/a 9600 0 /dev/b /dev/c /dev/d\n",
            |_| {},
            seed,
        );
        for l in &mut r.lines.lines {
            l.split_reads = true;
        }
        r.forget_seen();
        r.lines.run_for(Duration::from_secs(1));
        r.assert_all_arrived();
    }
}

#[test]
fn garbage_on_a_receiver_line_loses_nothing() {
    let mut r = rig(TWO, |_| {}, 5);
    r.forget_seen();
    for g in [&[0x05u8, 0x06, 0x07][..], &[0x80, 0x01, 0x02]] {
        // Wait for an idle moment on line 2, then garble it.
        let latency = r.lines.lines[2].latency;
        r.lines.run_for(Duration::from_millis(3));
        assert!(r.lines.run_until(Duration::from_secs(1), |ls| {
            let before = ls.now().mono - latency - Duration::from_micros(1);
            ls.lines[2].device.is_quiet_at(before)
        }));
        r.lines.line(2).inject(g);
    }
    r.lines.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
    assert_eq!(r.master().skipped_bytes(), 6);
    assert_eq!(r.texts_with("skipped"), 1);
}

#[test]
fn silent_receiver_fails_the_flock_and_everything_restarts() {
    let mut r = rig(TWO, |_| {}, 6);
    r.forget_seen();
    r.lines.run_for(Duration::from_millis(200));
    r.lines.line(2).device.stall();
    r.lines.lines[0].device.flock_mut().set_error(13, 0x23);
    let stalled = r.lines.now().mono;
    let restarted = r.master().restarts();
    assert!(r
        .lines
        .run_until(Duration::from_secs(5), |ls| ls.lines[0].driver.restarts()
            > restarted));
    let after = r.lines.now().mono - stalled;
    assert!(
        after >= WATCHDOG && after < WATCHDOG + Duration::from_millis(700),
        "{after:?}"
    );
    assert_eq!(
        r.texts_with("Too long since last report, resetting (receiver 1)"),
        1
    );
    // The master asked why: stop and sleep, then the expanded error code.
    let master = r.written(0);
    let n = master.len();
    assert_eq!(master[n - 2..], [b"BG".to_vec(), vec![b'O', 16]]);
    assert_eq!(
        r.texts_with("Flock error code 13 (expanded: address 3, command 2)"),
        1,
        "{:?}",
        r.texts.borrow()
    );
    assert_eq!(r.texts_with("Tracker failed, trying to reset"), 1);
    // Every port reopens, the Flock is reset and both receivers stream again.
    r.forget_seen();
    for l in &r.lines.lines {
        assert_eq!(l.opens, 2);
    }
    assert_eq!(r.sim().resets(), 2);
    r.lines.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.master().failures(), 0);
}

#[test]
fn receiver_line_closed_restarts_alone() {
    let mut r = rig(TWO, |_| {}, 7);
    r.forget_seen();
    r.lines.line(1).close();
    let n0 = r.poses.borrow().iter().filter(|p| p.sensor == 0).count();
    r.lines.run_for(Duration::from_millis(400));
    // Receiver 1 goes on meanwhile; receiver 0 is silent.
    assert_eq!(
        r.poses.borrow().iter().filter(|p| p.sensor == 0).count(),
        n0
    );
    assert!(r.poses.borrow().iter().filter(|p| p.sensor == 1).count() > 30);
    r.forget_seen();
    assert_eq!(
        r.written(1),
        vec![b"B".to_vec(), b"@".to_vec(), b"B".to_vec(), b"@".to_vec()]
    );
    assert_eq!(r.lines.lines[1].opens, 2);
    assert_eq!((r.lines.lines[0].opens, r.lines.lines[2].opens), (1, 1));
    assert_eq!(r.sim().resets(), 1);
    r.lines.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
    assert_eq!(r.texts_with("failed"), 0);
}

#[test]
fn master_line_closed_resets_the_flock_when_it_returns() {
    let mut r = rig(TWO, |_| {}, 8);
    r.forget_seen();
    r.lines.line(0).close();
    r.lines.run_for(Duration::from_millis(300));
    // The receivers' lines go on while the master's is away.
    assert!(r.poses.borrow().len() > 50);
    r.lines.run_for(Duration::from_millis(300));
    r.forget_seen();
    assert_eq!(r.lines.lines[0].opens, 2);
    assert_eq!(r.sim().resets(), 2);
    for line in [1, 2] {
        assert_eq!(r.written(line).len(), 4, "'B' '@' twice on line {line}");
    }
    r.lines.run_for(Duration::from_secs(1));
    r.assert_all_arrived();
}

#[test]
fn dead_flock_pauses_after_four_failures_then_recovers() {
    let mut r = rig(TWO, |_| {}, 9);
    let t0 = r.lines.now();
    r.lines.lines[0].device.flock_mut().set_powered(false, t0);
    assert!(r
        .lines
        .run_until(Duration::from_secs(60), |ls| ls.lines[0].driver.restarts()
            == 3));
    r.lines.run_for(Duration::from_secs(7));
    assert_eq!(r.texts_with("the master bird does not answer"), 4);
    assert_eq!(r.texts_with("did not answer the error-code request"), 4);
    assert_eq!(r.texts_with("Next attempt in 15 seconds"), 1);
    let writes = r.lines.lines[0].written.len();
    r.lines.run_for(RETRY_PAUSE - Duration::from_secs(2));
    assert_eq!(
        r.lines.lines[0].written.len(),
        writes,
        "quiet while pausing"
    );
    let now = r.lines.now();
    r.lines.lines[0].device.flock_mut().set_powered(true, now);
    r.run_to_first_pose(Duration::from_secs(5));
    assert_eq!(r.master().restarts(), 4);
    r.forget_seen();
    r.lines.run_for(Duration::from_millis(500));
    r.assert_all_arrived();
}

#[test]
fn one_and_thirteen_receivers() {
    let mut thirteen = String::from("vrpn_Tracker_Flock_Parallel Big 13 /dev/m 38400 0");
    for i in 0..13 {
        thirteen.push_str(&format!(" /dev/r{i}"));
    }
    thirteen.push('\n');
    for text in [
        "vrpn_Tracker_Flock_Parallel One 1 /dev/m 19200 0 /dev/r0\n",
        thirteen.as_str(),
    ] {
        let mut r = rig(text, |_| {}, 10);
        r.forget_seen();
        r.lines.run_for(Duration::from_millis(500));
        r.assert_all_arrived();
        assert_eq!(r.sim().configured_units() as usize, r.receivers + 1);
    }
}

#[test]
fn a_port_per_receiver_is_required() {
    let mut cfg = parallel_cfg(TWO);
    cfg.slave_ports.pop();
    let conn = Connection::new_loopback();
    assert!(FlockParallelPort::new_group(&cfg, &conn).is_err());
}
