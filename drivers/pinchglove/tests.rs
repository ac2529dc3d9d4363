//! The Pinch Glove driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: the reset, exact changes and stamps, time stamps switched
//! on behind its back, garbage, the idle probe, a reopen, configurations.

use std::time::{Duration, Instant};

use super::config::PinchGlove;
use super::sim::{expected_changes, PinchSim, SimConfig};
use super::{PinchGloveProtocol, IDLE_PROBE, PROBE_TIMEOUT, TIME_STAMPS_OFF};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::{DeviceModel, VirtualLine};
use crate::{Connection, Now, TimeVal};

const LINE: &str = "vrpn_Button_PinchGlove PinchGlove0 /dev/ttyS0 9600\n";

struct Rig {
    line: VirtualLine<Lifecycle<PinchGloveProtocol>, PinchSim>,
    start: Now,
    client: Client,
    _conn: Connection,
}

fn rig(seed: u64, tweak: impl FnOnce(&mut SimConfig)) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: PinchGlove = parse_one(LINE);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection(&cfg.name, &conn, &[Interface::Button]).unwrap();
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, PinchSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        _conn: conn,
    }
}

impl Rig {
    /// Button changes heard from log index `from`: (button, pressed, time).
    fn changes_from(&self, from: usize) -> Vec<(usize, bool, TimeVal)> {
        self.client.heard()[from..]
            .iter()
            .filter_map(|h| match h {
                Heard::Button {
                    button,
                    pressed,
                    time,
                } => Some((*button, *pressed, *time)),
                _ => None,
            })
            .collect()
    }

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.client.texts_from(0);
        t.iter().filter(|t| t.contains(needle)).count()
    }

    fn arrival_wall(&self, t: Instant) -> TimeVal {
        self.start
            .wall
            .plus(t + self.line.latency - self.start.mono)
    }

    /// Every change heard is what the log says a client receives, in order, each stamped
    /// with the arrival of its message's first byte (at most one message still on the line).
    fn assert_exact(&self) {
        let sent = self.line.device.sent();
        let want = expected_changes(sent);
        let got = self.changes_from(0);
        assert!(got.len() >= 20, "{} changes", got.len());
        let last_msg = want[got.len() - 1].0;
        assert!(last_msg + 2 >= sent.len(), "{last_msg} of {}", sent.len());
        for (g, w) in got.iter().zip(&want) {
            assert_eq!((g.0, g.1), (w.1, w.2), "{w:?}");
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(g.2, self.arrival_wall(sent[w.0].first_byte), "{w:?}");
            }
        }
        assert!(
            want.get(got.len()).map_or(true, |w| w.0 > last_msg),
            "a message reported in part"
        );
    }

    fn writes(&self) -> Vec<Vec<u8>> {
        self.line.written.iter().map(|(_, w)| w.clone()).collect()
    }
}

/// Runs `line` in 1 ms steps until `done` holds (at most `max`); returns whether it held.
fn run_in_steps<D: SerialDriver, M: crate::sim::DeviceModel>(
    line: &mut VirtualLine<D, M>,
    max: Duration,
    mut done: impl FnMut(&VirtualLine<D, M>) -> bool,
) -> bool {
    let end = line.now().mono + max;
    while line.now().mono < end {
        if done(line) {
            return true;
        }
        line.run_for(Duration::from_millis(1));
    }
    done(line)
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several messages at once (the first with the
    // answer that ends the reset): every change is reported, from the first.
    let mut r = rig(21, |_| {});
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(4));
    assert!(r.line.driver.is_streaming());
    r.assert_exact();
}

#[test]
fn port_settings_and_ten_buttons() {
    let r = rig(1, |_| {});
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    assert_eq!(r.line.driver.protocol().buttons().num_buttons(), 10);
}

#[test]
fn reset_then_exact_changes_and_stamps() {
    let mut r = rig(2, |_| {});
    assert!(run_in_steps(&mut r.line, Duration::from_secs(1), |l| l
        .driver
        .is_streaming()));
    // T0 and its 3-byte answer 3 ms later: streaming within 10 ms (C++ also needs one answer,
    // but blocks the server until it comes).
    assert!(r.line.now().mono - r.start.mono < Duration::from_millis(10));
    assert_eq!(r.writes(), vec![TIME_STAMPS_OFF.to_vec()]);
    r.line.run_for(Duration::from_secs(4));
    r.assert_exact();
    // Every button was pressed and released.
    let got = r.changes_from(0);
    for b in 0..10 {
        assert!(got.iter().any(|c| c.0 == b && c.1) && got.iter().any(|c| c.0 == b && !c.1));
    }
    // Messages every 80 ms: the idle probe never ran.
    assert_eq!(r.line.driver.protocol().probes(), 0);
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
}

#[test]
fn time_stamps_are_switched_off_at_start_and_when_switched_on() {
    let mut r = rig(3, |s| s.time_stamps_at_start = true);
    r.line.run_for(Duration::from_millis(500));
    assert!(!r.line.device.time_stamps());
    assert_eq!(r.texts_with("time stamped"), 0);
    // Someone switches them on: the next message is reported and the glove reset.
    let now = r.line.now();
    r.line.device.receive(b"T1", now);
    r.line.run_for(Duration::from_secs(3));
    assert_eq!(r.texts_with("time stamped byte"), 1);
    assert!(!r.line.device.time_stamps());
    assert_eq!(r.line.driver.stats().resets, 2);
    r.assert_exact();
}

#[test]
fn garbage_and_damaged_messages_lose_nothing_else() {
    let mut r = rig(4, |_| {});
    r.line.run_for(Duration::from_millis(300));
    let junk: [&[u8]; 5] = [
        &[0x33, 0x44],
        &[0x8F],
        &[0x80, 0x10],
        &[0x85, 0x20, 0x8F],
        &[0x80, 0x10, 0x40],
    ];
    for j in junk {
        // Between messages: 20 ms after one started (it takes 3-6 ms at 9600 baud).
        assert!(run_in_steps(&mut r.line, Duration::from_secs(1), |l| {
            l.device.sent().last().is_some_and(|s| {
                let since = l.now().mono - s.first_byte;
                since > Duration::from_millis(20) && since < Duration::from_millis(30)
            })
        }));
        let now = r.line.now().mono;
        r.line.device.inject(j, now);
        r.line.run_for(Duration::from_millis(100));
    }
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 2 + 1 + 2 + 3);
    assert!(r.texts_with("skipped") >= 1);
    assert_eq!(r.texts_with("wrong message start byte (0x85)"), 1);
}

#[test]
fn a_silent_glove_is_probed_reset_and_resumes() {
    let mut r = rig(5, |_| {});
    r.line.run_for(Duration::from_millis(500));
    r.line.device.mute = true;
    let muted = r.line.now().mono;
    // The probe goes out 2 s after the last byte, the reset 1 s later.
    assert!(r
        .line
        .run_until(Duration::from_secs(4), |l| !l.driver.is_streaming()));
    let t0s_after: Vec<Instant> = r
        .line
        .written
        .iter()
        .filter(|(t, w)| *t > muted && w.as_slice() == TIME_STAMPS_OFF)
        .map(|(t, _)| *t)
        .collect();
    // The probe, then the reset's first T0.
    let reset_at = t0s_after[1] - muted;
    assert!(
        reset_at > IDLE_PROBE + PROBE_TIMEOUT - Duration::from_millis(100)
            && reset_at <= IDLE_PROBE + PROBE_TIMEOUT,
        "{reset_at:?}"
    );
    assert_eq!(r.line.driver.protocol().probes(), 1);
    assert_eq!(r.texts_with("no answer to a T0 probe"), 1);
    // Still silent: T0 is repeated every ANSWER_LIMIT, with one warning.
    r.line.run_for(Duration::from_millis(1050));
    let t0s = r
        .writes()
        .iter()
        .filter(|w| w.as_slice() == TIME_STAMPS_OFF)
        .count();
    assert!(t0s >= 11, "{t0s}");
    assert_eq!(r.texts_with("no answer to T0 (attempt 1;"), 1);
    let n = r.changes_from(0).len();
    r.line.device.mute = false;
    assert!(r
        .line
        .run_until(Duration::from_millis(200), |l| l.driver.is_streaming()));
    r.line.run_for(Duration::from_secs(1));
    assert!(r.changes_from(0).len() > n);
    r.assert_exact();
    assert_eq!(r.texts_with("answered after"), 1);
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(6, |_| {});
    r.line.run_for(Duration::from_millis(500));
    let n = r.client.len();
    r.line.close();
    r.line.run_for(Duration::from_millis(400));
    assert_eq!(
        r.changes_from(n).len(),
        0,
        "nothing while the port is closed"
    );
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.line.run_for(Duration::from_secs(1));
    assert!(r.changes_from(n).len() > 5);
    assert_eq!(r.line.driver.stats().resets, 2);
    let t0s = r
        .writes()
        .iter()
        .filter(|w| w.as_slice() == TIME_STAMPS_OFF)
        .count();
    assert_eq!(t0s, 2);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Button_PinchGlove\tPinchGlove0\t\tCOM1\t\t9600\n\
                vrpn_Button_PinchGlove Glove1 /dev/ttyS1 19200\n";
    let entries = parse_str(text, "pinch.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["PinchGlove0", "Glove1"]);
    for (bad, why) in [
        ("vrpn_Button_PinchGlove G /dev/ttyS0\n", "baud"),
        ("vrpn_Button_PinchGlove G /dev/ttyS0 9601\n", "9601"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
