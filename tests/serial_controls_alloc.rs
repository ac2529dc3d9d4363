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

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use streaming_alloc::{assert_streamed_steps, rig, stream_steps};

#[test]
fn serial_mouse_streams_without_allocating() {
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
        let sim = SerialMouseSim::new(MouseConfig::new(kind));
        let mut rig = rig("M0", sim, 7, |conn| cfg.lifecycle(conn));
        let step = Duration::from_millis(100);
        let (n, allocations, skipped) =
            stream_steps(&mut rig.line, &rig.reports, noise, 5, step, |_| {});
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
    let cfg: vrpn::drivers::vpjoystick::VpJoystick =
        parse_one("vrpn_VPJoystick J0 /dev/ttyS0 9600\n");
    let mut rig = rig("J0", VpJoystickSim::new(VpConfig::new(9600)), 8, |conn| {
        cfg.lifecycle(conn)
    });
    let step = Duration::from_millis(100);
    let noise = [0x41, 0x7F, 0x20];
    let (n, allocations, skipped) =
        stream_steps(&mut rig.line, &rig.reports, &noise, 5, step, |_| {});
    // 50 messages a second, each changing at least one of the eight buttons.
    assert_streamed_steps(n, 250, allocations, skipped);
}

#[test]
fn nikon_moves_and_polls_without_allocating() {
    let cfg: vrpn::drivers::nikon::Nikon = parse_one("vrpn_nikon_controls N0 /dev/ttyS0\n");
    let mut rig = rig("N0", NikonSim::new(NikonConfig::new(9600)), 9, |conn| {
        cfg.lifecycle(conn)
    });
    let out = AnalogOutputRemote::on_connection("N0", &rig.conn).unwrap();
    // A move asked for every 50 ms, and the knob turned by hand now and then (found by the
    // idle poll).
    let mut k = 0;
    let step = Duration::from_millis(50);
    let (n, allocations, skipped) =
        stream_steps(&mut rig.line, &rig.reports, b"zz\r\n", 5, step, |line| {
            k += 1;
            if k % 10 == 0 {
                line.device.turn_knob(-k);
            } else {
                out.request_change_channel_value(0, f64::from(k as i32 * 37))
                    .unwrap();
            }
        });
    assert_streamed_steps(n, 80, allocations, skipped);
}

#[test]
fn zaber_moves_without_allocating() {
    let cfg: vrpn::drivers::zaber::Zaber = parse_one("vrpn_Zaber Z0 /dev/ttyS0\n");
    let mut rig = rig("Z0", ZaberSim::new(ZaberConfig::new(2)), 11, |conn| {
        cfg.lifecycle(conn)
    });
    let out = AnalogOutputRemote::on_connection("Z0", &rig.conn).unwrap();
    // A move of one of the two devices asked for every 50 ms (the idle poll runs between).
    let mut k = 0i32;
    let step = Duration::from_millis(50);
    let (n, allocations, skipped) =
        stream_steps(&mut rig.line, &rig.reports, &[9, 9, 9], 5, step, |_| {
            k += 1;
            out.request_change_channel_value(k % 2, f64::from(k * 311 - 2000))
                .unwrap();
        });
    assert_streamed_steps(n, 80, allocations, skipped);
}

#[test]
fn idea_moves_and_polls_without_allocating() {
    let cfg: vrpn::drivers::idea::Idea = parse_one(
        "vrpn_IDEA I0 /dev/ttyS0 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 0 0 0 0 \
         50 0.5 -60.0\n",
    );
    let mut rig = rig("I0", IdeaSim::new(IdeaConfig::new()), 12, |conn| {
        cfg.lifecycle(conn)
    });
    let out = AnalogOutputRemote::on_connection("I0", &rig.conn).unwrap();
    // A move asked for every 50 ms (the position and the inputs polled in turn all along),
    // and the inputs pressed and released now and then.
    let mut k = 0i32;
    let step = Duration::from_millis(50);
    let (n, allocations, skipped) =
        stream_steps(&mut rig.line, &rig.reports, b"zz\r\n", 5, step, |line| {
            k += 1;
            if k % 7 == 0 {
                line.device.set_inputs((k % 16) as u8 & 0b1110);
            }
            out.request_change_channel_value(0, f64::from(-100 - k * 37 % 300))
                .unwrap();
        });
    assert_streamed_steps(n, 80, allocations, skipped);
}

#[test]
fn biosciences_polls_and_sets_without_allocating() {
    let cfg: vrpn::drivers::biosciences::Biosciences =
        parse_one("vrpn_BiosciencesTools B0 /dev/ttyS0 37.0 36.5 1\n");
    let mut rig = rig("B0", BioSim::new(BioConfig::new()), 10, |conn| {
        cfg.lifecycle(conn)
    });
    let out = AnalogOutputRemote::on_connection("B0", &rig.conn).unwrap();
    // A set point (or control on/off, which is a button change) asked for every 100 ms.
    let mut k = 0u32;
    let step = Duration::from_millis(100);
    let (n, allocations, skipped) =
        stream_steps(&mut rig.line, &rig.reports, b"x?\r", 5, step, |_| {
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
    assert_streamed_steps(n, 500, allocations, skipped);
    let settings = rig.line.device.settings();
    assert!(settings.reference[0].is_some() && settings.reference[1].is_some());
}
