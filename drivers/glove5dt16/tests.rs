//! The 5DT Data Glove 16 driver against its simulator on a virtual serial line, with an
//! Analog remote on one in-process connection: start-up, exact values and stamps, information
//! packets among the data, garbage, the watchdog, the configuration line.

use std::time::Duration;

use super::config::Glove5dt16;
use super::sim::{Glove16Sim, SimConfig};
use super::Glove16Protocol;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::Lifecycle;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::analog_rig::AnalogLine;
use crate::Connection;

type Rig = AnalogLine<Lifecycle<Glove16Protocol>, Glove16Sim>;

fn rig(cfg_line: &str, seed: u64) -> Rig {
    let cfg: Glove5dt16 = parse_one(cfg_line);
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    AnalogLine::new(
        &cfg.name,
        |conn| cfg.lifecycle(conn).unwrap(),
        Glove16Sim::new(sim),
        seed,
        |m| {
            m.sent()
                .iter()
                .map(|s| (s.channels.to_vec(), s.first_byte))
                .collect()
        },
    )
}

const LINE: &str = "vrpn_5dt16 glove_5dt16 /dev/ttyS0 19200\n";

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several packets at once (the first ends the
    // reset): each is reported, from the first the glove sent on.
    let mut r = rig(LINE, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.run_until_reports(100, Duration::from_secs(5));
    assert_eq!(r.check(0, 0), 0);
}

#[test]
fn starts_on_the_first_packet_and_reports_exact_values() {
    let mut r = rig(LINE, 1);
    r.line.split_reads = true;
    r.run_until_reports(1, Duration::from_secs(1));
    let startup = r.line.now().mono - r.start.mono;
    // One information and one data packet at 19200 baud.
    assert!(startup < Duration::from_millis(30), "{startup:?}");
    assert!(r.line.driver.is_streaming());
    r.run_until_reports(100, Duration::from_secs(5));
    r.check(0, 0);
    assert!(r.has_text("Hardware Version 2.01"));
    assert!(r.has_text("A right glove is ready"));
    assert!(r.has_text("no wireless glove"));
    // Information packets come every 20 data packets; they are announced once.
    let n = r
        .texts
        .borrow()
        .iter()
        .filter(|t| t.contains("Hardware"))
        .count();
    assert_eq!(n, 1);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn garbage_costs_no_packet() {
    let mut r = rig(LINE, 2);
    r.run_until_reports(10, Duration::from_secs(5));
    for junk in [&[1u8, 2, 3][..], b"<x", b"<<", b">"] {
        let n = r.heard.borrow().len();
        r.run_until_reports(n + 1, Duration::from_secs(1));
        let now = r.line.now().mono;
        r.line.device.inject(junk, now);
    }
    let n = r.heard.borrow().len();
    r.run_until_reports(n + 30, Duration::from_secs(5));
    r.check(0, 0);
    assert_eq!(r.line.driver.stats().skipped_bytes, 8);
    assert!(r.has_text("skipped"), "{:?}", r.texts.borrow());
}

#[test]
fn a_silent_glove_is_listened_to_again_and_resumes() {
    let mut r = rig(LINE, 3);
    r.run_until_reports(10, Duration::from_secs(5));
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(4500));
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    assert!(r.has_text("Tracker failed, trying to reset"));
    assert!(r.has_text("Timeout during reset"));
    let (from, logged) = (r.heard.borrow().len(), r.line.device.sent().len());
    r.line.device.mute = false;
    r.run_until_reports(from + 20, Duration::from_secs(5));
    r.check(from, logged);
    assert_eq!(r.line.driver.stats().opens, 1, "reset on the open port");
}

#[test]
fn a_closed_port_is_reopened() {
    let mut r = rig(LINE, 4);
    r.run_until_reports(10, Duration::from_secs(5));
    r.line.close();
    let n = r.heard.borrow().len();
    r.run_until_reports(n + 10, Duration::from_secs(5));
    assert_eq!(r.line.driver.stats().opens, 2);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_5dt16    glove_5dt16     COM1    19200\n\
                vrpn_5dt16 g2 /dev/ttyUSB0 115200\n";
    let entries = parse_str(text, "5dt16.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["glove_5dt16", "g2"]);
    for (bad, why) in [
        ("vrpn_5dt16 g /dev/ttyS0\n", "baud"),
        ("vrpn_5dt16 g /dev/ttyS0 12345\n", "12345"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
