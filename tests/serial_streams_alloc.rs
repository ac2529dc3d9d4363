//! Serial devices that stream (the Spaceball, the 5DT gloves, the Streaming Arduino) report
//! without allocating: checked with a counting global allocator around every driver call
//! while the simulators stream through them, with reads split at random points and damage on
//! the line. (The Zaber, the BiosciencesTools and the Nikon: `serial_controls_alloc.rs`.)

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::glove5dt::sim::{GloveSim, SimConfig as GloveSimConfig};
use vrpn::drivers::glove5dt16::sim::{Glove16Sim, SimConfig as Glove16SimConfig};
use vrpn::drivers::spaceball::sim::{SimConfig as SpaceballSimConfig, SpaceballSim};
use vrpn::drivers::streaming_arduino::sim::{ArduinoSim, SimConfig as ArduinoSimConfig};
use vrpn::serial::SerialDriver;
use vrpn::server::config::parse_one;
use vrpn::sim::DeviceModel;
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

/// Streams `device` through `driver` (an Analog named `name`) for 5 s after a warm-up, with
/// `noise` put on the line once a second, and counts allocations inside the driver's calls.
/// Returns the reports heard and the bytes skipped.
fn stream_analog<D: SerialDriver + HasStats, M: DeviceModel>(
    conn: &Connection,
    name: &str,
    driver: D,
    device: M,
    inject: fn(&mut M, &[u8], std::time::Instant),
    noise: &[u8],
) -> (u64, u64) {
    let analog = AnalogRemote::on_connection(name, conn).unwrap();
    let reports = Rc::new(Cell::new(0u64));
    let a = reports.clone();
    analog.on_report(move |_| a.set(a.get() + 1));
    let mut line = VirtualLine::new(Counted(driver), device, start(), 9);
    line.split_reads = true;
    line.run_for(Duration::from_millis(1000));
    let now = line.now().mono;
    inject(&mut line.device, noise, now);
    line.run_for(Duration::from_millis(1000));
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        let now = line.now().mono;
        inject(&mut line.device, noise, now);
    }
    let allocations = COUNT.with(Cell::get);
    let reports = reports.get() - before;
    assert_eq!(
        allocations, 0,
        "{name}: allocations while streaming {reports} reports"
    );
    (reports, line.driver.0.skipped())
}

/// The lifecycle's count of skipped bytes.
trait HasStats {
    fn skipped(&self) -> u64;
}

impl<P: vrpn::driver::Protocol> HasStats for vrpn::driver::Lifecycle<P> {
    fn skipped(&self) -> u64 {
        self.stats().skipped_bytes
    }
}

#[test]
fn gloves_and_arduino_stream_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();

    let cfg: vrpn::drivers::glove5dt::Glove5dt = parse_one("vrpn_5dt g1 /dev/ttyS0 19200 1 0\n");
    let (n, skipped) = stream_analog(
        &conn,
        "g1",
        cfg.lifecycle(&conn).unwrap(),
        GloveSim::new(GloveSimConfig::new(19200)),
        GloveSim::inject,
        &[1, 2, 3],
    );
    // Polled: one record per request and answer, about 150 a second at 19200 baud.
    assert!(
        n >= 500 && skipped >= 15,
        "5DT polled: {n} reports, {skipped} skipped"
    );

    let cfg: vrpn::drivers::glove5dt::Glove5dt = parse_one("vrpn_5dt g2 /dev/ttyS0 9600 2 1\n");
    let (n, skipped) = stream_analog(
        &conn,
        "g2",
        cfg.lifecycle(&conn).unwrap(),
        GloveSim::new(GloveSimConfig::new(9600)),
        GloveSim::inject,
        &[0x80, 1, 2],
    );
    assert!(
        n >= 400 && skipped >= 15,
        "5DT wireless: {n} reports, {skipped} skipped"
    );

    let cfg: vrpn::drivers::glove5dt16::Glove5dt16 = parse_one("vrpn_5dt16 g3 /dev/ttyS0 19200\n");
    let (n, skipped) = stream_analog(
        &conn,
        "g3",
        cfg.lifecycle(&conn).unwrap(),
        Glove16Sim::new(Glove16SimConfig::new(19200)),
        Glove16Sim::inject,
        b"<x<",
    );
    assert!(
        n >= 180 && skipped >= 10,
        "5DT glove 16: {n} reports, {skipped} skipped"
    );

    let cfg: vrpn::drivers::streaming_arduino::StreamingArduino =
        parse_one("vrpn_Streaming_Arduino a1 /dev/ttyS0 4\n");
    let (n, skipped) = stream_analog(
        &conn,
        "a1",
        cfg.lifecycle(&conn).unwrap(),
        ArduinoSim::new(ArduinoSimConfig::new(115_200)),
        ArduinoSim::inject,
        b"x1,2\n",
    );
    assert!(
        n >= 900 && skipped >= 25,
        "Streaming Arduino: {n} reports, {skipped} skipped"
    );
}
