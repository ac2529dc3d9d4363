//! The Flock drivers report records without allocating: checked with a counting global
//! allocator around every driver call while a Flock streams through them (one line in group
//! mode, and one line per receiver) with reads split at random points and garbage on the line.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::flock::sim::{FlockSim, SimConfig};
use vrpn::drivers::flock::FlockParallelPort;
use vrpn::sim::{VirtualLine, VirtualLines};

use vrpn::server::config::parse_one;
use vrpn::{Connection, TrackerRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
use counted_driver::{start, Counted, COUNT};

fn pose_counter(remote: &TrackerRemote) -> Rc<Cell<u64>> {
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    remote.on_pose(move |_| p.set(p.get() + 1));
    poses
}

#[test]
fn one_line_flock_streams_without_allocating() {
    let text = "vrpn_Tracker_Flock Tracker0 4 /dev/ttyS0 115200 1\n";
    let cfg: vrpn::drivers::flock::Flock = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = pose_counter(&tracker);
    let mut line = VirtualLine::new(
        Counted(driver),
        FlockSim::new(SimConfig::for_flock(&cfg)),
        start(),
        3,
    );
    line.split_reads = true;
    // Reset, then streaming with one resynchronisation note to warm every path up.
    line.run_for(Duration::from_millis(1500));
    assert!(line.driver.0.is_streaming());
    line.inject(&[0x01, 0x80, 0x02]);
    line.run_for(Duration::from_millis(500));
    COUNT.with(|c| c.set(0));
    let before = poses.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        line.inject(&[0x03, 0x81, 0x04]);
    }
    let allocations = COUNT.with(Cell::get);
    let poses = poses.get() - before;
    assert!(poses > 1900, "{poses} poses");
    assert!(line.driver.0.stats().skipped_bytes >= 6);
    assert_eq!(
        allocations, 0,
        "allocations while streaming {poses} records"
    );
}

#[test]
fn parallel_flock_streams_without_allocating() {
    let text = "vrpn_Tracker_Flock_Parallel Tracker0 3 /dev/m 38400 0 /dev/a /dev/b /dev/c\n";
    let cfg: vrpn::drivers::flock::FlockParallel = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let ports = FlockParallelPort::new_group(&cfg, &conn).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = pose_counter(&tracker);
    let sims = FlockSim::parallel(SimConfig::for_parallel(&cfg));
    let mut lines = VirtualLines::new(ports.into_iter().map(Counted).zip(sims), start(), 4);
    for l in &mut lines.lines {
        l.split_reads = true;
    }
    lines.run_for(Duration::from_millis(2000));
    assert!(lines.lines[0].driver.0.is_streaming());
    lines.line(2).inject(&[0x01, 0x80, 0x02]);
    lines.run_for(Duration::from_millis(500));
    COUNT.with(|c| c.set(0));
    let before = poses.get();
    for _ in 0..5 {
        lines.run_for(Duration::from_secs(1));
        lines.line(3).inject(&[0x03, 0x81, 0x04]);
    }
    let allocations = COUNT.with(Cell::get);
    let poses = poses.get() - before;
    assert!(poses > 1400, "{poses} poses");
    assert_eq!(
        allocations, 0,
        "allocations while streaming {poses} records"
    );
}
