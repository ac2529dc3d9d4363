//! The Immersion box driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: the reset's bytes and timing, exact changes and stamps,
//! garbage, the watchdog, a reopen, configurations.

use std::time::{Duration, Instant};

use super::config::ImmersionBox;
use super::reset::{configure_command, BEGIN, END_SESSION, IDENT_COMMANDS, SYNC};
use super::sim::{expected_changes, IboxSim, SimConfig, IDENT};
use super::{ImmersionBoxProtocol, WATCHDOG};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINE: &str = "vrpn_ImmersionBox ibox /dev/ttyd2 38400 4 0 0\n";

struct Rig {
    line: VirtualLine<Lifecycle<ImmersionBoxProtocol>, IboxSim>,
    start: Now,
    client: Client,
    buttons: usize,
    /// The button byte the log's first record is compared with.
    initial: u8,
    _conn: Connection,
}

fn rig(text: &str, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: ImmersionBox = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection(
        &cfg.name,
        &conn,
        &[Interface::Button, Interface::Analog, Interface::Dial],
    )
    .unwrap();
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, IboxSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        buttons: cfg.buttons as usize,
        initial: 0,
        _conn: conn,
    }
}

impl Rig {
    fn changes(&self) -> Vec<(usize, bool, TimeVal)> {
        self.client
            .heard()
            .iter()
            .filter_map(|h| match h {
                Heard::Button {
                    button,
                    pressed,
                    time,
                } => Some((*button, *pressed, *time)),
                Heard::Analog { .. } | Heard::Dial { .. } => panic!("{h:?}"),
                _ => None,
            })
            .collect()
    }

    /// Forgets what was sent and heard; later records are compared with the driver's state.
    fn forget(&mut self) {
        self.line.device.clear_log();
        self.client.clear();
        let b = self.line.driver.protocol().buttons();
        self.initial = (0..self.buttons)
            .filter(|&i| b.button(i).is_pressed())
            .fold(0, |acc, i| acc | 1 << i);
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

    fn assert_exact(&self) {
        let sent = self.line.device.sent();
        let want = expected_changes(sent, self.buttons, self.initial);
        let got = self.changes();
        assert!(got.len() >= 20, "{} changes", got.len());
        assert!(
            want.len() - got.len() <= 2,
            "{} of {}",
            got.len(),
            want.len()
        );
        for (g, w) in got.iter().zip(&want) {
            assert_eq!((g.0, g.1), (w.1, w.2), "{w:?}");
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(g.2, self.arrival_wall(sent[w.0].first_byte), "{w:?}");
            }
        }
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
    // A loaded machine reads late and takes several answers or records at once (the first
    // records with the echo that ends the reset): every change is reported, from the first.
    let mut r = rig(LINE, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(2));
    assert!(r.line.driver.is_streaming());
    r.assert_exact();
}

#[test]
fn port_settings_and_servers() {
    let r = rig("vrpn_ImmersionBox ibox com1 115200 7 8 6\n", 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(115200))
    );
    let p = r.line.driver.protocol();
    assert_eq!(p.buttons().num_buttons(), 7);
    assert_eq!(p.analog().num_channels(), 8);
    assert_eq!(p.dials().num_dials(), 6);
}

#[test]
fn reset_sends_cplusplus_commands_and_ends_at_the_echo() {
    let mut r = rig(LINE, 2);
    assert!(run_in_steps(&mut r.line, Duration::from_secs(2), |l| l
        .driver
        .is_streaming()));
    let startup = r.line.now().mono - r.start.mono;
    // 10 ms after E, then nine short answers at 38400 baud: well under C++'s 0.85 s.
    assert!(startup < Duration::from_millis(50), "{startup:?}");
    let mut want: Vec<u8> = [END_SESSION, SYNC, BEGIN].concat();
    want.extend(IDENT_COMMANDS);
    want.extend(configure_command(0));
    assert_eq!(r.line.device.heard(), want.as_slice());
    let ident = r.line.driver.protocol().ident();
    for (t, want) in ident.iter().zip(IDENT) {
        assert_eq!(t.bytes(), want.as_bytes());
    }
    assert_eq!(r.texts_with("vrpn_ImmersionBox found: name IBOX-SIM"), 1);
    assert_eq!(r.texts_with("version 1.07"), 1);
    r.line.run_for(Duration::from_secs(2));
    r.assert_exact();
    // Every button went down and up; the analogs and dials never report (see the docs).
    for b in 0..4 {
        assert!(r.changes().iter().any(|c| c.0 == b && c.1));
        assert!(r.changes().iter().any(|c| c.0 == b && !c.1));
    }
}

#[test]
fn every_count_reads_records_of_its_length() {
    for (line, header) in [
        ("vrpn_ImmersionBox b /dev/ttyS0 9600 7 2 1\n", 0x85u8),
        ("vrpn_ImmersionBox b /dev/ttyS0 9600 3 4 3\n", 0x8A),
        ("vrpn_ImmersionBox b /dev/ttyS0 19200 5 8 4\n", 0x8F),
        ("vrpn_ImmersionBox b /dev/ttyS0 19200 2 0 6\n", 0x83),
    ] {
        let mut r = rig(line, 3);
        r.line.run_for(Duration::from_secs(2));
        assert_eq!(
            r.line.device.heard()[r.line.device.heard().len() - 22],
            header & 0x7F
        );
        r.assert_exact();
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0, "{line}");
    }
}

#[test]
fn garbage_costs_no_record() {
    let mut r = rig(LINE, 4);
    r.line.run_for(Duration::from_millis(300));
    for j in [&[0x01u8, 0x7F][..], &[0xC0], &[0x55, 0x81, 0x22]] {
        assert!(run_in_steps(&mut r.line, Duration::from_secs(1), |l| {
            l.device.sent().last().is_some_and(|s| {
                let since = l.now().mono - s.first_byte;
                since > Duration::from_millis(3) && since < Duration::from_millis(8)
            })
        }));
        let now = r.line.now().mono;
        r.line.device.inject(j, now);
        r.line.run_for(Duration::from_millis(50));
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_exact();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 6);
    assert!(r.texts_with("skipped") >= 1);
}

#[test]
fn a_silent_box_is_reset_after_two_seconds_and_resumes() {
    let mut r = rig(LINE, 5);
    r.line.run_for(Duration::from_millis(500));
    r.line.device.mute = true;
    let muted = r.line.now().mono;
    assert!(r
        .line
        .run_until(Duration::from_secs(3), |l| !l.driver.is_streaming()));
    let fired = r
        .line
        .written
        .iter()
        .find(|(t, w)| *t > muted && w.as_slice() == END_SESSION)
        .unwrap()
        .0
        - muted;
    assert!(
        fired > WATCHDOG - Duration::from_millis(15) && fired <= WATCHDOG,
        "{fired:?}"
    );
    assert_eq!(r.texts_with("Too long since last report, resetting"), 1);
    // Reset on the open port (no reopen), and the sync string repeated while it is silent.
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.opens, 1);
    let syncs = r
        .line
        .written
        .iter()
        .filter(|(_, w)| w.as_slice() == SYNC)
        .count();
    assert!(syncs >= 10, "{syncs}");
    r.line.device.mute = false;
    assert!(run_in_steps(&mut r.line, Duration::from_secs(1), |l| l
        .driver
        .is_streaming()));
    // Records the box sent while the driver was resetting are not reported: compare from
    // here on (a moment between records).
    assert!(run_in_steps(&mut r.line, Duration::from_secs(1), |l| {
        let now = l.now().mono;
        l.device.sent().last().is_some_and(|s| {
            now - s.first_byte > Duration::from_millis(2)
                && now - s.first_byte < Duration::from_millis(8)
        })
    }));
    r.forget();
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
}

#[test]
fn a_box_that_never_synchronises_fails_after_ten_seconds() {
    let mut r = rig(LINE, 6);
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(10_500));
    assert_eq!(r.texts_with("no echo of IMMC within 10 s"), 1);
    assert!(r.changes().is_empty());
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(LINE, 7);
    r.line.run_for(Duration::from_millis(500));
    r.line.close();
    let n = r.changes().len();
    r.line.run_for(Duration::from_millis(300));
    assert_eq!(r.changes().len(), n, "nothing while closed");
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.driver.stats().resets, 2);
    assert!(r.changes().len() > n + 20);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_ImmersionBox      ibox    /dev/ttyd2      38400   4 0 0\n\
                vrpn_ImmersionBox      ibox1   com1            115200  4 0 0\n\
                vrpn_ImmersionBox      ibox2   /dev/ttyS1      9600    7 8 6\n";
    let entries = parse_str(text, "ibox.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["ibox", "ibox1", "ibox2"]);
    for (bad, why) in [
        ("vrpn_ImmersionBox b /dev/ttyS0 9600 4 0\n", "encoders"),
        ("vrpn_ImmersionBox b /dev/ttyS0 9600 8 0 0\n", "buttons"),
        ("vrpn_ImmersionBox b /dev/ttyS0 9600 4 9 0\n", "analogs"),
        ("vrpn_ImmersionBox b /dev/ttyS0 9600 4 0 7\n", "encoders"),
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
