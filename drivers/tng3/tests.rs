//! The TNG-3 driver against its simulator on a virtual serial line, with a client on the same
//! in-process connection: finding the step, exact values and stamps, garbage, the watchdog, a
//! reopen, configurations.

use std::time::{Duration, Instant};

use super::config::Tng3;
use super::sim::{expected, Report, SimConfig, Tng3Sim};
use super::{Tng3Protocol, SYNC_LIMIT};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINE: &str = "vrpn_Tng3 tng3name /dev/ttyS0 8 8\n";

struct Rig {
    line: VirtualLine<Lifecycle<Tng3Protocol>, Tng3Sim>,
    start: Now,
    client: Client,
    counts: (usize, usize),
    _conn: Connection,
}

fn rig(text: &str, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Tng3 = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client =
        Client::on_connection(&cfg.name, &conn, &[Interface::Analog, Interface::Button]).unwrap();
    let mut sim = SimConfig::new();
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, Tng3Sim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        counts: (cfg.analogs as usize, cfg.buttons as usize),
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
        Heard::Analog { channels, time } => Some((Report::Analog(channels.clone()), *time)),
        _ => None,
    }
}

impl Rig {
    fn heard(&self) -> Vec<(Report, TimeVal)> {
        self.client.heard().iter().filter_map(report).collect()
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

    /// What was heard is exactly what the records logged from record `from` on say (the
    /// ones before it were sent before the driver looked), stamped with their start bytes.
    fn assert_exact_from(&self, from: usize) {
        let sent = &self.line.device.sent()[from..];
        let want = expected(sent, self.counts.0, self.counts.1);
        let got = self.heard();
        assert!(got.len() >= 20, "{} reports", got.len());
        assert!(
            want.len() - got.len() <= 2 + self.counts.1,
            "{} of {}",
            got.len(),
            want.len()
        );
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.0, w.0, "{w:?}");
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(g.1, self.arrival_wall(sent[w.1].first_byte), "{w:?}");
            }
        }
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several records at once (the first ends the
    // reset): every record is reported, from the first.
    let mut r = rig(LINE, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(3));
    assert!(r.line.driver.is_streaming());
    r.assert_exact_from(0);
}

#[test]
fn port_settings_and_counts() {
    let r = rig("vrpn_Tng3 t com1 1 1\n", 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(19200))
    );
    assert_eq!(r.line.driver.protocol().analog().num_channels(), 1);
    assert_eq!(r.line.driver.protocol().buttons().num_buttons(), 1);
}

#[test]
fn finds_the_step_then_every_record_arrives_exactly() {
    for (seed, line) in [(2, LINE), (3, "vrpn_Tng3 tng3name /dev/ttyd2 4 0\n")] {
        let mut r = rig(line, seed);
        r.line.run_for(Duration::from_secs(3));
        // The first record is confirmed by the second's start byte: 20 ms.
        assert!(r.line.driver.is_streaming());
        assert_eq!(r.line.written, Vec::new(), "the box takes no commands");
        r.assert_exact_from(0);
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    }
}

#[test]
fn garbage_costs_no_record() {
    let mut r = rig(LINE, 4);
    r.line.run_for(Duration::from_millis(300));
    // Noise, start bytes among it, a whole false record. The false record starts with the
    // start byte the box just sent, not the one due next: in step, a record that starts with
    // the expected byte is taken at its tenth byte (the protocol has no check to tell it from
    // a real one; docs/DRIVERS.md says so).
    let mut false_record = [0u8, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0x33];
    let junk: [&[u8]; 2] = [&[0x01, 0x02], &[0x55, 0x13, 0xAA]];
    for j in junk.iter().copied().chain([&[][..]]) {
        r.line.run_for(Duration::from_millis(95));
        let n = r.line.device.sent().len();
        assert!(r
            .line
            .run_until(Duration::from_secs(1), |l| l.device.sent().len() > n));
        // Between records: 10 bytes take 5.2 ms, one every 20 ms.
        r.line.run_for(Duration::from_millis(8));
        let now = r.line.now().mono;
        if j.is_empty() {
            let last = r.line.device.sent().last().unwrap().k;
            false_record[0] = if last % 2 == 0 { 0x55 } else { 0xAA };
            r.line.device.inject(&false_record, now);
        } else {
            r.line.device.inject(j, now);
        }
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_exact_from(0);
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 2 + 3 + 11);
    assert!(r.texts_with("out of step") >= 1);
}

#[test]
fn a_silent_box_is_looked_for_again_and_resumes() {
    let mut r = rig(LINE, 5);
    r.line.run_for(Duration::from_millis(500));
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(2100));
    assert_eq!(r.texts_with("Too long since last report, resetting"), 1);
    assert!(!r.line.driver.is_streaming());
    r.line.run_for(SYNC_LIMIT);
    assert_eq!(r.texts_with("syncDatastream timeout expired"), 1);
    r.line.device.mute = false;
    r.line.run_for(Duration::from_secs(1));
    assert!(r.line.driver.is_streaming());
    r.assert_exact_from(0);
    assert_eq!(r.line.opens, 1, "no reopen");
}

#[test]
fn a_closed_port_is_reopened_and_the_step_found_again() {
    let mut r = rig(LINE, 6);
    r.line.run_for(Duration::from_millis(500));
    r.line.close();
    let n = r.heard().len();
    r.line.run_for(Duration::from_millis(400));
    assert_eq!(r.heard().len(), n, "nothing while closed");
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.driver.stats().resets, 2);
    assert!(r.heard().len() > n + 40);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Tng3      tng3name    /dev/ttyd2  4 0\n\
                vrpn_Tng3      tng3b       com1        8 8\n\
                vrpn_Tng3      tng3c       com1        1 1\n";
    let entries = parse_str(text, "tng3.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["tng3name", "tng3b", "tng3c"]);
    for (bad, why) in [
        ("vrpn_Tng3 t /dev/ttyS0 4\n", "analogs"),
        ("vrpn_Tng3 t /dev/ttyS0 9 0\n", "buttons"),
        ("vrpn_Tng3 t /dev/ttyS0 0 9\n", "analogs"),
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
