//! The DynaSight and joystick drivers report without allocating: checked with a counting
//! global allocator around every driver call while the simulators stream through them, with
//! reads split at random points and damage on the line.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::dyna::sim::{DynaSim, SimConfig};
use vrpn::drivers::joylin::sim::{JoystickSim, SimConfig as JoySimConfig};
use vrpn::sim::VirtualLine;

use vrpn::server::config::parse_one;
use vrpn::{AnalogRemote, ButtonRemote, Connection, TrackerRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
use counted_driver::{start, Counted, COUNT};

#[test]
fn dynasight_streams_without_allocating() {
    let text = "vrpn_Tracker_Dyna Dyna0 1 /dev/ttyS0 19200\n";
    let cfg: vrpn::drivers::dyna::Dyna = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("Dyna0", &conn).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));
    let mut line = VirtualLine::new(
        Counted(driver),
        DynaSim::new(SimConfig::new(cfg.baud)),
        start(),
        3,
    );
    line.split_reads = true;
    // Reset, then streaming with one resynchronisation note to warm every path up.
    line.run_for(Duration::from_millis(500));
    assert!(line.driver.0.is_streaming());
    let noise = [0x01, 0x85, 0x02, 0x7F];
    let now = line.now().mono;
    line.device.inject(&noise, now);
    line.run_for(Duration::from_millis(1500));
    COUNT.with(|c| c.set(0));
    let before = poses.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        let now = line.now().mono;
        line.device.inject(&noise, now);
    }
    let allocations = COUNT.with(Cell::get);
    let poses = poses.get() - before;
    assert!(poses >= 295, "{poses} poses");
    assert!(line.driver.0.stats().skipped_bytes >= 20);
    assert_eq!(
        allocations, 0,
        "allocations while streaming {poses} records"
    );
}

#[test]
fn joystick_streams_without_allocating() {
    let text = "vrpn_Joylin Joy0 /dev/input/js0\n";
    let cfg: vrpn::drivers::joylin::Joylin = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let analog = AnalogRemote::on_connection("Joy0", &conn).unwrap();
    let buttons = ButtonRemote::on_connection("Joy0", &conn).unwrap();
    let reports = Rc::new(Cell::new(0u64));
    let (a, b) = (reports.clone(), reports.clone());
    analog.on_report(move |_| a.set(a.get() + 1));
    buttons.on_change(move |_| b.set(b.get() + 1));
    let mut line = VirtualLine::new(
        Counted(driver),
        JoystickSim::new(JoySimConfig::new(6, 12)),
        start(),
        4,
    );
    line.split_reads = true;
    // Initial state, live events, one damaged stretch to warm every path up.
    line.run_for(Duration::from_millis(500));
    line.inject(&[0x10, 0x20, 0x30]);
    line.run_for(Duration::from_millis(500));
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        line.inject(&[0x10, 0x20, 0x30]);
    }
    let allocations = COUNT.with(Cell::get);
    let reports = reports.get() - before;
    // 200 events a second for 5 s, each reported.
    assert!(reports >= 990, "{reports} reports");
    assert!(line.driver.0.protocol().skipped_bytes() > 0);
    assert_eq!(
        allocations, 0,
        "allocations while streaming {reports} reports"
    );
}
