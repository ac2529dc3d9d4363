//! The Crossbow driver against the simulator on a virtual serial line, with the driver's
//! server and a client's remote on one in-process connection: the reset's commands, exact
//! poses, accelerations and velocities with their stamps, a device left streaming, garbage,
//! silence, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Crossbow;
use super::sim::{CrossbowSim, SimConfig, SERIAL};
use super::CrossbowProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{
    Connection, Now, SenderFilter, TimeVal, TrackerAcceleration, TrackerPose, TrackerRemote,
    TrackerVelocity,
};

type Shared<T> = Rc<RefCell<Vec<T>>>;

struct Rig {
    line: VirtualLine<Lifecycle<CrossbowProtocol>, CrossbowSim>,
    start: Now,
    poses: Shared<TrackerPose>,
    accs: Shared<TrackerAcceleration>,
    vels: Shared<TrackerVelocity>,
    texts: Shared<String>,
    _remote: TrackerRemote,
    _conn: Connection,
}

fn rig(text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Crossbow = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |x| p.borrow_mut().push(*x));
    let accs: Shared<TrackerAcceleration> = Rc::default();
    let a = accs.clone();
    remote.on_acceleration(move |x| a.borrow_mut().push(*x));
    let vels: Shared<TrackerVelocity> = Rc::default();
    let v = vels.clone();
    remote.on_velocity(move |x| v.borrow_mut().push(*x));
    let texts: Shared<String> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    sim.ranges = (cfg.g_range, cfg.ar_range);
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, CrossbowSim::new(sim), start, seed),
        start,
        poses,
        accs,
        vels,
        texts,
        _remote: remote,
        _conn: conn,
    }
}

impl Rig {
    fn texts_with(&self, needle: &str) -> usize {
        self.texts
            .borrow()
            .iter()
            .filter(|t| t.contains(needle))
            .count()
    }

    fn run_to_first_pose(&mut self) -> Duration {
        let poses = self.poses.clone();
        let opened = self.line.now().mono;
        assert!(
            self.line
                .run_until(Duration::from_secs(10), |_| !poses.borrow().is_empty()),
            "{:?}",
            self.texts
        );
        self.line.now().mono - opened
    }

    /// Everything from pose `from` on is the device's, in order, with first-byte stamps.
    fn assert_run(&self, from: usize) -> usize {
        let poses = &self.poses.borrow()[from..];
        let accs = &self.accs.borrow()[from..];
        let vels = &self.vels.borrow()[from..];
        assert!(!poses.is_empty());
        assert_eq!((poses.len(), accs.len()), (vels.len(), vels.len()));
        let sent = self.line.device.sent();
        let q0 = poses[0].quat.into_inner();
        let at = sent
            .iter()
            .rposition(|s| s.values.0 == [q0.i, q0.j, q0.k, q0.w])
            .expect("the first pose was sent");
        assert!(
            sent.len() - at - poses.len() <= 1,
            "packets lost: {} sent from {at}, {} arrived",
            sent.len(),
            poses.len()
        );
        for (i, s) in sent[at..].iter().take(poses.len()).enumerate() {
            let (quat, acc, vq) = s.values;
            let (p, a, v) = (&poses[i], &accs[i], &vels[i]);
            let q = p.quat.into_inner();
            assert_eq!([q.i, q.j, q.k, q.w], quat);
            assert_eq!([p.pos.x, p.pos.y, p.pos.z], [0.0; 3]);
            assert_eq!([a.acc.x, a.acc.y, a.acc.z], acc);
            let q = v.vel_quat.into_inner();
            assert_eq!([q.i, q.j, q.k, q.w], vq);
            assert_eq!(v.vel_quat_dt, 1.0);
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                let arrived = self
                    .start
                    .wall
                    .plus(s.first_byte + self.line.latency - self.start.mono);
                assert_eq!((p.time, a.time, v.time), (arrived, arrived, arrived));
            }
        }
        at
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers at once: the reset still
    // completes, and every packet is reported, from the first (the reset ends by asking for
    // one: none can share a read with its last answer).
    let mut r = rig(
        "vrpn_Tracker_Crossbow Tracker0 COM1: 38400 2.0 100\n",
        |_| {},
        21,
    );
    r.line.read_lag = Duration::from_millis(12);
    r.run_to_first_pose();
    r.line.run_for(Duration::from_secs(1));
    assert!(r.poses.borrow().len() > 40, "{}", r.poses.borrow().len());
    assert_eq!(r.assert_run(0), 0);
}

#[test]
fn the_reset_asks_ping_serial_and_version_then_polls() {
    let mut r = rig(
        "vrpn_Tracker_Crossbow Tracker0 COM1: 38400 2.0 100\n",
        |_| {},
        1,
    );
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(38400))
    );
    let startup = r.run_to_first_pose();
    assert!(startup < Duration::from_millis(150), "{startup:?}");
    assert_eq!(&r.line.device.commands()[..5], b"PRSvG");
    assert_eq!(r.line.driver.protocol().serial(), SERIAL);
    assert_eq!(r.texts_with("version 'RGA300CA-200 Rev C'"), 1);
    assert_eq!(r.line.device.rts_pulses(), 0);
    r.line.run_for(Duration::from_secs(1));
    // Polled at the line's pace: 24 bytes at 38400 baud plus the answer delay (3 ms).
    let n = r.poses.borrow().len();
    assert!(
        n >= 100,
        "{n} packets in {:?}",
        r.line.now().mono - r.start.mono
    );
    r.assert_run(0);
}

#[test]
fn a_device_left_streaming_is_stopped_and_ranges_scale_the_values() {
    let mut r = rig(
        "vrpn_Tracker_Crossbow Tracker0 /dev/ttyS0 38400 4 200\n",
        |s| s.continuous_at_start = true,
        2,
    );
    r.run_to_first_pose();
    r.line.run_for(Duration::from_millis(500));
    r.assert_run(0);
}

#[test]
fn garbage_costs_no_packet_and_silence_resets_with_an_rts_pulse() {
    let mut r = rig("vrpn_Tracker_Crossbow T /dev/ttyS0 38400\n", |_| {}, 3);
    r.run_to_first_pose();
    for junk in [
        &[0xAAu8, 0x55, 1, 2][..],
        &[0xAA],
        &[0x00, 0x55, 0xAA, 0xAA],
    ] {
        // Right after a packet: the line is idle until the next is asked for and sent.
        r.line.run_for(Duration::from_millis(50));
        let poses = r.poses.clone();
        let n = poses.borrow().len();
        assert!(r
            .line
            .run_until(Duration::from_secs(1), |_| poses.borrow().len() > n));
        r.line.inject(junk);
    }
    r.line.run_for(Duration::from_millis(300));
    r.assert_run(0);
    assert!(r.line.driver.stats().skipped_bytes >= 9);
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(4));
    assert!(r.texts_with("Tracker failed, trying to reset") >= 1);
    assert!(r.texts_with("not responding") >= 1);
    r.line.silent = false;
    let from = r.poses.borrow().len();
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(5), |_| poses.borrow().len() > from + 50));
    assert!(r.line.device.rts_pulses() >= 1);
    r.assert_run(from);
}

#[test]
fn configuration_lines_and_their_errors() {
    let c: Crossbow = parse_one("vrpn_Tracker_Crossbow Tracker0 COM1: 38400 2.0 100\n");
    assert_eq!(
        (c.port.as_str(), c.baud, c.g_range, c.ar_range),
        ("COM1:", 38400, 2.0, 100.0)
    );
    let c: Crossbow = parse_one("vrpn_Tracker_Crossbow T /dev/ttyS0 9600\n");
    assert_eq!((c.g_range, c.ar_range), (2.0, 100.0));
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_Tracker_Crossbow T COM1\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_Tracker_Crossbow T COM1 38400 -2 100\n"),
        ConfigErrorKind::OutOfRange
    );
    assert_eq!(
        err("vrpn_Tracker_Crossbow T COM1 38400 2 100 7\n"),
        ConfigErrorKind::BadValue
    );
}
