//! The YEI 3-Space drivers report without allocating: a counting global allocator around
//! every driver call while the simulator streams through them, with reads split at random
//! points and garbage on the line.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::yei::sim::{SimConfig, YeiSim};
use vrpn::drivers::yei::{Yei, YeiWireless};
use vrpn::serial::SerialDriver;
use vrpn::server::config::parse_one;
use vrpn::sim::{DeviceModel, VirtualLine};
use vrpn::{AnalogRemote, ButtonRemote, Connection, TrackerRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
use counted_driver::{start, Counted, COUNT};

/// Streams through `driver` for 5 s after a warm-up with `noise` on the line; returns
/// (allocations, reports).
fn stream<D: SerialDriver, M: DeviceModel>(
    line: &mut VirtualLine<Counted<D>, M>,
    reports: &Rc<Cell<u64>>,
    noise: &[u8],
) -> (u64, u64) {
    line.split_reads = true;
    line.run_for(Duration::from_secs(2));
    line.inject(noise);
    line.run_for(Duration::from_millis(1500));
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        line.inject(noise);
    }
    (COUNT.with(Cell::get), reports.get() - before)
}

/// Counts every pose, acceleration, analog report and button change of `name`.
fn remotes(name: &str, conn: &Connection, reports: &Rc<Cell<u64>>) -> impl Sized {
    let tracker = TrackerRemote::on_connection(name, conn).unwrap();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let r = reports.clone();
    tracker.on_acceleration(move |_| r.set(r.get() + 1));
    let analog = AnalogRemote::on_connection(name, conn).unwrap();
    let r = reports.clone();
    analog.on_report(move |_| r.set(r.get() + 1));
    let buttons = ButtonRemote::on_connection(name, conn).unwrap();
    let r = reports.clone();
    buttons.on_change(move |_| r.set(r.get() + 1));
    (tracker, analog, buttons)
}

#[test]
fn wired_unit_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: Yei = parse_one("vrpn_YEI_3Space_Sensor Y0 /dev/ttyACM0 115200 0 0 100 0 0 1 0\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = Rc::new(Cell::new(0));
    let _remotes = remotes("Y0", &conn, &reports);
    let sim = YeiSim::new(SimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 9);
    let (allocations, reports) = stream(&mut line, &reports, b"\x41\x7F\x00garbage");
    // 100 records/s, each at least two poses, an acceleration and an analog report.
    assert!(reports >= 4 * 450, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 50);
    assert_eq!(allocations, 0, "allocations while streaming");
}

#[test]
fn wireless_dongle_with_two_units_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: YeiWireless = parse_one(
        "vrpn_YEI_3Space_Sensor_Wireless W0 0 /dev/ttyACM0 115200 0 0 100 0 0 1 1 /\n\
         vrpn_YEI_3Space_Sensor_Wireless W1 3 0 0 100 0 1 0 1\n",
    );
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = Rc::new(Cell::new(0));
    let _remotes = (
        remotes("W0", &conn, &reports),
        remotes("W1", &conn, &reports),
    );
    let sim = YeiSim::new(SimConfig::wireless(cfg.baud, &[0, 3]));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 9);
    let (allocations, reports) = stream(&mut line, &reports, b"\x41\x7F\x00\x03\x12garbage");
    // Two units at 100 records/s, each at least two poses, an acceleration and an analog
    // report.
    assert!(reports >= 2 * 4 * 450, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 50);
    assert_eq!(line.driver.0.stats().resets, 1);
    assert_eq!(allocations, 0, "allocations while streaming");
}
