//! The Nikon focus driver against its simulated microscope on a virtual serial line, with an
//! Analog and an Analog_Output remote on one in-process connection: the reset, moves asked for
//! and reported exactly with first-byte stamps, the idle poll, a slow reader, garbage, error
//! answers, silence, an unplugged line, the configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::answer::{move_command, Answer, Framer, Step};
use super::config::Nikon;
use super::sim::{NikonSim, SimConfig};
use super::NikonProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, Connection, Now, SenderFilter, TimeVal};

type Heard = Rc<RefCell<Vec<(f64, TimeVal)>>>;

struct Rig {
    line: VirtualLine<Lifecycle<NikonProtocol>, NikonSim>,
    start: Now,
    heard: Heard,
    texts: Rc<RefCell<Vec<String>>>,
    out: AnalogOutputRemote,
    _analog: AnalogRemote,
    _conn: Connection,
}

fn rig(seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Nikon = parse_one("vrpn_nikon_controls Nikon0 COM1\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Heard = Rc::default();
    let analog = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = heard.clone();
    analog.on_report(move |a| {
        assert_eq!(a.num_channel, 1);
        h.borrow_mut().push((a.channel[0], a.time))
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
    let mut sim = SimConfig::new(9600);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, NikonSim::new(sim), start, seed),
        start,
        heard,
        texts,
        out,
        _analog: analog,
        _conn: conn,
    }
}

/// `v` without runs of equal values (a client is told a position only when it changed).
fn changes<T: Copy + PartialEq>(v: impl IntoIterator<Item = (f64, T)>) -> Vec<(f64, T)> {
    let mut out: Vec<(f64, T)> = Vec::new();
    for (x, t) in v {
        if out.last().map_or(true, |l| l.0 != x) {
            out.push((x, t));
        }
    }
    out
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

    fn move_to(&mut self, value: f64) {
        let n = self.heard.borrow().len();
        self.out.request_change_channel_value(0, value).unwrap();
        self.run_until_reports(n + 1, Duration::from_secs(2));
    }

    /// Every report is a change of the positions the microscope told, in order, stamped
    /// with the arrival of the answer's first byte.
    fn check(&self) {
        let heard = changes(self.heard.borrow().iter().copied());
        let sent = changes(
            self.line
                .device
                .sent()
                .iter()
                .map(|s| (s.focus as f64, s.at)),
        );
        assert_eq!(heard.len(), sent.len(), "{heard:?} / {sent:?}");
        for (i, ((v, time), (want, at))) in heard.iter().zip(&sent).enumerate() {
            assert_eq!(v, want, "report {i}");
            let first = self.start.wall.plus(*at - self.start.mono);
            let late = time.seconds_since(first);
            assert!((0.0..0.002).contains(&late), "report {i}: {late} s late");
        }
    }
}

#[test]
fn reset_reports_the_focus_and_moves_are_reported_exactly() {
    let mut r = rig(1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    r.run_until_reports(1, Duration::from_secs(2));
    assert_eq!(r.heard.borrow()[0].0, 1234.0);
    assert_eq!(r.texts_with("reset complete (this is good)"), 1);
    assert_eq!(r.line.written[0].1, b"rSPR\r");
    for (k, v) in [500.0, -20.0, 99_999.9, 0.0, -777.0, 3.0]
        .into_iter()
        .enumerate()
    {
        r.move_to(v);
        assert_eq!(r.line.device.focus(), v as i64, "move {k}");
    }
    let moves: Vec<&[u8]> = r
        .line
        .written
        .iter()
        .filter(|w| w.1.starts_with(b"fSMV"))
        .map(|w| &w.1[..])
        .collect();
    assert_eq!(moves[2], b"fSMV99999\r");
    assert_eq!(moves[4], b"fSMV-777\r");
    r.check();
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn answers_in_the_read_of_the_reset_answer_are_reported() {
    // A slow reader takes the reset's answer and the next one in one read (a loaded
    // machine): the second is an answer, not part of the reset.
    let mut r = rig(2);
    r.line.read_lag = Duration::from_millis(30);
    r.line.run_for(Duration::from_millis(15));
    assert!(r.heard.borrow().is_empty(), "read before the lag");
    r.line.inject(b"aSPR777\r\n");
    r.line.run_for(Duration::from_millis(100));
    let heard: Vec<f64> = r.heard.borrow().iter().map(|h| h.0).collect();
    assert_eq!(heard, [1234.0, 777.0]);
    assert_eq!(r.texts_with("reset complete (this is good)"), 1);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn a_quiet_microscope_is_polled_and_a_turned_knob_reported() {
    let mut r = rig(3);
    r.run_until_reports(1, Duration::from_secs(2));
    r.line.run_for(Duration::from_millis(10_500));
    // Asked once a second, answered each time: no time-out.
    let polls = r.line.device.requests();
    assert!((10..=12).contains(&polls), "{polls} requests");
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    assert_eq!(r.heard.borrow().len(), 1, "no change, no report");
    r.line.device.turn_knob(4321);
    r.run_until_reports(2, Duration::from_millis(1100));
    assert_eq!(r.heard.borrow()[1].0, 4321.0);
    r.check();
}

#[test]
fn garbage_errors_silence_and_unplugging() {
    let mut r = rig(4);
    r.run_until_reports(1, Duration::from_secs(2));
    r.move_to(10.0);
    for junk in [&b"zz\r\n"[..], b"\x00\xff", b"aXYZ\r\n"] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(50));
    }
    r.move_to(20.0);
    assert_eq!(r.line.driver.stats().skipped_bytes, 4 + 2 + 6);
    // A move out of range: the microscope's error, as a warning; no report.
    let n = r.heard.borrow().len();
    r.out.request_change_channel_value(0, 5e6).unwrap();
    r.line.run_for(Duration::from_millis(100));
    assert_eq!(r.texts_with("Operand error"), 1);
    assert_eq!(r.heard.borrow().len(), n);
    r.check();
    // Silence: polled, then reset after 10 s; moves resume.
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(11));
    assert_eq!(r.texts_with("Timeout..."), 1);
    r.line.silent = false;
    r.line.run_for(Duration::from_secs(3));
    assert_eq!(r.texts_with("reset complete (this is good)"), 2);
    r.move_to(30.0);
    // Unplugged and back: reset, reported, moves resume.
    r.line.close();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.texts_with("reset complete (this is good)"), 3);
    r.move_to(40.0);
    r.check();
}

#[test]
fn answers_are_framed_and_read_as_cpp_reads_them() {
    let t = Now {
        mono: Instant::now(),
        wall: TimeVal::new(5, 0),
    };
    let later = Now {
        mono: t.mono + Duration::from_millis(3),
        wall: TimeVal::new(5, 3000),
    };
    let mut f = Framer::new();
    let mut got = Vec::new();
    for (i, &b) in b"x\naSPR-42\r\nqSMVA\r\noSMV\r\nnSMV2\r\nnSPR5\r\naSPR 7junk\r\n"
        .iter()
        .enumerate()
    {
        if let Step::Answer(a, at) = f.push(b, if i < 3 { t } else { later }) {
            got.push((a, at == t));
        }
    }
    assert_eq!(
        got,
        [
            (Answer::Focus(-42), true),
            (Answer::Moving, false),
            (Answer::Arrived, false),
            (Answer::MoveError(2), false),
            (Answer::FocusError(5), false),
            (Answer::Focus(7), false),
        ]
    );
    assert_eq!(f.take_skipped(), 2);
    let mut cmd = [0u8; 32];
    let n = move_command(i64::MIN, &mut cmd);
    assert_eq!(&cmd[..n], b"fSMV-9223372036854775808\r");
}

#[test]
fn configuration_lines_and_their_errors() {
    let n: Nikon = parse_one("vrpn_nikon_controls nikon COM1\n");
    assert_eq!((n.name.as_str(), n.port.as_str()), ("nikon", "COM1"));
    let n: Nikon = parse_one("vrpn_nikon_controls nikon /dev/ttyUSB0 ignored\n");
    assert_eq!(n.port, "/dev/ttyUSB0");
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_nikon_controls nikon\n"),
        ConfigErrorKind::MissingArguments
    );
}
