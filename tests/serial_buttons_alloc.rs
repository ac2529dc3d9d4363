//! The Wanda, Pinch Glove, UNC joystick and Immersion box drivers report without
//! allocating: a counting global allocator around every driver call while the simulators
//! stream through them, with reads split at random points and garbage on the line.

use std::cell::Cell;
use std::time::Duration;

use vrpn::drivers::immersionbox::sim::{IboxSim, SimConfig as IboxConfig};
use vrpn::drivers::pinchglove::sim::{PinchSim, SimConfig as PinchConfig};
use vrpn::drivers::uncjoystick::sim::{JoystickSim, SimConfig as JoyConfig};
use vrpn::drivers::wanda::sim::{SimConfig as WandaConfig, WandaSim};
use vrpn::server::config::parse_one;

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use counted_driver::COUNT;
use streaming_alloc::{assert_streamed, rig, stream};

#[test]
fn wanda_streams_without_allocating() {
    let cfg: vrpn::drivers::wanda::Wanda = parse_one("vrpn_Wanda W0 /dev/ttyS0 1200 60\n");
    let mut rig = rig("W0", WandaSim::new(WandaConfig::new()), 1, |conn| {
        cfg.lifecycle(conn)
    });
    // Bursts and pauses: the centring after each burst is counted too.
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x85, 0x41], 5);
    assert_streamed(n, 100, allocations);
}

#[test]
fn pinch_glove_streams_without_allocating() {
    let cfg: vrpn::drivers::pinchglove::PinchGlove =
        parse_one("vrpn_Button_PinchGlove P0 /dev/ttyS0 9600\n");
    let mut rig = rig("P0", PinchSim::new(PinchConfig::new(9600)), 2, |conn| {
        cfg.lifecycle(conn)
    });
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x33, 0x80, 0x10], 5);
    assert_streamed(n, 150, allocations);
}

#[test]
fn unc_joystick_streams_and_repeats_without_allocating() {
    let cfg: vrpn::drivers::uncjoystick::UncJoystick =
        parse_one("vrpn_Joystick J0 /dev/ttyS0 19200 10\n");
    let mut rig = rig("J0", JoystickSim::new(JoyConfig::new(19200)), 3, |conn| {
        cfg.lifecycle(conn)
    });
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x85, 0x12], 4);
    assert_streamed(n, 200, allocations);
    // The minimum rate's repeats while the box is quiet.
    rig.line.device.mute = true;
    COUNT.with(|c| c.set(0));
    let before = rig.reports.get();
    rig.line.run_for(Duration::from_secs(2));
    assert!(rig.reports.get() - before >= 19);
    assert_eq!(COUNT.with(Cell::get), 0, "allocations while repeating");
}

#[test]
fn immersion_box_streams_without_allocating() {
    let cfg: vrpn::drivers::immersionbox::ImmersionBox =
        parse_one("vrpn_ImmersionBox I0 /dev/ttyS0 38400 7 8 6\n");
    let mut rig = rig("I0", IboxSim::new(IboxConfig::new(38400)), 4, |conn| {
        cfg.lifecycle(conn)
    });
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x01, 0x7F], 5);
    assert_streamed(n, 300, allocations);
}
