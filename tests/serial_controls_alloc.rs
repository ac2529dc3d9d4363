//! The serial mouse's buttons, the VP joystick, the Nikon focus, the Zaber positioners, the
//! IDEA stepper drive and the BiosciencesTools controller report without allocating: a
//! counting global allocator around every driver call while the simulators stream through
//! them (reads split at random points, garbage on the line), and, for the devices with an
//! Analog_Output, while clients keep asking for moves and set points.

use std::time::Duration;

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::drivers::biosciences::sim::{BioSim, SimConfig as BioConfig};
use vrpn::drivers::idea::sim::{IdeaSim, SimConfig as IdeaConfig};
use vrpn::drivers::nikon::sim::{NikonSim, SimConfig as NikonConfig};
use vrpn::drivers::serialmouse::packet::MouseType;
use vrpn::drivers::serialmouse::sim::{SerialMouseSim, SimConfig as MouseConfig};
use vrpn::drivers::vpjoystick::sim::{SimConfig as VpConfig, VpJoystickSim};
use vrpn::drivers::zaber::sim::{SimConfig as ZaberConfig, ZaberSim};
use vrpn::server::config::parse_one;
use vrpn::sim::VirtualLine;
use vrpn::Connection;

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use counted_driver::{start, Counted};
use streaming_alloc::{count_reports, quiet_texts, stream_steps};

#[test]
fn serial_mouse_streams_without_allocating() {
    quiet_texts();
    for (word, kind, noise) in [
        ("3button", MouseType::ThreeButton, &[0x01u8, 0x02, 0x03][..]),
        (
            "mousesystems",
            MouseType::MouseSystems,
            &[0x41, 0x7F, 0x20][..],
        ),
    ] {
        let cfg: vrpn::drivers::serialmouse::SerialMouse =
            parse_one(&format!("vrpn_Button_SerialMouse M0 /dev/ttyS0 {word}\n"));
        let conn = Connection::new_loopback();
        let (reports, _a, _b) = count_reports("M0", &conn);
        let driver = cfg.lifecycle(&conn).unwrap();
        let sim = SerialMouseSim::new(MouseConfig::new(kind));
        let mut line = VirtualLine::new(Counted(driver), sim, start(), 7);
        let step = Duration::from_millis(100);
        let (n, allocations, skipped) = stream_steps(&mut line, &reports, noise, 5, step, |_| {});
        // A packet every 40 or 60 ms, most changing a button. In `3button` every byte is a
        // first byte or motion: nothing is skipped there.
        assert!(n >= 50, "{word}: {n} reports");
        assert!(
            kind == MouseType::ThreeButton || skipped > 0,
            "{word}: nothing skipped"
        );
        assert_eq!(
            allocations, 0,
            "{word}: allocations while sending {n} reports"
        );
    }
}

#[test]
fn vp_joystick_streams_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::vpjoystick::VpJoystick =
        parse_one("vrpn_VPJoystick J0 /dev/ttyS0 9600\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("J0", &conn);
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = VpJoystickSim::new(VpConfig::new(9600));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 8);
    let step = Duration::from_millis(100);
    let noise = [0x41, 0x7F, 0x20];
    let (n, allocations, skipped) = stream_steps(&mut line, &reports, &noise, 5, step, |_| {});
    // 50 messages a second, each changing at least one of the eight buttons.
    assert!(
        n >= 250 && skipped > 0,
        "{n} reports, {skipped} bytes skipped"
    );
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn nikon_moves_and_polls_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::nikon::Nikon = parse_one("vrpn_nikon_controls N0 /dev/ttyS0\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("N0", &conn);
    let out = AnalogOutputRemote::on_connection("N0", &conn).unwrap();
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = NikonSim::new(NikonConfig::new(9600));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 9);
    // A move asked for every 50 ms, and the knob turned by hand now and then (found by the
    // idle poll).
    let mut k = 0;
    let step = Duration::from_millis(50);
    let (n, allocations, skipped) = stream_steps(&mut line, &reports, b"zz\r\n", 5, step, |line| {
        k += 1;
        if k % 10 == 0 {
            line.device.turn_knob(-k);
        } else {
            out.request_change_channel_value(0, f64::from(k as i32 * 37))
                .unwrap();
        }
    });
    assert!(
        n >= 80 && skipped > 0,
        "{n} reports, {skipped} bytes skipped"
    );
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn zaber_moves_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::zaber::Zaber = parse_one("vrpn_Zaber Z0 /dev/ttyS0\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("Z0", &conn);
    let out = AnalogOutputRemote::on_connection("Z0", &conn).unwrap();
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = ZaberSim::new(ZaberConfig::new(2));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 11);
    // A move of one of the two devices asked for every 50 ms (the idle poll runs between).
    let mut k = 0i32;
    let step = Duration::from_millis(50);
    let (n, allocations, skipped) = stream_steps(&mut line, &reports, &[9, 9, 9], 5, step, |_| {
        k += 1;
        out.request_change_channel_value(k % 2, f64::from(k * 311 - 2000))
            .unwrap();
    });
    assert!(
        n >= 80 && skipped > 0,
        "{n} reports, {skipped} bytes skipped"
    );
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn idea_moves_and_polls_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::idea::Idea = parse_one(
        "vrpn_IDEA I0 /dev/ttyS0 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 0 0 0 0 \
         50 0.5 -60.0\n",
    );
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("I0", &conn);
    let out = AnalogOutputRemote::on_connection("I0", &conn).unwrap();
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = IdeaSim::new(IdeaConfig::new());
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 12);
    // A move asked for every 50 ms (the position and the inputs polled in turn all along),
    // and the inputs pressed and released now and then.
    let mut k = 0i32;
    let step = Duration::from_millis(50);
    let (n, allocations, skipped) = stream_steps(&mut line, &reports, b"zz\r\n", 5, step, |line| {
        k += 1;
        if k % 7 == 0 {
            line.device.set_inputs((k % 16) as u8 & 0b1110);
        }
        out.request_change_channel_value(0, f64::from(-100 - k * 37 % 300))
            .unwrap();
    });
    assert!(
        n >= 80 && skipped > 0,
        "{n} reports, {skipped} bytes skipped"
    );
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn biosciences_polls_and_sets_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::biosciences::Biosciences =
        parse_one("vrpn_BiosciencesTools B0 /dev/ttyS0 37.0 36.5 1\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("B0", &conn);
    let out = AnalogOutputRemote::on_connection("B0", &conn).unwrap();
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = BioSim::new(BioConfig::new());
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 10);
    // A set point (or control on/off, which is a button change) asked for every 100 ms.
    let mut k = 0u32;
    let step = Duration::from_millis(100);
    let (n, allocations, skipped) = stream_steps(&mut line, &reports, b"x?\r", 5, step, |_| {
        k += 1;
        let channel = (k % 3) as i32;
        let value = if channel == 2 {
            f64::from(k % 2)
        } else {
            30.0 + f64::from(k % 70) / 10.0
        };
        out.request_change_channel_value(channel, value).unwrap();
    });
    // Polled without pause: about 200 answers a second, each changing its channel.
    assert!(
        n >= 500 && skipped > 0,
        "{n} reports, {skipped} bytes skipped"
    );
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
    let settings = line.device.settings();
    assert!(settings.reference[0].is_some() && settings.reference[1].is_some());
}
