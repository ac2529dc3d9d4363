//! The IDEA driver against its simulated drive on a virtual serial line, with Analog, Button
//! and Analog_Output remotes on one in-process connection: the reset's commands in C++'s
//! order, the limit hunt, moves seen as they go and reported exactly, the inputs, limits,
//! faults, silence, garbage, a slow reader, the configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Idea;
use super::sim::{IdeaSim, SimConfig};
use super::IdeaProtocol;
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal};

/// The sample's line with a limit hunt: 50 steps at a time at half the speeds and currents
/// until input 1 (the high limit) closes, then the position is set to -60 steps.
const LINE: &str = "vrpn_IDEA Idea0 /dev/ttyUSB0 3200 1200 2000 40000 100000 290 0 290 290 50 \
                    8 1 -1 0 1 -1 0 50 0.5 -60.0\n";
/// C++'s own sample line: no initial move, no hunt.
const PLAIN: &str = "vrpn_IDEA Analog0 COM1 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 \
                     0 0 0 0 0 1.0 -60.0\n";

type Heard<T> = Rc<RefCell<Vec<(T, TimeVal)>>>;

struct Rig {
    line: VirtualLine<Lifecycle<IdeaProtocol>, IdeaSim>,
    start: Now,
    positions: Heard<f64>,
    buttons: Heard<(usize, bool)>,
    texts: Rc<RefCell<Vec<String>>>,
    out: AnalogOutputRemote,
    _analog: AnalogRemote,
    _button: ButtonRemote,
    _conn: Connection,
}

fn rig_with(text: &str, sim: SimConfig, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Idea = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let positions: Heard<f64> = Rc::default();
    let analog = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = positions.clone();
    analog.on_report(move |a| h.borrow_mut().push((a.channel[0], a.time)));
    let buttons: Heard<(usize, bool)> = Rc::default();
    let button = ButtonRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = buttons.clone();
    button.on_change(move |c| {
        h.borrow_mut()
            .push(((c.button, c.state.is_pressed()), c.time))
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
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, IdeaSim::new(sim), start, seed),
        start,
        positions,
        buttons,
        texts,
        out,
        _analog: analog,
        _button: button,
        _conn: conn,
    }
}

fn logged() -> SimConfig {
    SimConfig {
        keep_log: true,
        ..SimConfig::new()
    }
}

fn rig(seed: u64) -> Rig {
    rig_with(LINE, logged(), seed)
}

/// `v` without runs of equal values (a client is told of a change only).
fn changes<T: Copy + PartialEq>(v: impl IntoIterator<Item = (T, Instant)>) -> Vec<(T, Instant)> {
    let mut out: Vec<(T, Instant)> = Vec::new();
    for (x, t) in v {
        if out.last().map_or(true, |l| l.0 != x) {
            out.push((x, t));
        }
    }
    out
}

impl Rig {
    fn has_text(&self, part: &str) -> bool {
        self.texts.borrow().iter().any(|t| t.contains(part))
    }

    fn streaming(&mut self, max: Duration) {
        assert!(
            self.line.run_until(max, |l| l.driver.is_streaming()),
            "not streaming; texts {:?}",
            self.texts.borrow()
        );
    }

    /// Asks for a move to `to` and runs until the position `to` is reported.
    fn move_to(&mut self, to: f64) {
        self.out.request_change_channel_value(0, to).unwrap();
        let h = self.positions.clone();
        assert!(
            self.line.run_until(Duration::from_secs(3), |_| h
                .borrow()
                .last()
                .is_some_and(|p| p.0 == to)),
            "never at {to}; heard {:?}",
            self.positions.borrow().last()
        );
    }

    /// The positions reported from `from` on are the changes the drive told after its log
    /// index `after`, in order, each stamped with its answer's first byte.
    fn check_positions(&self, from: usize, after: usize) {
        let heard = self.positions.borrow();
        let got = &heard[from..];
        let told = changes(
            self.line.device.positions()[after..]
                .iter()
                .map(|t| (t.value, t.at)),
        );
        let start = told
            .iter()
            .position(|t| t.0 == got[0].0)
            .expect("first report told");
        let told = &told[start..start + got.len()];
        for (i, ((v, time), (want, at))) in got.iter().zip(told).enumerate() {
            assert_eq!(v, want, "report {i}");
            if !self.line.read_lag.is_zero() {
                // A slow read's answers all carry its wake time: values only.
                continue;
            }
            let want = self.start.wall.plus(*at - self.start.mono);
            let late = time.seconds_since(want);
            assert!((0.0..0.002).contains(&late), "report {i}: {late} s late");
        }
    }
}

#[test]
fn reset_writes_cxx_commands_in_order_and_hunts_for_the_high_limit() {
    let mut r = rig(1);
    r.streaming(Duration::from_secs(3));
    let heard = r.line.device.heard().to_vec();
    let head = [
        "R",
        "f",
        "Z0",
        "O178",
        ":",
        "l",
        "Pfoundlimit,1,1",
        "A",
        "X",
        "P",
        "i2,0,0,0,1024,0,0,0,1,1,1,1",
        "M3200,3200,600,1000,20000,50000,145,0,145,145,50,8",
        "o",
    ];
    // The drive is deaf for 30 ms after R: the first f or two are lost.
    let fs = heard[1..].iter().take_while(|c| *c == "f").count();
    assert!((1..=3).contains(&fs), "{heard:?}");
    let heard_once: Vec<&str> = heard
        .iter()
        .enumerate()
        .filter(|&(i, _)| !(i > 1 && i < 1 + fs))
        .map(|(_, c)| c.as_str())
        .collect();
    assert_eq!(heard_once[..head.len()], head, "{heard:?}");
    // Moves of 50 steps from 0 until the rail at 150 steps closes input 1: to 50, 100, 150;
    // each followed by `o` until it stops, then `l` and `:`.
    let moves: Vec<&str> = heard_once
        .iter()
        .filter(|c| c.starts_with('M'))
        .map(|c| &c[..c.find(',').unwrap()])
        .collect();
    assert_eq!(moves, ["M3200", "M6400", "M9600"]);
    let tail = &heard_once[heard_once.len() - 3..];
    assert_eq!(tail, [":", "Z-3840", "l"], "{heard:?}");
    assert_eq!(r.line.device.outputs(), 0b0010);
    assert!(r.has_text("reset complete"));
    // The first report: -60 steps, the hunt's moves unreported.
    let h = r.positions.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(1), |_| !h.borrow().is_empty()));
    assert_eq!(r.positions.borrow()[0].0, -60.0);
}

#[test]
fn cxx_sample_line_resets_without_moving() {
    let mut r = rig_with(PLAIN, logged(), 2);
    r.streaming(Duration::from_secs(2));
    assert_eq!(r.line.device.moves(), 0);
    let heard = r.line.device.heard();
    assert!(heard.iter().any(|c| c == "O240"), "{heard:?}");
    assert!(heard.iter().any(|c| c == "Z-3840"));
    // Reset in well under C++'s 350 ms of sleeps.
    let done = r.line.written.last().unwrap().0 - r.start.mono;
    assert!(done < Duration::from_millis(200), "{done:?}");
}

#[test]
fn moves_are_seen_as_they_go_and_reported_exactly() {
    let mut r = rig(3);
    r.line.split_reads = true;
    r.streaming(Duration::from_secs(3));
    let from = r.positions.borrow().len();
    let after = r.line.device.positions().len();
    for k in 0..10 {
        r.move_to(-100.0 - f64::from(k * 37 % 200));
    }
    // 3200 steps/s: a move of 100 steps takes 31 ms and is seen on its way.
    assert!(r.positions.borrow().len() - from > 30);
    r.check_positions(from, after);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes the reset's answers and the stream's together:
    // the reset ends, and every change of position and input is still reported in order.
    let mut r = rig(4);
    r.line.read_lag = Duration::from_millis(12);
    r.streaming(Duration::from_secs(5));
    let from = r.positions.borrow().len();
    let after = r.line.device.positions().len();
    for k in 0..8 {
        r.move_to(-80.0 - f64::from(k * 53 % 300));
    }
    r.line.device.set_inputs(0b0110);
    r.line.run_for(Duration::from_millis(200));
    r.check_positions(from, after);
    let b = r.buttons.borrow();
    assert!(b.iter().any(|c| c.0 == (1, true)) && b.iter().any(|c| c.0 == (2, true)));
}

#[test]
fn inputs_are_buttons_and_limits_are_kept() {
    let mut r = rig(5);
    r.streaming(Duration::from_secs(3));
    r.line.run_for(Duration::from_millis(100));
    // At the rail: input 1 is closed.
    assert_eq!(r.buttons.borrow()[0].0, (0, true));
    let n = r.buttons.borrow().len();
    r.line.device.set_inputs(0b1000);
    r.line.run_for(Duration::from_millis(50));
    assert_eq!(r.buttons.borrow()[n].0, (3, true));
    // Forward into the closed high limit: refused.
    let moves = r.line.device.moves();
    r.out.request_change_channel_value(0, 100.0).unwrap();
    r.line.run_for(Duration::from_millis(100));
    assert!(r.has_text("Asked to move into limit"));
    assert_eq!(r.line.device.moves(), moves);
    // Back, then forward again: the motor stops at the rail and the limit is warned of.
    r.move_to(-200.0);
    assert_eq!(r.buttons.borrow().last().unwrap().0, (0, false));
    r.out.request_change_channel_value(0, 500.0).unwrap();
    let h = r.positions.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(2), |_| h.borrow().last().unwrap().0
            == -60.0));
    r.line.run_for(Duration::from_millis(50));
    assert!(r.has_text("Encountered high limit"));
    assert_eq!(r.buttons.borrow().last().unwrap().0, (0, true));
}

#[test]
fn a_fault_fails_the_reset_until_it_clears() {
    let mut r = rig(6);
    r.line.device.set_fault(3);
    r.line.run_for(Duration::from_millis(2500));
    assert!(r.has_text("Drive reports a fault"));
    assert!(r.line.driver.stats().reset_attempts >= 2);
    assert!(!r.line.driver.is_streaming());
    r.line.device.set_fault(0);
    r.streaming(Duration::from_secs(3));
}

#[test]
fn a_silent_drive_is_reset_and_streams_again() {
    let mut r = rig(7);
    r.streaming(Duration::from_secs(3));
    r.move_to(-90.0);
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(2600));
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    assert!(r.has_text("Timeout, resetting"));
    r.line.silent = false;
    r.streaming(Duration::from_secs(4));
    let (from, after) = (r.positions.borrow().len(), r.line.device.positions().len());
    r.move_to(-70.0);
    r.move_to(-170.0);
    r.check_positions(from, after);
    assert_eq!(r.line.driver.stats().opens, 1, "reset on the open port");
}

#[test]
fn garbage_costs_no_answer_and_a_lost_answer_is_asked_again() {
    let mut r = rig(8);
    r.streaming(Duration::from_secs(3));
    let (from, after) = (r.positions.borrow().len(), r.line.device.positions().len());
    for (k, junk) in [&b"zz"[..], b"`", b"`l12\r`x", b"\r\n"].iter().enumerate() {
        let now = r.line.now().mono;
        r.line.device.inject(junk, now);
        r.move_to(-100.0 - k as f64 * 10.0);
    }
    r.check_positions(from, after);
    assert!(r.line.driver.stats().skipped_bytes >= 10);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_IDEA\tAnalog0\tCOM1 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 0 0 0 0 0 1.0 -60.0\n\
                vrpn_IDEA Analog1 /dev/ttyUSB1 3200 1200 2000 40000 100000 290 0 290 290 50 8 -1 -1 0 0 0 0 10000 0.2 -60.0\n\
                vrpn_IDEA Analog2 /dev/ttyUSB2 1 2 3 4 5 6 7 8 9 10 4 4 2 -1 1 -5 1 -2.5e3 1 0\n";
    let entries = parse_str(text, "idea.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["Analog0", "Analog1", "Analog2"]);
    let c: Idea = parse_one(&text.lines().nth(2).unwrap().replace('\t', " "));
    assert_eq!((c.high_limit, c.low_limit), (Some(4), Some(2)));
    assert_eq!(c.outputs, [None, Some(true), None, Some(true)]);
    assert_eq!(c.initial_move, -2500.0);
    assert_eq!(c.motion.step, 4);
    for (bad, what) in [
        ("vrpn_IDEA i0 COM1 3200 1200\n", "22"),
        (
            "vrpn_IDEA i0 COM1 3200 1200 2000 40000 100000 290 0 290 290 50 8 5 -1 0 0 0 0 0 1 0\n",
            "high_limit_index",
        ),
        (
            "vrpn_IDEA i0 COM1 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 0 0 0 0 0 x 0\n",
            "fractional_c_a",
        ),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.cfg") && e.contains(":2"), "{e}");
        assert!(e.contains(what) || what == "22", "{e}");
    }
}
