//! The Magellan and CerealBox drivers report without allocating: checked with a counting
//! global allocator around every driver call while the simulated devices stream through
//! them with reads split at random points, garbage on the line (and its notes), the
//! Magellan's idle queries and the CerealBox's repeated requests.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::cerealbox::sim::{self as cereal, CerealSim};
use vrpn::drivers::magellan::sim::{self as magellan, MagellanSim};
use vrpn::sim::VirtualLine;

use vrpn::server::config::parse_one;
use vrpn::{AnalogRemote, ButtonRemote, Connection, DialRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
use counted_driver::{start, Counted, COUNT};

fn counter() -> (Rc<Cell<u64>>, Rc<Cell<u64>>) {
    let c = Rc::new(Cell::new(0u64));
    (c.clone(), c)
}

#[test]
fn magellan_streams_without_allocating() {
    let text = "vrpn_Magellan Magellan0 /dev/ttyS0 9600\n";
    let cfg: vrpn::drivers::magellan::Magellan = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let analog = AnalogRemote::on_connection("Magellan0", &conn).unwrap();
    let buttons = ButtonRemote::on_connection("Magellan0", &conn).unwrap();
    let (reports, r) = counter();
    analog.on_report(move |_| r.set(r.get() + 1));
    let (changes, c) = counter();
    buttons.on_change(move |_| c.set(c.get() + 1));
    let sim = MagellanSim::new(magellan::SimConfig::default());
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 3);
    line.split_reads = true;
    // Reset, streaming, a resynchronisation note and an idle query, to warm every path up.
    line.run_for(Duration::from_millis(500));
    assert!(line.driver.0.is_streaming());
    line.inject(b"\x00x?");
    let now = line.now();
    line.device.set_moving(false, now);
    line.run_for(Duration::from_millis(2500));
    let now = line.now();
    line.device.set_moving(true, now);
    line.run_for(Duration::from_millis(500));
    COUNT.with(|c| c.set(0));
    let (r0, c0, p0) = (
        reports.get(),
        changes.get(),
        line.driver.0.protocol().probes(),
    );
    for i in 0..5 {
        line.run_for(Duration::from_secs(1));
        line.inject(b"\x01zz\r");
        if i == 2 {
            let now = line.now();
            line.device.set_moving(false, now);
            line.run_for(Duration::from_millis(2100));
            let now = line.now();
            line.device.set_moving(true, now);
        }
    }
    let allocations = COUNT.with(Cell::get);
    let (reports, changes) = (reports.get() - r0, changes.get() - c0);
    assert!(reports > 150, "{reports} analog reports");
    assert!(changes > 100, "{changes} button changes");
    assert!(line.driver.0.protocol().probes() > p0);
    assert!(line.driver.0.protocol().skipped_bytes() >= 5 * 4);
    assert_eq!(
        allocations, 0,
        "allocations while sending {reports} analog reports and {changes} button changes"
    );
}

#[test]
fn cerealbox_streams_without_allocating() {
    let text = "vrpn_CerealBox Cereal0 /dev/ttyS0 19200 24 8 8\n";
    let cfg: vrpn::drivers::cerealbox::CerealBox = parse_one(text);
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let analog = AnalogRemote::on_connection("Cereal0", &conn).unwrap();
    let buttons = ButtonRemote::on_connection("Cereal0", &conn).unwrap();
    let dials = DialRemote::on_connection("Cereal0", &conn).unwrap();
    let (reports, r) = counter();
    analog.on_report(move |_| r.set(r.get() + 1));
    let (changes, c) = counter();
    buttons.on_change(move |_| c.set(c.get() + 1));
    let (updates, u) = counter();
    dials.on_update(move |_| u.set(u.get() + 1));
    let mut line = VirtualLine::new(
        Counted(driver),
        CerealSim::new(cereal::SimConfig::default()),
        start(),
        4,
    );
    line.split_reads = true;
    line.run_for(Duration::from_millis(300));
    assert!(line.driver.0.is_streaming());
    line.inject(b"\x00x");
    line.device.ignore_requests(1);
    line.run_for(Duration::from_millis(1500));
    COUNT.with(|c| c.set(0));
    let (r0, c0, u0, p0) = (
        reports.get(),
        changes.get(),
        updates.get(),
        line.driver.0.protocol().repolls(),
    );
    for _ in 0..5 {
        line.run_for(Duration::from_millis(1003));
        line.inject(b"\x02q\x7f");
        line.device.ignore_requests(1);
    }
    let allocations = COUNT.with(Cell::get);
    let (reports, changes, updates) = (reports.get() - r0, changes.get() - c0, updates.get() - u0);
    assert!(reports > 500, "{reports} analog reports");
    assert!(
        changes > 500 && updates > 500,
        "{changes} changes, {updates} updates"
    );
    assert!(line.driver.0.protocol().repolls() >= p0 + 4);
    assert_eq!(
        allocations, 0,
        "allocations while sending {reports} analog reports, {changes} button changes and \
         {updates} dial updates"
    );
}
