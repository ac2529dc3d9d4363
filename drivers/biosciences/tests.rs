//! The BiosciencesTools driver against its simulated controller on a virtual serial line, with
//! Analog, Analog_Output and Button remotes on one in-process connection: the reset's bytes,
//! readings polled and reported exactly, settings asked for, silence, garbage, the
//! configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Biosciences;
use super::sim::{BioSim, SimConfig};
use super::{set_temperature, BioProtocol};
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal};

const LINE: &str = "vrpn_BiosciencesTools Analog0 COM1 37.0 36.5 0\n";

type Heard = Rc<RefCell<Vec<(Vec<f64>, TimeVal)>>>;

struct Rig {
    line: VirtualLine<Lifecycle<BioProtocol>, BioSim>,
    start: Now,
    heard: Heard,
    texts: Rc<RefCell<Vec<String>>>,
    out: AnalogOutputRemote,
    _analog: AnalogRemote,
    _conn: Connection,
}

fn rig(seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Biosciences = parse_one(LINE);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Heard = Rc::default();
    let analog = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = heard.clone();
    analog.on_report(move |a| {
        h.borrow_mut()
            .push((a.channel[..a.num_channel].to_vec(), a.time))
    });
    let out = AnalogOutputRemote::on_connection(&cfg.name, &conn).unwrap();
    let texts: Rc<RefCell<Vec<String>>> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new();
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, BioSim::new(sim), start, seed),
        start,
        heard,
        texts,
        out,
        _analog: analog,
        _conn: conn,
    }
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

    fn has_text(&self, part: &str) -> bool {
        self.texts.borrow().iter().any(|t| t.contains(part))
    }

    /// Reports from `from` on are the answers logged from `after` on (a contiguous run),
    /// each stamped with its answer's first byte.
    fn check(&self, from: usize, after: usize) {
        let heard = self.heard.borrow();
        let got = &heard[from..];
        let all = self.line.device.sent();
        let start = (after..all.len())
            .find(|&i| all[i].channels[..] == got[0].0[..])
            .unwrap_or_else(|| panic!("first report {:?} never sent", got[0]));
        let sent = &all[start..];
        assert!(got.len() <= sent.len());
        for (i, ((channels, time), s)) in got.iter().zip(sent).enumerate() {
            assert_eq!(channels[..], s.channels[..], "report {i}");
            if !self.line.read_lag.is_zero() {
                // A slow read's reports all carry its wake time.
                continue;
            }
            let want = self.start.wall.plus(s.first_byte - self.start.mono);
            let late = time.seconds_since(want);
            assert!((0.0..0.002).contains(&late), "report {i}: {late} s late");
        }
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers at once: each is still reported,
    // from the first on.
    let mut r = rig(11);
    r.line.read_lag = Duration::from_millis(8);
    r.run_until_reports(100, Duration::from_secs(5));
    assert_eq!(
        r.heard.borrow()[0].0[..],
        r.line.device.sent()[0].channels[..]
    );
    r.check(0, 0);
}

#[test]
fn reset_writes_the_settings_and_polls_every_channel_in_turn() {
    let mut r = rig(1);
    r.line.split_reads = true;
    r.run_until_reports(1, Duration::from_secs(1));
    let startup = r.line.now().mono - r.start.mono;
    assert!(startup < Duration::from_millis(20), "{startup:?}");
    r.run_until_reports(120, Duration::from_secs(5));
    r.check(0, 0);
    let heard = r.line.device.heard();
    assert!(heard.starts_with(b"S1 0370\rS2 0365\rOFF\rT1\rT2\rT3\rT4\rT5\rT6\rT1\r"));
    let s = r.line.device.settings();
    assert_eq!(s.reference, [Some(37.0), Some(36.5)]);
    assert!(!s.control);
    assert!(r.has_text("reset complete (this is normal)"));
    assert_eq!(r.heard.borrow()[0].0.len(), 6);
}

#[test]
fn settings_asked_for_are_written_and_control_is_a_button() {
    let mut r = rig(2);
    let buttons = ButtonRemote::on_connection("Analog0", &r._conn).unwrap();
    let changes = Rc::new(RefCell::new(Vec::new()));
    let c = changes.clone();
    buttons.on_change(move |b| c.borrow_mut().push((b.button, b.state.is_pressed())));
    r.run_until_reports(10, Duration::from_secs(1));
    r.out.request_change_channel_value(0, 25.5).unwrap();
    r.out.request_change_channel_value(2, 1.0).unwrap();
    r.line.run_for(Duration::from_millis(50));
    let s = r.line.device.settings();
    assert_eq!(s.reference[0], Some(25.5));
    assert!(s.control);
    assert_eq!(*changes.borrow(), [(0, true)]);
    r.out.request_change_channels(&[30.0, 31.2, 0.0]).unwrap();
    r.line.run_for(Duration::from_millis(50));
    let s = r.line.device.settings();
    assert_eq!(s.reference, [Some(30.0), Some(31.2)]);
    assert!(!s.control);
    assert_eq!(*changes.borrow(), [(0, true), (0, false)]);
    // Readings went on meanwhile.
    let n = r.heard.borrow().len();
    r.run_until_reports(n + 20, Duration::from_secs(1));
    r.check(0, 0);
}

#[test]
fn garbage_costs_no_reading() {
    let mut r = rig(3);
    r.run_until_reports(10, Duration::from_secs(1));
    for junk in [&b"xyz"[..], b"\r\r", b"\x00\xFF"] {
        let n = r.heard.borrow().len();
        r.run_until_reports(n + 1, Duration::from_secs(1));
        let now = r.line.now().mono;
        r.line.device.inject(junk, now);
    }
    let n = r.heard.borrow().len();
    r.run_until_reports(n + 30, Duration::from_secs(2));
    r.check(0, 0);
    assert_eq!(r.line.driver.stats().skipped_bytes, 7);
    assert!(r.has_text("skipped"));
}

#[test]
fn a_silent_controller_is_set_up_again_and_resumes() {
    let mut r = rig(4);
    r.run_until_reports(10, Duration::from_secs(1));
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(2500));
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    assert!(r.has_text("Tracker failed, trying to reset"));
    let (from, after) = (r.heard.borrow().len(), r.line.device.sent().len());
    r.line.device.mute = false;
    // The watchdog fires again 2 s later and sets the controller up again.
    r.run_until_reports(from + 20, Duration::from_secs(4));
    r.check(from, after);
    assert_eq!(r.line.driver.stats().opens, 1, "reset on the open port");
    let heard = r.line.device.heard();
    assert!(heard.windows(8).filter(|w| w == b"S1 0370\r").count() >= 2);
}

#[test]
fn temperatures_are_formatted_as_cpp_does() {
    let f = |c, v| {
        let (b, n) = set_temperature(c, v);
        String::from_utf8(b[..n].to_vec()).unwrap()
    };
    assert_eq!(f(0, 37.0), "S1 0370\r");
    assert_eq!(f(1, 36.55), "S2 0365\r");
    assert_eq!(f(0, 4.2), "S1 0042\r");
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_BiosciencesTools\tAnalog0\tCOM1 37.0 37.0 0\n\
                vrpn_BiosciencesTools b1 /dev/ttyUSB0 25 30.5 1\n";
    let entries = parse_str(text, "bio.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["Analog0", "b1"]);
    for (bad, why) in [
        ("vrpn_BiosciencesTools b /dev/ttyS0 37 37\n", "control"),
        (
            "vrpn_BiosciencesTools b /dev/ttyS0 warm 37 0\n",
            "temperature 1",
        ),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
