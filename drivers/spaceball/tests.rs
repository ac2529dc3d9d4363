//! The Spaceball driver against its simulator on a virtual serial line, with an Analog and a
//! Button remote on one in-process connection: the reset's bytes and pacing, exact values and
//! stamps for both models, garbage, a reset banner, a reopen, the configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Spaceball;
use super::sim::{Event, Listener, Model, SimConfig, SpaceballSim};
use super::{SpaceballProtocol, BYTE_GAP, INIT};
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal};

const LINE: &str = "vrpn_Spaceball Spaceball0 /dev/ttyS0 9600\n";

struct Rig {
    line: VirtualLine<Lifecycle<SpaceballProtocol>, SpaceballSim>,
    start: Now,
    heard: Rc<RefCell<Listener>>,
    texts: Rc<RefCell<Vec<String>>>,
    _remotes: (AnalogRemote, ButtonRemote),
    _conn: Connection,
}

fn rig(model: Model, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Spaceball = parse_one(LINE);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Rc<RefCell<Listener>> = Rc::default();
    let analog = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = heard.clone();
    analog.on_report(move |a| h.borrow_mut().analog(&a.channel[..a.num_channel], a.time));
    let buttons = ButtonRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = heard.clone();
    buttons.on_change(move |c| {
        h.borrow_mut()
            .button(c.button, c.state.is_pressed(), c.time)
    });
    let texts: Rc<RefCell<Vec<String>>> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new(cfg.baud);
    sim.model = model;
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, SpaceballSim::new(sim), start, seed),
        start,
        heard,
        texts,
        _remotes: (analog, buttons),
        _conn: conn,
    }
}

impl Rig {
    fn events(&self) -> usize {
        self.heard.borrow().events.len()
    }

    fn run_until_events(&mut self, n: usize, max: Duration) {
        let h = self.heard.clone();
        assert!(
            self.line.run_until(max, |_| h.borrow().events.len() >= n),
            "{} of {n} events; texts {:?}",
            self.events(),
            self.texts.borrow()
        );
    }

    /// What was heard is exactly what was sent from log index `after` on (a contiguous run,
    /// from the heard event `from`), each stamped with the arrival of its first byte (the
    /// virtual line delivers at once).
    fn check(&self, from: usize, after: usize) -> usize {
        let heard = self.heard.borrow();
        let got = &heard.events[from..];
        let sent = self.line.device.sent();
        let start = (after..sent.len())
            .find(|&i| sent[i].event == got[0].0)
            .unwrap_or_else(|| panic!("first event {:?} never sent", got[0]));
        for (i, (event, time)) in got.iter().enumerate() {
            let s = &sent[start + i];
            assert_eq!(*event, s.event, "event {i}");
            if !self.line.read_lag.is_zero() {
                // A slow read's records all carry its wake time: values only.
                continue;
            }
            let want = self.start.wall.plus(s.first_byte - self.start.mono);
            let late = time.seconds_since(want);
            assert!((0.0..0.002).contains(&late), "event {i}: {late} s late");
        }
        start
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several packets at once, during the set-up and
    // after: each is reported, from the first the ball sent on.
    for (model, seed) in [(Model::Sb4000, 21), (Model::Sb2003, 22)] {
        let mut r = rig(model, seed);
        r.line.read_lag = Duration::from_millis(12);
        r.run_until_events(200, Duration::from_secs(10));
        assert_eq!(r.check(0, 0), 0, "{model:?}");
    }
}

#[test]
fn port_settings() {
    let r = rig(Model::Sb4000, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
}

#[test]
fn reset_writes_the_set_up_string_slowly_and_starts_in_a_fifth_of_a_second() {
    let mut r = rig(Model::Sb4000, 2);
    assert!(r
        .line
        .run_until(Duration::from_secs(1), |l| l.driver.is_streaming()));
    let heard = r.line.device.heard();
    assert_eq!(heard, INIT);
    let at = r.line.device.heard_at();
    for w in at.windows(2) {
        assert!(w[1] - w[0] >= BYTE_GAP, "{:?}", w[1] - w[0]);
    }
    // The last byte goes out 32 gaps after the first; the reset ends when it is written.
    let took = r.line.now().mono - r.start.mono;
    assert!(
        took >= BYTE_GAP * 32 && took < Duration::from_millis(200),
        "{took:?}"
    );
    // Packets the ball sent meanwhile were reported (the input was flushed first).
    assert!(r.events() > 0);
}

#[test]
fn values_and_stamps_arrive_exactly_in_order_for_both_models() {
    for (model, seed) in [(Model::Sb4000, 3), (Model::Sb2003, 4)] {
        let mut r = rig(model, seed);
        r.line.split_reads = true;
        r.run_until_events(200, Duration::from_secs(10));
        r.check(0, 0);
        assert_eq!(r.line.driver.protocol().is_4000(), model == Model::Sb4000);
        let buttons = r
            .heard
            .borrow()
            .events
            .iter()
            .filter(|e| matches!(e.0, Event::Buttons(_)))
            .count();
        assert!(buttons >= 40, "{buttons} key packets");
    }
}

#[test]
fn garbage_costs_no_packet() {
    let mut r = rig(Model::Sb4000, 6);
    r.run_until_events(20, Duration::from_secs(5));
    let junk: [&[u8]; 6] = [
        b"\x01\x02xyz",
        b"D\x00\x01\x02",
        b"K\xFF",
        b"^",
        b"D^M^Q\x0D",
        b"E\x01\r",
    ];
    for junk in junk {
        let n = r.events();
        r.run_until_events(n + 1, Duration::from_secs(1));
        let now = r.line.now().mono;
        r.line.device.inject(junk, now);
    }
    let n = r.events();
    r.run_until_events(n + 40, Duration::from_secs(5));
    r.check(0, 0);
    assert_eq!(r.line.driver.protocol().errors(), 1);
    // 5 + 4 + 2 + 0 (an eaten escape) + 3 (the plain CR at the end is a packet).
    assert_eq!(r.line.driver.stats().skipped_bytes, 14);
    assert!(r.texts.borrow().iter().any(|t| t.contains("skipped")));
}

#[test]
fn a_reset_banner_sets_the_device_up_again() {
    let mut r = rig(Model::Sb4000, 7);
    r.run_until_events(20, Duration::from_secs(5));
    let now = r.line.now().mono;
    r.line.device.banner(now);
    let n = r.events();
    r.run_until_events(n + 30, Duration::from_secs(5));
    assert_eq!(r.line.device.heard(), [INIT, INIT].concat());
    assert!(r.texts.borrow().iter().any(|t| t.contains("reset itself")));
    assert_eq!(r.line.driver.stats().resets, 2);
}

#[test]
fn a_closed_port_is_reopened_and_set_up_again() {
    let mut r = rig(Model::Sb4000, 8);
    r.run_until_events(20, Duration::from_secs(5));
    r.line.close();
    let n = r.events();
    r.run_until_events(n + 20, Duration::from_secs(5));
    assert_eq!(r.line.device.heard(), [INIT, INIT].concat());
    assert_eq!(r.line.driver.stats().opens, 2);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Spaceball Spaceball0 /dev/ttyS0 9600\n\
                vrpn_Spaceball\tsb1\tCOM1\t19200\n";
    let entries = parse_str(text, "sb.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["Spaceball0", "sb1"]);
    for (bad, why) in [
        ("vrpn_Spaceball Spaceball0 /dev/ttyS0 12345\n", "12345"),
        ("vrpn_Spaceball Spaceball0 /dev/ttyS0\n", "baud"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
