//! Serial devices that stream (the Spaceball, the 5DT gloves, the Streaming Arduino, the
//! Zaber, the BiosciencesTools, the Nikon) report without allocating: checked with a counting
//! global allocator around every driver call while the simulators stream through them, with
//! reads split at random points and damage on the line.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::spaceball::sim::{SimConfig as SpaceballSimConfig, SpaceballSim};
use vrpn::server::config::parse_one;
use vrpn::sim::VirtualLine;
use vrpn::{AnalogRemote, ButtonRemote, Connection};

#[path = "common/counted_driver.rs"]
mod counted_driver;
use counted_driver::{start, Counted, COUNT};

#[test]
fn spaceball_streams_without_allocating() {
    let cfg: vrpn::drivers::spaceball::Spaceball =
        parse_one("vrpn_Spaceball Spaceball0 /dev/ttyS0 9600\n");
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let analog = AnalogRemote::on_connection("Spaceball0", &conn).unwrap();
    let buttons = ButtonRemote::on_connection("Spaceball0", &conn).unwrap();
    let reports = Rc::new(Cell::new(0u64));
    let (a, b) = (reports.clone(), reports.clone());
    analog.on_report(move |_| a.set(a.get() + 1));
    buttons.on_change(move |_| b.set(b.get() + 1));
    let mut line = VirtualLine::new(
        Counted(driver),
        SpaceballSim::new(SpaceballSimConfig::new(cfg.baud)),
        start(),
        3,
    );
    line.split_reads = true;
    // Set-up, then streaming with garbage and a rescan to warm every path up.
    let noise: &[u8] = b"\x01D\x00\x02^";
    line.run_for(Duration::from_millis(500));
    assert!(line.driver.0.is_streaming());
    let now = line.now().mono;
    line.device.inject(noise, now);
    line.run_for(Duration::from_millis(1500));
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        let now = line.now().mono;
        line.device.inject(noise, now);
    }
    let allocations = COUNT.with(Cell::get);
    let reports = reports.get() - before;
    // 50 packets a second for 5 s: 3 of 4 move the ball, 1 of 4 toggles a button.
    assert!(reports >= 245, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 20);
    assert_eq!(
        allocations, 0,
        "allocations while streaming {reports} reports"
    );
}
