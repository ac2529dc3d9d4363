//! The Streaming Arduino driver against its simulator on a virtual serial line, with an
//! Analog remote on one in-process connection: the boot and the count, exact values and
//! stamps, bad lines and garbage, the watchdog and a reopen, the configuration line.

use std::time::Duration;

use super::config::StreamingArduino;
use super::sim::{ArduinoSim, SimConfig};
use super::{ArduinoProtocol, ASK_EVERY};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::Lifecycle;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::analog_rig::AnalogLine;
use crate::Connection;

type Rig = AnalogLine<Lifecycle<ArduinoProtocol>, ArduinoSim>;

fn rig(cfg_line: &str, seed: u64) -> Rig {
    let cfg: StreamingArduino = parse_one(cfg_line);
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    AnalogLine::new(
        &cfg.name,
        |conn| cfg.lifecycle(conn).unwrap(),
        ArduinoSim::new(sim),
        seed,
        |m| {
            m.sent()
                .iter()
                .map(|s| (s.values.to_vec(), s.first_byte))
                .collect()
        },
    )
}

const LINE: &str = "vrpn_Streaming_Arduino sa0 /dev/ttyd2 4\n";

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several lines at once (the first ends the
    // reset): each is reported but the first, which this driver drops on purpose, as it
    // does for a prompt reader (the Arduino may have been mid-line when the count arrived;
    // C++ takes the first byte for the start of a line).
    let mut r = rig(LINE, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.run_until_reports(100, Duration::from_secs(5));
    assert_eq!(r.check(0, 0), 1);
}

#[test]
fn the_count_is_repeated_through_the_boot_then_lines_are_exact() {
    let mut r = rig(LINE, 1);
    r.line.split_reads = true;
    r.run_until_reports(1, Duration::from_secs(4));
    let startup = r.line.now().mono - r.start.mono;
    // Boot loader 0.3 s, then the next repeat of the count, then a line (the first after the
    // reset is dropped).
    assert!(
        startup >= Duration::from_millis(300)
            && startup < Duration::from_millis(300) + ASK_EVERY * 2,
        "{startup:?}"
    );
    assert_eq!(r.line.device.analogs(), 4);
    let heard = r.line.device.heard();
    assert!(
        heard.len() >= 4 && heard.chunks(2).all(|c| c == b"4\n"),
        "{heard:?}"
    );
    r.run_until_reports(200, Duration::from_secs(5));
    r.check(0, 0);
    assert_eq!(r.heard.borrow()[0].0.len(), 4);
}

#[test]
fn more_than_eight_analogs_are_clamped_with_a_warning() {
    let mut r = rig("vrpn_Streaming_Arduino sa0 COM5 12 115200\n", 2);
    r.run_until_reports(20, Duration::from_secs(4));
    r.check(0, 0);
    assert_eq!(r.line.device.analogs(), 8);
    assert!(r.has_text("Can only support 8 analog channels, not 12"));
}

#[test]
fn bad_lines_and_garbage_cost_only_themselves() {
    let mut r = rig(LINE, 3);
    r.run_until_reports(10, Duration::from_secs(4));
    // The first line after the reset was dropped (it may have lost its start).
    let before = r.line.driver.stats().skipped_bytes;
    for junk in [&b"xyz"[..], b"1,2\n", b"\x00\xFF", b"a,b,c,d\n"] {
        let n = r.heard.borrow().len();
        r.run_until_reports(n + 1, Duration::from_secs(1));
        let now = r.line.now().mono;
        r.line.device.inject(junk, now);
    }
    let n = r.heard.borrow().len();
    r.run_until_reports(n + 30, Duration::from_secs(5));
    r.check(0, 0);
    // 3 + 4 + 2 + 8 bytes.
    assert_eq!(r.line.driver.stats().skipped_bytes - before, 17);
    assert!(r.has_text("skipped"), "{:?}", r.texts.borrow());
}

#[test]
fn a_silent_sketch_gets_its_port_reopened_and_resumes() {
    let mut r = rig(LINE, 4);
    r.run_until_reports(10, Duration::from_secs(4));
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(2500));
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    assert!(r.has_text("Tracker failed, trying to reset"));
    assert_eq!(r.line.driver.stats().opens, 2);
    let (from, logged) = (r.heard.borrow().len(), r.line.device.sent().len());
    r.line.device.mute = false;
    r.run_until_reports(from + 20, Duration::from_secs(5));
    r.check(from, logged);
}

#[test]
fn a_sketch_that_never_answers_is_reported_and_reopened() {
    let mut r = rig(LINE, 5);
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(3500));
    assert!(r.has_text("Could not reset"));
    assert!(r.line.driver.stats().opens >= 2);
    r.line.device.mute = false;
    r.run_until_reports(10, Duration::from_secs(5));
    r.check(0, 0);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Streaming_Arduino      sa0    /dev/ttyd2  4\n\
                vrpn_Streaming_Arduino      sa1    COM5  4\n\
                vrpn_Streaming_Arduino sa2 /dev/ttyACM0 2 57600\n";
    let entries = parse_str(text, "sa.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["sa0", "sa1", "sa2"]);
    let c: StreamingArduino = parse_one("vrpn_Streaming_Arduino sa0 /dev/ttyd2 4\n");
    assert_eq!(c.baud, 115_200);
    let c: StreamingArduino = parse_one("vrpn_Streaming_Arduino sa2 /dev/ttyACM0 2 57600\n");
    assert_eq!((c.baud, c.analogs()), (57_600, 2));
    for (bad, why) in [
        ("vrpn_Streaming_Arduino sa0 /dev/ttyd2\n", "analogs"),
        ("vrpn_Streaming_Arduino sa0 /dev/ttyd2 0\n", "analogs"),
        ("vrpn_Streaming_Arduino sa0 /dev/ttyd2 4 12345\n", "12345"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
