//! The Fastrak driver reports records without allocating: checked with a counting global
//! allocator around every driver call while an IS-900 with a wand and a stylus streams
//! through it (pose, button and analog paths, split reads) on a virtual serial line.

#[path = "common/counted_driver.rs"]
mod counted_driver;

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use counted_driver::{Counted, COUNT};
use vrpn::drivers::fastrak::sim::{FastrakSim, SimConfig};
use vrpn::server::config::parse_one;
use vrpn::sim::VirtualLine;
use vrpn::{AnalogRemote, ButtonRemote, Connection, TrackerRemote};

#[test]
fn streaming_records_allocates_nothing() {
    let text = "vrpn_Tracker_Fastrak Isense900 /dev/ttyS1 115200 IS900time /\n\
                Wand Wand0 0 -1.0 0.0 0.0 1.0 -1.0 0.0 0.0 1.0 /\n\
                Stylus Stylus0 2\n";
    let cfg: vrpn::drivers::fastrak::config::Fastrak = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("Isense900", &conn).unwrap();
    let wand_buttons = ButtonRemote::on_connection("Wand0", &conn).unwrap();
    let wand_analog = AnalogRemote::on_connection("Wand0", &conn).unwrap();
    let stylus = ButtonRemote::on_connection("Stylus0", &conn).unwrap();
    let (poses, changes, analogs) = (
        Rc::new(Cell::new(0u64)),
        Rc::new(Cell::new(0u64)),
        Rc::new(Cell::new(0u64)),
    );
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));
    let c = changes.clone();
    wand_buttons.on_change(move |_| c.set(c.get() + 1));
    let c = changes.clone();
    stylus.on_change(move |_| c.set(c.get() + 1));
    let a = analogs.clone();
    wand_analog.on_report(move |_| a.set(a.get() + 1));

    let start = counted_driver::start();
    let mut line = VirtualLine::new(
        Counted(driver),
        FastrakSim::new(SimConfig::new(115_200)),
        start,
        3,
    );
    line.split_reads = true;
    // Reset, then a second of streaming to warm every path up.
    line.run_for(Duration::from_millis(1500));
    assert!(line.driver.0.is_streaming());
    COUNT.with(|c| c.set(0));
    let before = (poses.get(), changes.get(), analogs.get());
    line.run_for(Duration::from_secs(5));
    let allocations = COUNT.with(Cell::get);
    let poses = poses.get() - before.0;
    let changes = changes.get() - before.1;
    let analogs = analogs.get() - before.2;
    assert!(poses > 1000, "{poses} poses");
    assert!(changes > 50, "{changes} button changes");
    assert!(analogs > 200, "{analogs} analog reports");
    assert_eq!(
        allocations, 0,
        "allocations while streaming {poses} records"
    );
}
