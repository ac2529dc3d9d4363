//! The 5DT glove driver against its simulator on a virtual serial line, with an Analog remote
//! on one in-process connection: the reset, exact values and stamps in every mode, garbage,
//! the watchdog, wrong answers, the configuration line.

use std::time::Duration;

use super::config::{Glove5dt, Mode};
use super::sim::{GloveSim, SimConfig};
use super::Glove5dtProtocol;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::Lifecycle;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::analog_rig::AnalogLine;
use crate::Connection;

type Rig = AnalogLine<Lifecycle<Glove5dtProtocol>, GloveSim>;

fn rig(cfg_line: &str, seed: u64) -> Rig {
    let cfg: Glove5dt = parse_one(cfg_line);
    let mut sim = SimConfig::new(cfg.baud);
    sim.ten_bytes = cfg.ten_bytes;
    sim.keep_log = true;
    AnalogLine::new(
        &cfg.name,
        |conn| cfg.lifecycle(conn).unwrap(),
        GloveSim::new(sim),
        seed,
        |m| {
            m.sent()
                .iter()
                .map(|s| (s.channels.to_vec(), s.first_byte))
                .collect()
        },
    )
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several records at once (and the records right
    // after the reset's answers): each is reported, from the first the glove sent on.
    for (line, seed) in [
        ("vrpn_5dt glove 1 19200 1 0\n", 21),
        ("vrpn_5dt glove 1 19200 2 1\n", 22),
        ("vrpn_5dt glove 1 9600 1 0\n", 23),
    ] {
        let mut r = rig(line, seed);
        r.line.read_lag = Duration::from_millis(12);
        r.run_until_reports(100, Duration::from_secs(5));
        assert_eq!(r.check(0, 0), 0, "{line}");
    }
}

#[test]
fn polled_glove_is_reset_then_asked_for_each_record() {
    let mut r = rig("vrpn_5dt glove 1 19200 1 0\n", 1);
    r.line.split_reads = true;
    r.run_until_reports(1, Duration::from_secs(1));
    let startup = r.line.now().mono - r.start.mono;
    assert!(startup < Duration::from_millis(50), "{startup:?}");
    r.run_until_reports(100, Duration::from_secs(5));
    r.check(0, 0);
    let heard = r.line.device.heard();
    assert_eq!(&heard[..3], b"AGC");
    assert!(heard[3..].iter().all(|&b| b == b'C'));
    assert!(heard.len() >= 100);
    assert!(r.has_text("glove \"DG5 Glove\" version 2.1"));
    assert!(r.has_text("A right glove is ready"));
    assert!(r.has_text("Pitch and Roll are available"));
}

#[test]
fn streaming_ten_byte_glove() {
    let mut r = rig("vrpn_5dt glove 1 19200 2 1\n", 2);
    r.line.split_reads = true;
    r.run_until_reports(200, Duration::from_secs(5));
    r.check(0, 0);
    assert_eq!(r.line.device.heard(), b"AGD");
}

#[test]
fn the_simulator_of_vrpn_device_sim_sends_the_records_its_line_asks_for() {
    // A driver that reads records of a fixed length (C++'s) cannot keep step with records
    // of another length: the line `vrpn_device_sim glove5dt` prints must say the length its
    // simulator sends, and C++ starts on it (a line asking for ten-byte records of this
    // nine-byte simulator kept C++ resetting).
    let sim = &super::sim::SIMULATOR;
    let cfg: Glove5dt = parse_one(&format!("{}\n", sim.config_line("/dev/ttyS0", sim.baud)));
    assert_eq!(cfg.ten_bytes, SimConfig::new(sim.baud).ten_bytes);
    assert_eq!((cfg.mode, cfg.baud), (Mode::Polled, 19200));
    let mut r = rig(&format!("{}\n", sim.config_line("1", sim.baud)), 9);
    r.run_until_reports(50, Duration::from_secs(2));
    r.check(0, 0);
}

#[test]
fn wireless_glove_is_only_listened_to() {
    // 9600 baud: wireless, streaming ten-byte records whatever the line says.
    let mut r = rig("vrpn_5dt glove 1 9600 1 0\n", 3);
    r.line.split_reads = true;
    r.run_until_reports(100, Duration::from_secs(5));
    r.check(0, 0);
    assert!(r.line.device.heard().is_empty());
    assert!(r.has_text("receive-only 'wireless-type' glove"));
    assert!(r.has_text("is ready and reporting"));
}

#[test]
fn garbage_costs_no_record() {
    for (line, seed) in [
        ("vrpn_5dt glove 1 19200 2 0\n", 4),
        ("vrpn_5dt glove 1 9600 2 1\n", 5),
    ] {
        let mut r = rig(line, seed);
        r.run_until_reports(10, Duration::from_secs(5));
        for junk in [&[1u8, 2, 3][..], &[0x55, 0x40], &[0xFF]] {
            let n = r.heard.borrow().len();
            r.run_until_reports(n + 1, Duration::from_secs(1));
            let now = r.line.now().mono;
            r.line.device.inject(junk, now);
        }
        let n = r.heard.borrow().len();
        r.run_until_reports(n + 30, Duration::from_secs(5));
        r.check(0, 0);
        assert_eq!(r.line.driver.stats().skipped_bytes, 6);
        assert!(r.has_text("skipped"), "{:?}", r.texts.borrow());
    }
}

#[test]
fn a_silent_glove_is_reset_on_the_open_port_and_resumes() {
    for (line, seed, reset) in [
        ("vrpn_5dt glove 1 19200 1 0\n", 6, &b"AGC"[..]),
        ("vrpn_5dt glove 1 19200 2 0\n", 7, b"AGD"),
    ] {
        let mut r = rig(line, seed);
        r.run_until_reports(10, Duration::from_secs(5));
        r.line.device.mute = true;
        r.line.run_for(Duration::from_millis(4500));
        assert_eq!(r.line.driver.stats().watchdog_fired, 1);
        assert!(r.has_text("Tracker failed, trying to reset"));
        assert!(r.has_text("Unable to read from the glove"));
        let (from, logged) = (r.heard.borrow().len(), r.line.device.sent().len());
        r.line.device.mute = false;
        r.run_until_reports(from + 20, Duration::from_secs(5));
        r.check(from, logged);
        assert_eq!(r.line.driver.stats().opens, 1, "reset on the open port");
        let heard = r.line.device.heard();
        assert!(heard.windows(3).filter(|w| *w == reset).count() >= 2);
    }
}

#[test]
fn a_wrong_answer_is_reported_and_retried() {
    let mut r = rig("vrpn_5dt glove 1 19200 1 0\n", 8);
    r.line.device.set_init_answer(Some(b'x'));
    r.line.run_for(Duration::from_millis(2500));
    assert!(r.heard.borrow().is_empty());
    assert!(r.has_text("Unable to read from the glove"));
    r.line.device.set_init_answer(Some(super::INIT_ANSWER));
    r.run_until_reports(10, Duration::from_secs(5));
    r.check(0, 0);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_5dt\tglove_5dt\t/dev/ttyS0\t19200\t1 0\n\
                vrpn_5dt\tglove_5dt2\tCOM1\t19200\t1 0\n\
                vrpn_5dt   glove_5dt_wireless /dev/ttyS1 9600 2 1\n";
    let entries = parse_str(text, "5dt.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["glove_5dt", "glove_5dt2", "glove_5dt_wireless"]);
    let w: Glove5dt = parse_one("vrpn_5dt g /dev/ttyS1 9600 1 0\n");
    assert!(w.wireless() && w.record_len() == 10 && w.mode == Mode::Polled);
    for (bad, why) in [
        ("vrpn_5dt g /dev/ttyS0 19200 3 0\n", "mode"),
        ("vrpn_5dt g /dev/ttyS0 19200 1\n", "ten_bytes"),
        ("vrpn_5dt g /dev/ttyS0 12345 1 0\n", "12345"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
