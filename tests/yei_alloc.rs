//! The YEI 3-Space drivers report without allocating: a counting global allocator around
//! every driver call while the simulator streams through them, with reads split at random
//! points and garbage on the line.

use std::cell::Cell;
use std::rc::Rc;

use vrpn::drivers::yei::sim::{SimConfig, YeiSim};
use vrpn::drivers::yei::{Yei, YeiWireless};
use vrpn::server::config::parse_one;
use vrpn::sim::VirtualLine;
use vrpn::{AnalogRemote, ButtonRemote, Connection, TrackerRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use counted_driver::{start, Counted};
use streaming_alloc::{assert_streamed_skipping, bump, quiet_texts, stream_after_warm_up};

/// Counts every pose, acceleration, analog report and button change of `name`.
fn remotes(name: &str, conn: &Connection, reports: &Rc<Cell<u64>>) -> impl Sized {
    let tracker = TrackerRemote::on_connection(name, conn).unwrap();
    tracker.on_pose(bump(reports));
    tracker.on_acceleration(bump(reports));
    let analog = AnalogRemote::on_connection(name, conn).unwrap();
    analog.on_report(bump(reports));
    let buttons = ButtonRemote::on_connection(name, conn).unwrap();
    buttons.on_change(bump(reports));
    (tracker, analog, buttons)
}

#[test]
fn wired_unit_streams_without_allocating() {
    quiet_texts();
    let cfg: Yei = parse_one("vrpn_YEI_3Space_Sensor Y0 /dev/ttyACM0 115200 0 0 100 0 0 1 0\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = Rc::new(Cell::new(0));
    let _remotes = remotes("Y0", &conn, &reports);
    let sim = YeiSim::new(SimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 9);
    let streamed = stream_after_warm_up(&mut line, &reports, b"\x41\x7F\x00garbage");
    // 100 records/s, each at least two poses, an acceleration and an analog report.
    assert_streamed_skipping(&line, streamed, 4 * 450, 50);
}

#[test]
fn wireless_dongle_with_two_units_streams_without_allocating() {
    quiet_texts();
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
    let (allocations, reports) =
        stream_after_warm_up(&mut line, &reports, b"\x41\x7F\x00\x03\x12garbage");
    // Two units at 100 records/s, each at least two poses, an acceleration and an analog
    // report.
    assert!(reports >= 2 * 4 * 450, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 50);
    assert_eq!(line.driver.0.stats().resets, 1);
    assert_eq!(allocations, 0, "allocations while streaming");
}
