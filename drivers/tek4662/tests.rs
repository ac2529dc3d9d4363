//! The Tek4662 driver against its simulated plotter on a virtual serial line, with a Tracker
//! and a Poser remote on one in-process connection: the reset's bytes, pose requests moving the
//! pen and reported exactly with first-byte stamps, the 4 Hz poll, a slow reader, garbage, a
//! garbled answer, silence, an unplugged line, bad requests, the configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Tek4662;
use super::gin::{self, counts, move_command, COUNTS_PER_METER, GIN, RESET_SEQUENCE};
use super::sim::{count_metres, wander_position, PlotterSim, SimConfig};
use super::Tek4662Protocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::poser::PoserRemote;
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{Connection, Now, SenderFilter, TimeVal, TrackerRemote};

type Heard = Rc<RefCell<Vec<([f64; 3], [f64; 4], TimeVal)>>>;

struct Rig {
    line: VirtualLine<Lifecycle<Tek4662Protocol>, PlotterSim>,
    start: Now,
    heard: Heard,
    texts: Rc<RefCell<Vec<String>>>,
    poser: PoserRemote,
    _tracker: TrackerRemote,
    _conn: Connection,
}

fn rig(wander: bool, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Tek4662 = parse_one("vrpn_Tek4662 Tek4662 COM1 1200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Heard = Rc::default();
    let tracker = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = heard.clone();
    tracker.on_pose(move |p| {
        assert_eq!(p.sensor, 0);
        let q = p.quat.coords;
        h.borrow_mut()
            .push(([p.pos.x, p.pos.y, p.pos.z], [q.x, q.y, q.z, q.w], p.time))
    });
    let poser = PoserRemote::on_connection(&cfg.name, &conn).unwrap();
    let texts: Rc<RefCell<Vec<String>>> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new(1200);
    sim.keep_log = true;
    sim.wander = wander;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, PlotterSim::new(sim), start, seed),
        start,
        heard,
        texts,
        poser,
        _tracker: tracker,
        _conn: conn,
    }
}

/// A position in metres that the driver sends to count `c` exactly.
fn at_count(c: u16) -> f64 {
    (f64::from(c) + 0.5) / COUNTS_PER_METER
}

impl Rig {
    fn run_until_reports(&mut self, n: usize, max: Duration) {
        let h = self.heard.clone();
        assert!(
            self.line.run_until(max, |_| h.borrow().len() >= n),
            "{} of {n} reports; texts {:?}",
            self.heard.borrow().len(),
            self.texts.borrow()
        );
    }

    fn texts_with(&self, part: &str) -> usize {
        self.texts
            .borrow()
            .iter()
            .filter(|t| t.contains(part))
            .count()
    }

    /// Asks for the pen at (`x`, `y`) counts and runs until the plotter is there and has
    /// said so.
    fn move_to(&mut self, x: u16, y: u16) {
        self.poser
            .request_pose(
                self.line.now().wall,
                [at_count(x), at_count(y), 0.0],
                [0.0, 0.0, 0.0, 1.0],
            )
            .unwrap();
        let h = self.heard.clone();
        let want = [count_metres(x), count_metres(y), 0.0];
        assert!(
            self.line.run_until(Duration::from_secs(3), |l| {
                l.device.pen() == (x, y) && h.borrow().last().is_some_and(|r| r.0 == want)
            }),
            "pen {:?}, want ({x}, {y}); texts {:?}",
            self.line.device.pen(),
            self.texts.borrow()
        );
    }

    /// Reports from `from` on are the answers logged from `after` on, in order, each at the
    /// identity orientation and (unless `values_only`) stamped with its first byte.
    fn check(&self, from: usize, after: usize, values_only: bool) {
        let heard = self.heard.borrow();
        let got = &heard[from..];
        let sent = &self.line.device.sent()[after..];
        assert_eq!(got.len(), sent.len(), "{got:?} / {sent:?}");
        for (i, ((pos, quat, time), s)) in got.iter().zip(sent).enumerate() {
            assert_eq!(*pos, s.metres, "report {i}");
            assert_eq!(*quat, [0.0, 0.0, 0.0, 1.0], "report {i}");
            if values_only {
                continue;
            }
            let want = self.start.wall.plus(s.at - self.start.mono);
            let late = time.seconds_since(want);
            assert!((0.0..0.002).contains(&late), "report {i}: {late} s late");
        }
    }

    /// Times the driver wrote a GIN request (alone or after a move).
    fn gin_writes(&self) -> Vec<Instant> {
        self.line
            .written
            .iter()
            .filter(|w| w.1.ends_with(&GIN) && w.1.len() != RESET_SEQUENCE.len())
            .map(|w| w.0)
            .collect()
    }
}

#[test]
fn reset_writes_cpps_bytes_and_reports_the_pen() {
    let mut r = rig(false, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(1200))
    );
    r.run_until_reports(1, Duration::from_secs(2));
    let mut want = vec![0u8; 17];
    want.extend_from_slice(b"\x1bAE\x1bAN\x1bAM");
    assert_eq!(r.line.written[0].1, want);
    assert_eq!(r.line.device.resets(), 1);
    assert_eq!(
        r.heard.borrow()[0].0,
        [count_metres(1000), count_metres(500), 0.0]
    );
    assert_eq!(r.texts_with("vrpn_Poser_Tek4662: Reset correctly"), 1);
    // The answer's first byte leaves 1 ms after the request; seven bytes at 1200 baud.
    let stamp = r.heard.borrow()[0].2.seconds_since(r.start.wall);
    assert!((0.001..0.003).contains(&stamp), "{stamp}");
    r.check(0, 0, false);
}

#[test]
fn poses_move_the_pen_and_the_tracker_reports_exactly() {
    let mut r = rig(false, 2);
    r.line.split_reads = true;
    r.run_until_reports(1, Duration::from_secs(2));
    let targets = [
        (0, 0),
        (4095, 2730),
        (1, 2),
        (2048, 1024),
        (3071, 17),
        (5, 2729),
        (1234, 567),
        (4094, 1),
    ];
    let moves_before = r.line.device.moves();
    for &(x, y) in &targets {
        r.move_to(x, y);
    }
    assert_eq!(r.line.device.moves() - moves_before, targets.len() as u64);
    r.line.run_for(Duration::from_secs(1));
    r.check(0, 0, false);
    // Each move is GS and the address, then a GIN request.
    let m = move_command(1234, 567);
    assert!(r
        .line
        .written
        .windows(2)
        .any(|w| w[0].1 == m && w[1].1 == GIN));
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn requests_are_clamped_and_the_last_of_several_is_carried_out() {
    let mut r = rig(false, 3);
    r.run_until_reports(1, Duration::from_secs(2));
    // Beyond the workspace: the far corner (C++ clamps the same way).
    r.poser
        .request_pose(r.line.now().wall, [1.0, 5.0, 3.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.device.pen(), (counts(0.381), 2730));
    assert!(counts(0.381) >= 4094);
    r.poser
        .request_pose(r.line.now().wall, [-1.0, -1.0, -1.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.device.pen(), (0, 0));
    // A long move under way: the requests that come meanwhile wait, and only the last moves.
    let moves = r.line.device.moves();
    r.poser
        .request_pose(r.line.now().wall, [0.381, 0.254, 0.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    r.line.run_for(Duration::from_millis(100));
    for x in [100u16, 200, 300] {
        r.poser
            .request_pose(r.line.now().wall, [at_count(x), 0.1, 0.0], [0.0; 4])
            .unwrap();
        r.line.run_for(Duration::from_millis(50));
    }
    r.line.run_for(Duration::from_secs(3));
    assert_eq!(r.line.device.moves() - moves, 2);
    assert_eq!(r.line.device.pen(), (300, counts(0.1)));
    // Not a number: refused with a text, nothing moves; velocities do nothing (as in C++).
    let moves = r.line.device.moves();
    r.poser
        .request_pose(r.line.now().wall, [f64::NAN, 0.1, 0.0], [0.0; 4])
        .unwrap();
    r.poser
        .request_pose_velocity(r.line.now().wall, [0.1, 0.1, 0.0], [0.0; 4], 1.0)
        .unwrap();
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.device.moves(), moves);
    assert_eq!(r.texts_with("not a number"), 1);
    r.check(0, 0, false);
}

#[test]
fn between_moves_the_position_is_asked_four_times_a_second() {
    let mut r = rig(true, 4);
    r.run_until_reports(1, Duration::from_secs(2));
    r.line.run_for(Duration::from_secs(10));
    let asks = r.gin_writes();
    assert!((38..=41).contains(&asks.len()), "{} requests", asks.len());
    // Each request comes 250 ms after the previous answer's first byte, not sooner.
    let sent = r.line.device.sent();
    for (ask, answer) in asks.iter().zip(sent) {
        let gap = *ask - answer.at;
        assert!(
            gap >= Duration::from_millis(250) && gap < Duration::from_millis(252),
            "{gap:?}"
        );
    }
    // The joystick's wandering pen is followed exactly.
    assert_eq!(sent[5].counts, wander_position(5));
    r.check(0, 0, false);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers at once: the reset's answer and
    // the one after it in one read, then answers and pieces of answers.
    let mut r = rig(true, 5);
    r.line.read_lag = Duration::from_millis(150);
    // The reset's answer has left by 70 ms; the read comes at 150 ms.
    r.line.run_for(Duration::from_millis(90));
    assert!(r.heard.borrow().is_empty(), "read before the lag");
    let extra = [0x20 | 3, 0x20 | 1, 0x20 | 5, 0x20 | 7, 0x20, 0x20, 0x40];
    assert_eq!(
        gin::decode(&extra).map(|g| (g.x, g.y)),
        Some(((3 << 7) | (5 << 2), (1 << 7) | (7 << 2)))
    );
    r.line.inject(&extra);
    r.run_until_reports(2, Duration::from_millis(200));
    let first: Vec<[f64; 3]> = r.heard.borrow().iter().map(|h| h.0).collect();
    let extra_at = [
        count_metres(3 << 7 | 5 << 2),
        count_metres(1 << 7 | 7 << 2),
        0.0,
    ];
    assert_eq!(first, [r.line.device.sent()[0].metres, extra_at]);
    assert_eq!(r.line.driver.stats().resets, 1);
    // Then everything the plotter says, with moves among the polls.
    r.line.read_lag = Duration::from_millis(40);
    r.line.split_reads = true;
    let from = r.heard.borrow().len();
    r.line.run_for(Duration::from_secs(3));
    r.line.device.set_wander(false);
    r.move_to(700, 800);
    r.move_to(10, 2000);
    r.line.device.set_wander(true);
    r.line.run_for(Duration::from_secs(2));
    r.check(from, 1, true);
    assert!(r.heard.borrow().len() - from >= 15);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn garbage_between_answers_costs_no_answer() {
    let mut r = rig(true, 6);
    r.run_until_reports(1, Duration::from_secs(2));
    let junk: [&[u8]; 5] = [b"zz", b"\x00\xff", b"@A", b"12", b"\x1f\x60\x7f"];
    for (k, j) in junk.iter().enumerate() {
        // Just after an answer the line is quiet until the next request.
        r.run_until_reports(2 + k, Duration::from_secs(1));
        r.line.inject(j);
    }
    r.line.run_for(Duration::from_secs(2));
    r.check(0, 0, false);
    assert_eq!(r.line.driver.stats().skipped_bytes, 11);
    assert!(r.texts_with("Tek4662: skipped") >= 1);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn an_answer_lost_on_the_line_is_asked_for_again() {
    let mut r = rig(true, 7);
    r.run_until_reports(1, Duration::from_secs(2));
    r.line.run_for(Duration::from_millis(200));
    // Part of the next answer is lost.
    let answers = r.line.device.answers();
    assert!(r
        .line
        .run_until(Duration::from_secs(1), |l| l.device.answers() > answers));
    r.line.run_for(Duration::from_millis(20));
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(30));
    r.line.silent = false;
    let n = r.heard.borrow().len();
    r.line.run_for(Duration::from_millis(1900));
    assert_eq!(r.heard.borrow().len(), n, "waiting for the lost answer");
    assert_eq!(r.line.driver.protocol().outstanding(), 1);
    r.line.run_for(Duration::from_secs(2));
    assert!(r.heard.borrow().len() >= n + 5);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    // The reports are the answers that arrived whole.
    let sent = r.line.device.sent();
    let heard: Vec<[f64; 3]> = r.heard.borrow().iter().map(|h| h.0).collect();
    let whole: Vec<[f64; 3]> = sent
        .iter()
        .map(|s| s.metres)
        .filter(|m| heard.contains(m))
        .collect();
    assert_eq!(heard, whole);
    assert_eq!(sent.len(), heard.len() + 1, "one answer lost");
}

#[test]
fn silence_resets_the_plotter_and_reports_resume() {
    let mut r = rig(true, 8);
    r.run_until_reports(1, Duration::from_secs(2));
    r.line.run_for(Duration::from_secs(1));
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(5400));
    assert_eq!(
        r.texts_with("vrpn_Poser_Tek4662: Device timeout (resetting)"),
        1
    );
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    r.line.run_for(Duration::from_secs(2));
    assert!(r.texts_with("Expected 7 characters, got 0") >= 1);
    assert!(!r.line.driver.is_streaming());
    r.line.silent = false;
    let (from, after) = (r.heard.borrow().len(), r.line.device.sent().len());
    assert!(r
        .line
        .run_until(Duration::from_secs(2), |l| l.driver.is_streaming()));
    r.line.run_for(Duration::from_secs(1));
    r.line.device.set_wander(false);
    r.move_to(3000, 2000);
    // What was heard after the silence is what the plotter said after it (the answers
    // lost in the silence were never reported).
    r.check(from, after, false);
    assert_eq!(r.line.driver.stats().opens, 1, "reset on the open port");
}

#[test]
fn an_unplugged_plotter_is_reopened_and_moves_again() {
    let mut r = rig(false, 9);
    r.run_until_reports(1, Duration::from_secs(2));
    r.move_to(100, 200);
    r.line.close();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.texts_with("Reset correctly"), 2);
    r.move_to(200, 100);
    r.check(0, 0, false);
}

#[test]
fn a_reset_with_a_garbled_answer_is_tried_again() {
    let mut r = rig(false, 10);
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(50));
    r.line.inject(b"zzzzzzzzz");
    r.line.run_for(Duration::from_millis(1000));
    assert_eq!(r.texts_with("vrpn_Poser_Tek4662: Error resetting"), 1);
    r.line.silent = false;
    r.run_until_reports(1, Duration::from_secs(2));
    assert_eq!(r.line.driver.stats().reset_attempts, 2);
}

#[test]
fn configuration_lines_and_their_errors() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let t: Tek4662 = parse_one("vrpn_Tek4662\tTek4662\tCOM1\t1200\n");
    assert_eq!(
        t,
        Tek4662 {
            name: "Tek4662".into(),
            port: "COM1".into(),
            baud: 1200
        }
    );
    let t: Tek4662 = parse_one("vrpn_Tek4662 plot /dev/ttyUSB0 9600 ignored\n");
    assert_eq!((t.port.as_str(), t.baud), ("/dev/ttyUSB0", 9600));
    let text = "vrpn_Tek4662 p0 COM1 1200\nvrpn_Tek4662 p1 /dev/ttyS1 2400\n";
    let entries = parse_str(text, "tek.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["p0", "p1"]);
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err();
    assert_eq!(
        err("vrpn_Tek4662 p0 COM1\n").kind(),
        ConfigErrorKind::MissingArguments
    );
    let e = err("# plotter\nvrpn_Tek4662 p0 COM1 fast\n").to_string();
    assert!(e.contains("t.cfg:2") && e.contains("baud"), "{e}");
    let e = err("vrpn_Tek4662 p0 COM1 1201\n").to_string();
    assert!(e.contains("t.cfg:1") && e.contains("baud"), "{e}");
}
