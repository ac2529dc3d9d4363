//! The UNC joystick driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: the reset, exact values and stamps, the minimum update
//! rate, garbage, a failed reset, a reopen, configurations.

use std::time::{Duration, Instant};

use super::config::UncJoystick;
use super::sim::{expected, JoystickSim, Report, SimConfig};
use super::{UncJoystickProtocol, ANSWER_LIMIT, REQUEST_ALL, REQUEST_CHANGES};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINE: &str = "vrpn_Joystick Joybox0 /dev/ttyd1 19200 10.0\n";

struct Rig {
    line: VirtualLine<Lifecycle<UncJoystickProtocol>, JoystickSim>,
    start: Now,
    client: Client,
    _conn: Connection,
}

fn rig(text: &str, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: UncJoystick = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client =
        Client::on_connection(&cfg.name, &conn, &[Interface::Analog, Interface::Button]).unwrap();
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, JoystickSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        _conn: conn,
    }
}

fn report(h: &Heard) -> Option<(Report, TimeVal)> {
    match h {
        Heard::Button {
            button,
            pressed,
            time,
        } => Some((Report::Button(*button, *pressed), *time)),
        Heard::Analog { channels, time } => {
            let mut c = [0.0; 7];
            c.copy_from_slice(&channels[..7]);
            Some((Report::Analog(c), *time))
        }
        _ => None,
    }
}

impl Rig {
    fn heard_from(&self, from: usize) -> Vec<(Report, TimeVal)> {
        self.client.heard()[from..]
            .iter()
            .filter_map(report)
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

    /// What was heard, without the repeats of the minimum update rate (an analog report equal
    /// to the one before), is exactly what the log says, stamped with first-byte arrivals.
    fn assert_exact(&self) {
        let sent = self.line.device.sent();
        let want = expected(sent);
        let mut got = self.heard_from(0);
        let mut last = None;
        got.retain(|(r, _)| match r {
            Report::Analog(a) => {
                let new = last != Some(*a);
                last = Some(*a);
                new
            }
            Report::Button(..) => true,
        });
        let mut want_dedup = Vec::new();
        let mut last = None;
        for w in want {
            if let Report::Analog(a) = w.0 {
                if last == Some(a) {
                    continue;
                }
                last = Some(a);
            }
            want_dedup.push(w);
        }
        assert!(got.len() >= 20, "{} reports", got.len());
        assert!(want_dedup.len() - got.len() <= 2);
        for (g, w) in got.iter().zip(&want_dedup) {
            assert_eq!(g.0, w.0);
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(g.1, self.arrival_wall(sent[w.1].first_byte), "{w:?}");
            }
        }
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several records at once (the last answer to
    // the reset with the first changes): every report is made, from the first.
    let mut r = rig(LINE, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(3));
    assert!(r.line.driver.is_streaming());
    r.assert_exact();
}

#[test]
fn port_settings_and_counts() {
    let r = rig(LINE, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(19200))
    );
    assert_eq!(r.line.driver.protocol().analog().num_channels(), 7);
    assert_eq!(r.line.driver.protocol().buttons().num_buttons(), 2);
}

#[test]
fn reset_learns_rest_positions_then_changes_arrive_exactly() {
    let mut r = rig(LINE, 2);
    assert!(r
        .line
        .run_until(Duration::from_secs(1), |l| l.driver.is_streaming()));
    // The 16-byte answer at 19200 baud (8.3 ms) after 2 ms: `j` within 12 ms instead of
    // after C++'s 1 s sleep.
    let startup = r.line.written[1].0 - r.start.mono;
    assert!(startup < Duration::from_millis(12), "{startup:?}");
    assert_eq!(
        r.line.device.heard(),
        [REQUEST_ALL, REQUEST_CHANGES].concat()
    );
    assert_eq!(
        r.line.driver.protocol().rest(),
        [512, 503, 506, 509, 512, 515, 518]
    );
    // The rest state is reported at once: the sticks at zero, the slider where it is.
    let first = r.heard_from(0);
    assert_eq!(
        first.last().unwrap().0,
        Report::Analog([-(212.0f64 / 1019.0), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    );
    r.line.run_for(Duration::from_secs(3));
    r.assert_exact();
    // A change every 20 ms, faster than the 10 Hz minimum rate: nothing repeated.
    assert_eq!(r.line.driver.protocol().repeats(), 0);
    for b in 0..2 {
        for p in [true, false] {
            assert!(r
                .heard_from(0)
                .iter()
                .any(|(rep, _)| *rep == Report::Button(b, p)));
        }
    }
}

#[test]
fn a_quiet_box_is_reported_at_the_minimum_rate_and_nothing_else() {
    let mut r = rig(LINE, 3);
    r.line.run_for(Duration::from_millis(500));
    r.line.device.mute = true;
    let n = r.client.len();
    let muted = r.line.now();
    r.line.run_for(Duration::from_secs(2));
    let quiet = r.heard_from(n);
    // 10 a second, each the same analog state, stamped when it is sent: no button reports.
    assert!((19..=21).contains(&quiet.len()), "{}", quiet.len());
    let first = quiet[0].0;
    assert!(quiet.iter().all(|(rep, _)| *rep == first));
    for w in quiet.windows(2) {
        let gap = w[1].1.seconds_since(w[0].1);
        assert!((gap - 0.1).abs() < 1e-6, "{gap}");
    }
    assert!(quiet[0].1.seconds_since(muted.wall) <= 0.1);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    r.line.device.mute = false;
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
}

#[test]
fn no_repeats_with_a_zero_rate() {
    let mut r = rig("vrpn_Joystick J /dev/ttyS0 9600 0\n", 4);
    r.line.run_for(Duration::from_millis(300));
    r.line.device.mute = true;
    let n = r.client.len();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.heard_from(n).len(), 0);
    assert_eq!(r.line.driver.protocol().repeats(), 0);
}

#[test]
fn garbage_costs_no_record() {
    let mut r = rig(LINE, 5);
    r.line.run_for(Duration::from_millis(300));
    for j in [&[0x85u8, 0xFF][..], &[0x12, 0x13], &[0x44]] {
        // Between records (two bytes take 1 ms at 19200 baud; one every 20 ms).
        assert!(r.line.run_until(Duration::from_secs(1), |l| {
            l.device.sent().last().is_some_and(|s| {
                let since = l.now().mono - s.first_byte;
                since > Duration::from_millis(5) && since < Duration::from_millis(15)
            })
        }));
        let now = r.line.now().mono;
        r.line.device.inject(j, now);
        r.line.run_for(Duration::from_millis(100));
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_exact();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 5);
    assert!(r.texts_with("skipped") >= 1);
}

#[test]
fn an_unanswered_reset_is_retried_every_second() {
    let mut r = rig(LINE, 6);
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(3500));
    let requests: Vec<Instant> = r
        .line
        .written
        .iter()
        .filter(|(_, w)| w.as_slice() == REQUEST_ALL)
        .map(|(t, _)| *t)
        .collect();
    assert_eq!(requests.len(), 4);
    for w in requests.windows(2) {
        assert_eq!(w[1] - w[0], ANSWER_LIMIT);
    }
    assert_eq!(r.texts_with("got only 0 of 16 bytes"), 3);
    assert!(r.heard_from(0).is_empty(), "nothing invented");
    r.line.device.mute = false;
    assert!(r
        .line
        .run_until(Duration::from_millis(1100), |l| l.driver.is_streaming()));
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(LINE, 7);
    r.line.run_for(Duration::from_millis(500));
    r.line.close();
    let n = r.client.len();
    r.line.run_for(Duration::from_millis(400));
    assert_eq!(r.heard_from(n).len(), 0, "nothing while closed");
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.driver.stats().resets, 2);
    assert!(r.heard_from(n).len() > 20);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Joystick Joybox0 /dev/ttyd1 19200 10.0\n\
                vrpn_Joystick\tJ1\tCOM1\t9600\t0\n";
    let entries = parse_str(text, "joy.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["Joybox0", "J1"]);
    for (bad, why) in [
        ("vrpn_Joystick J /dev/ttyS0 19200\n", "minimum update rate"),
        ("vrpn_Joystick J /dev/ttyS0 19201 10\n", "19201"),
        ("vrpn_Joystick J /dev/ttyS0 19200 -1\n", "0 or more"),
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
