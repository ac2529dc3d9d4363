//! The wired YEI driver against the simulator on a virtual serial line, with the driver's
//! servers and a client's remotes on one in-process connection: the reset's bytes and
//! timing, exact poses, accelerations, channels and buttons in order with first-byte stamps,
//! a slow reader, garbage, silence, a unit that does not answer, a reopen, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::command::{wired, STOP_STREAMING};
use super::config::Yei;
use super::record::SLOTS;
use super::sim::{Sent, SimConfig, YeiSim};
use super::wired::WiredProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal, TrackerRemote};

/// What a client hears.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Value {
    Pose(usize, [f64; 4]),
    Analog(Vec<f64>),
    Button(usize, bool),
}

/// The reports a client must receive for `sent`, given the buttons it had before.
pub(super) fn values_of(sent: &[Sent], mut buttons: u8) -> Vec<(Value, Instant)> {
    let mut out = Vec::new();
    for s in sent {
        let t = s.first_byte;
        out.push((Value::Pose(0, s.quats[0]), t));
        out.push((Value::Pose(1, s.quats[1]), t));
        out.push((Value::Analog(s.channels.to_vec()), t));
        for i in 0..8 {
            let (was, is) = (buttons & (1 << i) != 0, s.buttons & (1 << i) != 0);
            if was != is {
                out.push((Value::Button(i, is), t));
            }
        }
        buttons = s.buttons;
    }
    out
}

pub(super) fn heard_values(h: &[Heard]) -> Vec<(Value, TimeVal)> {
    h.iter()
        .filter_map(|h| match h {
            Heard::Pose(p) => {
                let q = p.quat.coords;
                Some((Value::Pose(p.sensor, [q.x, q.y, q.z, q.w]), p.time))
            }
            Heard::Analog { channels, time } => Some((Value::Analog(channels.clone()), *time)),
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((Value::Button(*button, *pressed), *time)),
            _ => None,
        })
        .collect()
}

/// Accelerations heard: m/s² and the stamp.
type Accels = Rc<RefCell<Vec<([f64; 3], TimeVal)>>>;

struct Rig {
    line: VirtualLine<Lifecycle<WiredProtocol>, YeiSim>,
    start: Now,
    client: Client,
    accels: Accels,
    _tracker: TrackerRemote,
    _conn: Connection,
}

const LINE: &str = "vrpn_YEI_3Space_Sensor YEI0 /dev/ttyACM0 115200 1 1 50.0 0.25 0.5 1 1 \\\n\
                    238,1,1,1 \\\n\
                    238,1,1,0\n";

fn rig(text: &str, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Yei = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection(
        "YEI0",
        &conn,
        &[Interface::Tracker, Interface::Analog, Interface::Button],
    )
    .unwrap();
    let tracker = TrackerRemote::on_connection("YEI0", &conn).unwrap();
    let accels: Accels = Rc::default();
    let a = accels.clone();
    tracker.on_acceleration(move |r| {
        assert_eq!((r.sensor, r.acc_quat_dt), (1, 1.0));
        a.borrow_mut().push(([r.acc.x, r.acc.y, r.acc.z], r.time));
    });
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, YeiSim::new(sim), start, seed),
        start,
        client,
        accels,
        _tracker: tracker,
        _conn: conn,
    }
}

impl Rig {
    fn texts_with(&self, needle: &str) -> usize {
        self.client
            .heard()
            .iter()
            .filter(|h| matches!(h, Heard::Text { text, .. } if text.contains(needle)))
            .count()
    }

    fn at(&self, t: Instant) -> TimeVal {
        self.start
            .wall
            .plus(t + self.line.latency - self.start.mono)
    }

    /// Everything heard is what the unit sent from its first record on, in order; with
    /// `stamps`, each at its record's first byte.
    fn assert_all_heard(&self, min_records: usize, stamps: bool) {
        let sent = self.line.device.sent();
        assert!(sent.len() >= min_records, "{} records sent", sent.len());
        let want = values_of(sent, 0);
        let got = heard_values(&self.client.heard());
        assert!(
            want.len() - got.len() <= 3 * 11,
            "{} of {}",
            got.len(),
            want.len()
        );
        for (i, ((g, gt), (w, wt))) in got.iter().zip(&want).enumerate() {
            assert_eq!(g, w, "report {i}");
            if stamps {
                assert_eq!(*gt, self.at(*wt), "stamp of report {i}");
            }
        }
        let accels = self.accels.borrow();
        for (i, ((acc, at), s)) in accels.iter().zip(sent).enumerate() {
            assert_eq!(*acc, s.acc, "acceleration {i}");
            if stamps {
                assert_eq!(*at, self.at(s.first_byte));
            }
        }
        assert!(accels.len() + 1 >= sent.len());
    }
}

#[test]
fn the_reset_sets_up_the_unit_then_records_arrive_exactly() {
    let mut r = rig(LINE, 1);
    r.line.run_for(Duration::from_secs(2));
    let u = &r.line.device.units[0];
    assert_eq!((u.led_mode, u.led_color), (1, [0.25, 0.5, 1.0]));
    assert_eq!((u.calibrations, u.tares, u.starts), (1, 1, 1));
    assert_eq!((u.axes, u.interval_us, u.slots), (Some(1), 20_000, SLOTS));
    assert_eq!(u.ascii, ["238,1,1,1", "238,1,1,0"]);
    assert_eq!(r.line.device.bad_commands, 0);
    assert_eq!(r.line.driver.protocol().led(), Some((1, [0.25, 0.5, 1.0])));
    // The start-up commands and the stop; 50 ms later the two reads; once answered,
    // everything else in one write.
    let w = &r.line.written;
    let mut stop = Vec::new();
    wired(&[STOP_STREAMING], &mut stop);
    assert!(w[0].1.starts_with(&[0xF7, 0xC4, 1, 0xC5, 0xF7, 0xEE]));
    assert!(w[0].1.ends_with(&[0xF7, 0xA5, 0xA5, 0xF7, 0x60, 0x60]));
    assert_eq!(w[1].1, stop);
    assert_eq!(w[2].0 - w[1].0, Duration::from_millis(50));
    assert_eq!(w[2].1, [0xF7, 0xC8, 0xC8, 0xF7, 0xEF, 0xEF]);
    // 13 bytes at 115200 baud after the unit's 0.3 ms.
    assert!(
        w[3].0 - w[2].0 < Duration::from_millis(2),
        "{:?}",
        w[3].0 - w[2].0
    );
    assert!(w[3].1.starts_with(&[0xF7, 0x74, 1, 0x75, 0xF7, 0x52]));
    assert!(w[3].1.ends_with(b":238,1,1,0\n\0\xF7\x55\x55"));
    assert_eq!(w.len(), 4);
    // 50 records/s for the rest of the time.
    r.assert_all_heard(90, true);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn split_reads_lose_nothing() {
    let mut r = rig(LINE, 2);
    r.line.split_reads = true;
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_heard(40, false);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late: the answer to the LED reads that ends the reset shares a
    // read with the first records, which are decoded (not dropped), and records come in lumps.
    let mut r = rig(LINE, 3);
    r.line.device.units[0].ascii.clear();
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(1));
    assert!(r.line.device.sent()[0].first_byte < r.start.mono + Duration::from_millis(70));
    r.assert_all_heard(40, false);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn garbage_costs_no_record() {
    let mut r = rig(LINE, 4);
    r.line.run_for(Duration::from_millis(511));
    for junk in [&b"ZZ"[..], &[0x00, 0x3F, 0x80, 0, 0], &[0xFF; 7]] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(100));
    }
    r.assert_all_heard(35, true);
    assert_eq!(r.line.driver.stats().skipped_bytes, 14);
    assert_eq!(r.texts_with("skipped"), 1);
}

#[test]
fn silence_resets_and_the_unit_that_does_not_answer_is_retried() {
    let mut r = rig(LINE, 5);
    r.line.run_for(Duration::from_millis(500));
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(4700));
    assert_eq!(r.texts_with("vrpn_YEI_3Space::mainloop: Timeout..."), 1);
    assert!(r.texts_with("Unable to read get-led-mode response") >= 1);
    assert!(r.texts_with("vrpn_YEI_3Space: Cannot reset!") >= 1);
    r.line.silent = false;
    let n = r.line.device.sent().len();
    let heard = r.client.len();
    r.line.run_for(Duration::from_secs(3));
    assert!(r.client.len() > heard + 100);
    assert!(r.line.device.sent().len() > n + 50);
    // Start-up commands once per open; a reset only stops, reads back and restarts.
    let u = &r.line.device.units[0];
    assert_eq!((u.calibrations, u.tares), (1, 1));
    assert!(u.starts >= 2);
    // A unit that does not answer the LED reads is retried until it does.
    r.line.device.set_deaf(true);
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(2100));
    r.line.silent = false;
    let fails = r.texts_with("Cannot reset!");
    r.line.run_for(Duration::from_millis(4300));
    assert!(r.texts_with("Cannot reset!") >= fails + 2);
    r.line.device.set_deaf(false);
    let heard = r.client.len();
    r.line.run_for(Duration::from_secs(3));
    assert!(r.client.len() > heard + 100);
}

#[test]
fn a_reopened_port_gets_the_start_up_commands_again() {
    let mut r = rig(LINE, 6);
    r.line.run_for(Duration::from_millis(700));
    r.line.close();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    let u = &r.line.device.units[0];
    assert_eq!((u.calibrations, u.tares, u.starts), (2, 2, 2));
    let heard = r.client.len();
    r.line.run_for(Duration::from_millis(500));
    assert!(r.client.len() > heard + 50);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let y: Yei = parse_one("vrpn_YEI_3Space_Sensor\tYEI0\tCOM7\t115200\t0\t0\t200.0 0 0 1 0\n");
    assert_eq!(
        (y.unit.name.as_str(), y.port.as_str(), y.baud),
        ("YEI0", "COM7", 115200)
    );
    assert!(!y.unit.calibrate_gyros && !y.unit.tare);
    assert_eq!(
        (y.unit.frames_per_second, y.unit.led_color, y.unit.led_mode),
        (200.0, [0.0, 0.0, 1.0], 0)
    );
    assert!(y.unit.reset_commands.is_empty());
    let text = "vrpn_YEI_3Space_Sensor\tYEI0\tCOM7\t115200\t0\t0\t200.0 0 0 1 0\n\
                vrpn_YEI_3Space_Sensor\tYEI1\t/dev/cu.usbmodemfa131\t115200\t0\t0\t200.0 0 0 1 0\n\
                vrpn_YEI_3Space_Sensor\tYEI2\t/dev/ttyACM0\t115200\t1\t1\t0 0.5 0.5 0.5 1\n\
                vrpn_YEI_3Space_Sensor\tYEI3\tCOM7\t115200\t0\t0\t200.0 0 0 1 0 \\\n\
                238,1,1,1 \\\n\
                238,1,0,1 \\\n\
                238,1,1,0\n";
    let entries = parse_str(text, "yei.cfg").unwrap();
    let y3 = entries[3].spec::<Yei>().unwrap();
    assert_eq!(
        y3.unit.reset_commands,
        ["238,1,1,1", "238,1,0,1", "238,1,1,0"]
    );
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 4);
    assert_eq!(names, ["YEI0", "YEI1", "YEI2", "YEI3"]);
    let head = "vrpn_YEI_3Space_Sensor Y /dev/ttyACM0 115200";
    for (bad, kind, why) in [
        (
            format!("{head} 0 0 200\n"),
            ConfigErrorKind::MissingArguments,
            "expected 10",
        ),
        (
            format!("{head} 2 0 200 0 0 1 0\n"),
            ConfigErrorKind::OutOfRange,
            "calibrate",
        ),
        (
            format!("{head} 0 0 fast 0 0 1 0\n"),
            ConfigErrorKind::BadNumber,
            "frames_per_second",
        ),
        (
            format!("{head} 0 0 200 0 0 1.5 0\n"),
            ConfigErrorKind::OutOfRange,
            "blue",
        ),
        (
            format!("{head} 0 0 200 0 0 1 2\n"),
            ConfigErrorKind::OutOfRange,
            "LED_mode",
        ),
        (
            format!("{head} 0 0 200 0 0 1 0 x\n"),
            ConfigErrorKind::BadValue,
            "'x'",
        ),
        (
            format!("{head} 0 0 200 0 0 1 0 /\n"),
            ConfigErrorKind::BadValue,
            "Wireless",
        ),
        (
            format!("{head} 0 0 200 0 0 1 0 \\\n"),
            ConfigErrorKind::UnclosedBlock,
            "reset command",
        ),
        (
            format!("{head} 0 0 200 0 0 1 0 \\\n\n"),
            ConfigErrorKind::BadBlockLine,
            "empty",
        ),
        (
            format!("{head} 0 0 200 0 0 1 0 \\\n238 1\n"),
            ConfigErrorKind::BadBlockLine,
            "one command",
        ),
    ] {
        let e = parse_str(&format!("# c\n{bad}"), "bad.cfg").unwrap_err();
        assert_eq!(e.kind(), kind, "{bad}: {e}");
        let shown = e.to_string();
        assert!(
            shown.starts_with("bad.cfg:2:") || shown.starts_with("bad.cfg:3:"),
            "{shown}"
        );
        assert!(shown.contains(why), "{shown}");
    }
}
