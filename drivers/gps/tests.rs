//! The GPS driver against the simulated receiver on a virtual serial line, with the
//! driver's server and a client's remote on one in-process connection: exact fixes and
//! stamps, epochs without a fix, feet, garbage, silence, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Gps;
use super::sim::{GpsSim, SimConfig};
use super::{GpsProtocol, RESET_WAIT};
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{Connection, Now, SenderFilter, TimeVal, TrackerPose, TrackerRemote};

type Shared<T> = Rc<RefCell<Vec<T>>>;

struct Rig {
    line: VirtualLine<Lifecycle<GpsProtocol>, GpsSim>,
    start: Now,
    poses: Shared<TrackerPose>,
    texts: Shared<String>,
    _remote: TrackerRemote,
    _conn: Connection,
}

fn rig(text: &str, tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Gps = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let remote = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
    let poses: Shared<TrackerPose> = Rc::default();
    let p = poses.clone();
    remote.on_pose(move |pose| p.borrow_mut().push(*pose));
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
        line: VirtualLine::new(driver, GpsSim::new(sim), start, seed),
        start,
        poses,
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

    /// Every fix the client received is the receiver's, in order, from the one matching
    /// the first, stamped with the arrival of its `$`.
    fn assert_run(&self, from_pose: usize) -> usize {
        let poses = &self.poses.borrow()[from_pose..];
        assert!(!poses.is_empty());
        let sent = self.line.device.sent();
        let p0 = poses[0].pos;
        let at = sent
            .iter()
            .position(|s| s.values == [p0.x, p0.y, p0.z])
            .expect("the first fix was sent");
        assert!(sent.len() - at - poses.len() <= 1, "fixes lost");
        for (p, s) in poses.iter().zip(&sent[at..]) {
            assert_eq!([p.pos.x, p.pos.y, p.pos.z], s.values);
            let q = p.quat.into_inner();
            assert_eq!([q.i, q.j, q.k, q.w], [0.0, 0.0, 0.0, 1.0]);
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                let arrived = self
                    .start
                    .wall
                    .plus(s.first_byte + self.line.latency - self.start.mono);
                assert_eq!(p.time, arrived);
            }
        }
        at
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several sentences at once. The reset ends by
    // discarding what arrived during its wait (as C++ flushes the input); every fix whose
    // first byte came after that is reported, in order.
    let mut r = rig("vrpn_Tracker_GPS Gps0 /dev/ttyS0 38400\n", |_| {}, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(3));
    assert!(r.poses.borrow().len() >= 25, "{}", r.poses.borrow().len());
    let flushed_at = r.start.mono + RESET_WAIT;
    let first_kept = r
        .line
        .device
        .sent()
        .iter()
        .position(|s| s.first_byte + r.line.latency > flushed_at)
        .unwrap();
    assert_eq!(r.assert_run(0), first_kept);
}

#[test]
fn fixes_arrive_exactly_with_their_first_byte_stamps() {
    let mut r = rig("vrpn_Tracker_GPS Gps0 /dev/ttyUSB0 38400\n", |_| {}, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(38400))
    );
    let poses = r.poses.clone();
    let opened = r.line.now().mono;
    assert!(r
        .line
        .run_until(Duration::from_secs(2), |_| !poses.borrow().is_empty()));
    assert!(r.line.now().mono - opened < Duration::from_millis(300));
    assert_eq!(r.line.device.rts(), [true]);
    r.line.run_for(Duration::from_secs(3));
    assert!(r.poses.borrow().len() >= 28, "{}", r.poses.borrow().len());
    r.assert_run(0);
    assert_eq!(r.texts_with("Reset Completed"), 1);
}

#[test]
fn epochs_without_a_fix_send_nothing_and_feet_become_metres() {
    let mut r = rig(
        "vrpn_Tracker_GPS Gps0 /dev/ttyS0 4800\n",
        |s| {
            s.no_fix_every = Some(3);
            s.feet = true;
        },
        2,
    );
    r.line.run_for(Duration::from_secs(6));
    let n = r.poses.borrow().len();
    // 4800 baud: an epoch every 625 ms, two in three with a fix.
    assert!((5..=8).contains(&n), "{n} fixes");
    r.assert_run(0);
    assert!(r.texts_with("cannot determine position") >= 1);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn garbage_costs_no_fix_and_silence_reopens() {
    let mut r = rig("vrpn_Tracker_GPS Gps0 /dev/ttyS0 38400\n", |_| {}, 3);
    r.line.run_for(Duration::from_millis(500));
    for junk in [&b"$GPGGA,12"[..], b"\x00\xFF\n", b"$GPRMC*00\r\n", b"**"] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(170));
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_run(0);
    assert!(r.line.driver.stats().skipped_bytes >= 20);
    assert!(r.texts_with("skipped") >= 1);
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(3));
    assert!(r.texts_with("Tracker failed, trying to reset") >= 1);
    r.line.silent = false;
    let from = r.poses.borrow().len();
    let poses = r.poses.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(3), |_| poses.borrow().len() >= from + 5));
    r.assert_run(from);
}

#[test]
fn configuration_lines_and_their_errors() {
    let g: Gps = parse_one("vrpn_Tracker_GPS Tracker0 /dev/tty.KeySerial1 4800\n");
    assert_eq!(
        (g.name.as_str(), g.port.as_str(), g.baud),
        ("Tracker0", "/dev/tty.KeySerial1", 4800)
    );
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_Tracker_GPS Tracker0 COM1\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_Tracker_GPS Tracker0 COM1 fast\n"),
        ConfigErrorKind::BadNumber
    );
    assert_eq!(
        err("vrpn_Tracker_GPS Tracker0 COM1 4800 1\n"),
        ConfigErrorKind::BadValue
    );
}
