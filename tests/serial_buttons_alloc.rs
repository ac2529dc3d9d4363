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
use vrpn::sim::VirtualLine;
use vrpn::Connection;

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use counted_driver::{start, Counted, COUNT};
use streaming_alloc::{count_reports, quiet_texts, stream};

#[test]
fn wanda_streams_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::wanda::Wanda = parse_one("vrpn_Wanda W0 /dev/ttyS0 1200 60\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("W0", &conn);
    let driver = cfg.lifecycle(&conn).unwrap();
    let mut line = VirtualLine::new(
        Counted(driver),
        WandaSim::new(WandaConfig::new()),
        start(),
        1,
    );
    // Bursts and pauses: the centring after each burst is counted too.
    let (n, allocations) = stream(&mut line, &reports, &[0x85, 0x41], 5);
    assert!(n >= 100, "{n} reports");
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn pinch_glove_streams_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::pinchglove::PinchGlove =
        parse_one("vrpn_Button_PinchGlove P0 /dev/ttyS0 9600\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("P0", &conn);
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = PinchSim::new(PinchConfig::new(9600));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 2);
    let (n, allocations) = stream(&mut line, &reports, &[0x33, 0x80, 0x10], 5);
    assert!(n >= 150, "{n} reports");
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn unc_joystick_streams_and_repeats_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::uncjoystick::UncJoystick =
        parse_one("vrpn_Joystick J0 /dev/ttyS0 19200 10\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("J0", &conn);
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = JoystickSim::new(JoyConfig::new(19200));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 3);
    let (n, allocations) = stream(&mut line, &reports, &[0x85, 0x12], 4);
    assert!(n >= 200, "{n} reports");
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
    // The minimum rate's repeats while the box is quiet.
    line.device.mute = true;
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    line.run_for(Duration::from_secs(2));
    assert!(reports.get() - before >= 19);
    assert_eq!(COUNT.with(Cell::get), 0, "allocations while repeating");
}

#[test]
fn immersion_box_streams_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::immersionbox::ImmersionBox =
        parse_one("vrpn_ImmersionBox I0 /dev/ttyS0 38400 7 8 6\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("I0", &conn);
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = IboxSim::new(IboxConfig::new(38400));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 4);
    let (n, allocations) = stream(&mut line, &reports, &[0x01, 0x7F], 5);
    assert!(n >= 300, "{n} reports");
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}
