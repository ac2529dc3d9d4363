//! The 3D mouse driver against the simulator on a virtual serial line, with the driver's
//! servers and a client's remotes on one in-process connection: the reset's bytes and timing,
//! exact poses and button changes in order with their stamps, a slow reader, garbage,
//! unanswered requests, silence, failed resets, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::ThreeDMouse;
use super::record::BUTTONS;
use super::reset::{DIAGNOSTICS, RESET, SETTLE};
use super::sim::{Pose, SimConfig, ThreeDMouseSim};
use super::{ThreeDMouseProtocol, REQUEST};
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{ButtonRemote, Connection, Now, SenderFilter, TimeVal, TrackerRemote};

type Shared<T> = Rc<RefCell<Vec<T>>>;

struct Rig {
    line: VirtualLine<Lifecycle<ThreeDMouseProtocol>, ThreeDMouseSim>,
    start: Now,
    poses: Shared<(Pose, TimeVal)>,
    buttons: Shared<(usize, bool, TimeVal)>,
    texts: Shared<String>,
    _remotes: (TrackerRemote, ButtonRemote),
    _conn: Connection,
}

fn rig(text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: ThreeDMouse = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<(Pose, TimeVal)> = Rc::default();
    let p = poses.clone();
    tracker.on_pose(move |x| {
        let q = x.quat.into_inner();
        p.borrow_mut().push((
            (x.sensor, [x.pos.x, x.pos.y, x.pos.z], [q.i, q.j, q.k, q.w]),
            x.time,
        ))
    });
    let button = ButtonRemote::on_connection(&cfg.name, &conn).unwrap();
    let buttons: Shared<(usize, bool, TimeVal)> = Rc::default();
    let b = buttons.clone();
    button.on_change(move |c| {
        b.borrow_mut()
            .push((c.button, c.state.is_pressed(), c.time))
    });
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
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, ThreeDMouseSim::new(sim), start, seed),
        start,
        poses,
        buttons,
        texts,
        _remotes: (tracker, button),
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

    fn arrival(&self, first_byte: Instant) -> TimeVal {
        self.start
            .wall
            .plus(first_byte + self.line.latency - self.start.mono)
    }

    /// The poses heard from `from` on are the ones the simulator sent from record `after`
    /// on, in order, nothing lost but the last one on its way; with `stamps`, each carries
    /// its first byte's arrival. Returns the index of the record the first pose came from.
    fn assert_poses(&self, from: usize, after: usize, stamps: bool) -> usize {
        let heard = &self.poses.borrow()[from..];
        assert!(!heard.is_empty());
        let sent: Vec<(usize, Pose, Instant)> = self.line.device.sent()[after..]
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.sample.pose().map(|p| (after + i, p, s.first_byte)))
            .collect();
        let at = sent
            .iter()
            .position(|s| s.1 == heard[0].0)
            .expect("the first pose was sent");
        assert!(
            sent.len() - at - heard.len() <= 1,
            "poses lost: {} sent from {at}, {} arrived",
            sent.len(),
            heard.len()
        );
        for ((pose, time), (_, want, first)) in heard.iter().zip(&sent[at..]) {
            assert_eq!(pose, want);
            if stamps {
                assert_eq!(*time, self.arrival(*first));
            }
        }
        sent[at].0
    }

    /// The button changes heard are those of the records sent, from the first, in order.
    fn assert_buttons(&self, stamps: bool) {
        let mut state = [false; BUTTONS];
        let mut want = Vec::new();
        for s in self.line.device.sent() {
            for (i, &p) in s.sample.buttons().iter().enumerate() {
                if p != state[i] {
                    want.push((i, p, self.arrival(s.first_byte)));
                    state[i] = p;
                }
            }
        }
        let heard = self.buttons.borrow();
        assert!(heard.len() >= 10, "{} changes", heard.len());
        assert!(want.len() - heard.len() <= BUTTONS);
        for (h, w) in heard.iter().zip(&want) {
            if stamps {
                assert_eq!(h, w);
            } else {
                assert_eq!((h.0, h.1), (w.0, w.1));
            }
        }
    }
}

#[test]
fn the_reset_asks_for_diagnostics_then_records_arrive_exactly() {
    let mut r = rig("vrpn_Tracker_3DMouse Mouse0 COM1 19200\n", |_| {}, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(19200))
    );
    let startup = r.run_to_first_pose();
    // The unit restarts in 50 ms; it is asked after 100 ms; its answer and the first record
    // take 2 + 16 bytes at 19200 baud.
    assert!(startup < Duration::from_millis(150), "{startup:?}");
    let w = &r.line.written;
    assert_eq!(w[0].1, RESET);
    assert_eq!(w[1].1, DIAGNOSTICS);
    assert_eq!(w[1].0 - w[0].0, SETTLE);
    assert_eq!(w[2].1, REQUEST);
    assert_eq!(r.texts_with("Resetting the 3DMouse"), 1);
    assert_eq!(r.texts_with("3DMouse gives status (this is good)"), 1);
    assert_eq!(r.texts_with("Reset Completed (this is good)"), 1);
    assert_eq!(r.line.device.filter_count(), 1);
    r.line.run_for(Duration::from_secs(2));
    // Polled at the line's pace: 16 bytes at 19200 baud (8.3 ms) and the 1 ms answer delay.
    let n = r.line.device.sent().len();
    assert!(n >= 180, "{n} records");
    assert_eq!(r.assert_poses(0, 0, true), 0);
    r.assert_buttons(true);
    // Out-of-range records sent buttons but no pose.
    assert_eq!(r.poses.borrow().len(), n - n / 17 - 1);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes the diagnostics answer, or several records, in
    // one read, stamped with the wake time: the reset completes and every record is reported
    // from the first, and only one request stays in flight.
    for seed in 0..4 {
        let mut r = rig(
            "vrpn_Tracker_3DMouse Mouse0 COM1 19200 2\n",
            |_| {},
            30 + seed,
        );
        r.line.read_lag = Duration::from_millis(12);
        r.line.split_reads = seed % 2 == 1;
        r.run_to_first_pose();
        r.line.run_for(Duration::from_secs(2));
        let sent = r.line.device.sent().len();
        // Each answer waits for the late read before the next request: 12 ms + 9 ms.
        assert!(sent > 80, "{sent} records");
        assert_eq!(r.assert_poses(0, 0, false), 0);
        r.assert_buttons(false);
        // Answered requests, and at most one unanswered.
        assert!(r.line.device.requests() <= sent + 1);
        assert_eq!(r.line.driver.stats().resets, 1);
        assert_eq!(r.line.device.filter_count(), 2);
    }
}

#[test]
fn the_filter_count_is_set_after_the_diagnostics() {
    let mut r = rig("vrpn_Tracker_3DMouse Mouse0 COM1 19200 5\n", |_| {}, 2);
    r.run_to_first_pose();
    let w: Vec<&[u8]> = r.line.written.iter().map(|w| w.1.as_slice()).collect();
    assert_eq!(
        w[..4],
        [RESET, DIAGNOSTICS, &[0x2A, 0x24, 0x02, 0x07, 5], REQUEST]
    );
    assert_eq!(r.line.device.filter_count(), 5);
}

#[test]
fn a_slow_restart_is_asked_again() {
    // A unit that takes 700 ms to restart ignores the first requests.
    let mut r = rig(
        "vrpn_Tracker_3DMouse Mouse0 COM1 19200\n",
        |s| s.reboot_time = Duration::from_millis(700),
        3,
    );
    let startup = r.run_to_first_pose();
    assert!(startup < Duration::from_millis(1100), "{startup:?}");
    assert_eq!(r.line.device.diagnostics_asked(), 1);
    assert!(r.line.driver.protocol().reset.asked() >= 3);
    r.line.run_for(Duration::from_millis(500));
    r.assert_poses(0, 0, true);
}

#[test]
fn garbage_costs_no_record_and_unanswered_requests_are_repeated() {
    let mut r = rig("vrpn_Tracker_3DMouse Mouse0 COM1 19200\n", |_| {}, 4);
    r.run_to_first_pose();
    for junk in [&[0x01u8, 0x7F, 0x41][..], &[0xC5, 0x12], &[0x80]] {
        // Between an answer and the next: the line is idle for the answer delay.
        let sent = r.line.device.sent().len();
        assert!(r.line.run_until(Duration::from_secs(1), |l| {
            l.device.sent().len() > sent && l.device.is_idle()
        }));
        r.line.run_for(Duration::from_micros(200));
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(100));
    }
    r.line.run_for(Duration::from_millis(300));
    assert_eq!(r.line.driver.stats().skipped_bytes, 6);
    assert!(r.texts_with("skipped") >= 1);
    r.assert_poses(0, 0, true);
    r.assert_buttons(true);
    // Requests unanswered for 300 ms: asked again every answer_wait, no reset.
    let asked = r.line.device.requests();
    r.line.device.config_mut().answers = false;
    r.line.run_for(Duration::from_millis(300));
    let again = r.line.device.requests() - asked;
    assert!((3..=6).contains(&again), "{again} requests");
    r.line.device.config_mut().answers = true;
    let from = r.poses.borrow().len();
    let logged = r.line.device.sent().len();
    r.line.run_for(Duration::from_millis(300));
    assert!(r.poses.borrow().len() > from + 20);
    r.assert_poses(from, logged, true);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn silence_resets_and_records_resume() {
    let mut r = rig("vrpn_Tracker_3DMouse Mouse0 COM1 19200\n", |_| {}, 5);
    r.run_to_first_pose();
    r.line.run_for(Duration::from_millis(500));
    let buttons = r.buttons.borrow().len();
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(3));
    assert!(r.texts_with("3DMouse: no record for 2.0 s") >= 1);
    assert!(r.texts_with("3DMouse failed, trying to reset") >= 1);
    assert!(r.line.opens >= 2);
    assert!(r.line.device.resets() >= 2);
    // A reset invents nothing: no button released, no pose.
    assert_eq!(r.buttons.borrow().len(), buttons);
    let from = r.poses.borrow().len();
    let logged = r.line.device.sent().len();
    r.line.silent = false;
    r.line.run_for(Duration::from_secs(6));
    assert!(r.poses.borrow().len() > from + 100);
    r.assert_poses(from, logged, true);
}

#[test]
fn failed_tests_and_no_answer_fail_the_reset() {
    let mut r = rig(
        "vrpn_Tracker_3DMouse Mouse0 COM1 19200\n",
        |s| s.diagnostics = [0x9F, 0x3F],
        6,
    );
    r.line.run_for(Duration::from_millis(300));
    assert!(
        r.texts_with("Bad status report from 3DMouse (BF") == 0
            && r.texts_with("Receiver test failed") >= 1,
        "{:?}",
        r.texts
    );
    assert!(r.line.opens >= 2);
    assert!(r.poses.borrow().is_empty());
    r.line.device.config_mut().diagnostics = [0xBF, 0x3F];
    r.run_to_first_pose();
    // A silent unit: asked every 300 ms for 5 s, then the port is reopened.
    let mut r = rig("vrpn_Tracker_3DMouse Mouse0 COM1 19200\n", |_| {}, 7);
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(5200));
    assert_eq!(
        r.texts_with("no answer to the status request (17 asked)"),
        1
    );
    assert_eq!(r.line.opens, 2);
    r.line.silent = false;
    r.run_to_first_pose();
}

#[test]
fn configuration_lines_and_their_errors() {
    let m: ThreeDMouse = parse_one("vrpn_Tracker_3DMouse Tracker0 /dev/ttyS0 19200\n");
    assert_eq!(
        (m.name.as_str(), m.port.as_str(), m.baud, m.filter_count),
        ("Tracker0", "/dev/ttyS0", 19200, 1)
    );
    for n in 1..=5u8 {
        let m: ThreeDMouse = parse_one(&format!("vrpn_Tracker_3DMouse T COM1 9600 {n}\n"));
        assert_eq!((m.baud, m.filter_count), (9600, n));
    }
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err();
    let e = err("vrpn_Tracker_3DMouse T COM1\n");
    assert_eq!(e.kind(), ConfigErrorKind::MissingArguments);
    assert!(
        e.to_string().starts_with("t.cfg:1: vrpn_Tracker_3DMouse"),
        "{e}"
    );
    for bad in ["0", "6", "two"] {
        let e = err(&format!("\nvrpn_Tracker_3DMouse T COM1 19200 {bad}\n"));
        assert!(e.to_string().starts_with("t.cfg:2: "), "{e}");
        assert!(e.to_string().contains("filter count"), "{e}");
    }
    assert_eq!(
        err("vrpn_Tracker_3DMouse T COM1 19200 2 x\n").kind(),
        ConfigErrorKind::BadValue
    );
    assert_eq!(
        err("vrpn_Tracker_3DMouse T COM1 fast\n").kind(),
        ConfigErrorKind::BadNumber
    );
}

#[test]
fn every_variant_builds_a_tracker_and_buttons() {
    let text = "vrpn_Tracker_3DMouse A /dev/null-a 19200\n\
                vrpn_Tracker_3DMouse B /dev/null-b 9600 4\n";
    let entries = parse_str(text, "t.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["A", "B"]);
    let served: Vec<String> = entries
        .iter()
        .flat_map(|e| {
            e.config
                .served()
                .into_iter()
                .map(|s| format!("{}:{:?}", s.name, s.interface))
                .collect::<Vec<_>>()
        })
        .collect();
    assert_eq!(served, ["A:Tracker", "A:Button", "B:Tracker", "B:Button"]);
}
