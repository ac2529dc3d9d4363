//! What the serial drivers' zero-allocation tests share: counting a device's reports on an
//! in-process connection, and streaming a driver on a virtual line (reads split at random
//! points, noise on the line once a second) while a counting allocator watches its calls.
//! A test crate that includes this file also includes `counted_driver.rs` as
//! `mod counted_driver`.
#![allow(dead_code)]

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::driver::{Lifecycle, Protocol};
use vrpn::serial::SerialDriver;
use vrpn::sim::{DeviceModel, VirtualLine};
use vrpn::{AnalogRemote, ButtonRemote, Connection};

use super::counted_driver::{start, Counted, COUNT};

/// A driver's lifecycle on a virtual line, its calls counted.
pub type Line<P, M> = VirtualLine<Counted<Lifecycle<P>>, M>;

/// Counts every Analog and Button report `name` sends on `conn` (keep the remotes alive).
pub fn count_reports(name: &str, conn: &Connection) -> (Rc<Cell<u64>>, AnalogRemote, ButtonRemote) {
    let n = Rc::new(Cell::new(0u64));
    let analog = AnalogRemote::on_connection(name, conn).unwrap();
    let buttons = ButtonRemote::on_connection(name, conn).unwrap();
    let (a, b) = (n.clone(), n.clone());
    analog.on_report(move |_| a.set(a.get() + 1));
    buttons.on_change(move |_| b.set(b.get() + 1));
    (n, analog, buttons)
}

/// A counted driver on a virtual line, the loopback connection it serves on, and the count
/// of its Analog and Button reports.
pub struct Rig<P: Protocol, M: DeviceModel> {
    pub line: Line<P, M>,
    pub conn: Connection,
    pub reports: Rc<Cell<u64>>,
    _remotes: (AnalogRemote, ButtonRemote),
}

/// Keeps the drivers' texts off the test output, makes the driver `lifecycle` returns on a
/// loopback connection, counts the reports of its device `name`, and puts the driver, its
/// calls counted, on a virtual line to `device` (random choices seeded with `seed`).
pub fn rig<P: Protocol, M: DeviceModel, E: std::fmt::Debug>(
    name: &str,
    device: M,
    seed: u64,
    lifecycle: impl FnOnce(&Connection) -> Result<Lifecycle<P>, E>,
) -> Rig<P, M> {
    quiet_texts();
    let conn = Connection::new_loopback();
    let (reports, analog, buttons) = count_reports(name, &conn);
    let driver = lifecycle(&conn).unwrap();
    Rig {
        line: VirtualLine::new(Counted(driver), device, start(), seed),
        conn,
        reports,
        _remotes: (analog, buttons),
    }
}

/// The checks after [`stream`]: at least `least` reports and no allocation.
pub fn assert_streamed(n: u64, least: u64, allocations: u64) {
    assert!(n >= least, "{n} reports");
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

/// The checks after [`stream_steps`]: at least `least` reports, the noise skipped, and no
/// allocation.
pub fn assert_streamed_steps(n: u64, least: u64, allocations: u64, skipped: u64) {
    assert!(
        n >= least && skipped > 0,
        "{n} reports, {skipped} bytes skipped"
    );
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

/// Keeps the drivers' texts off the test output.
pub fn quiet_texts() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
}

/// Streams `seconds` with `noise` on the line once a second, after a warm-up with the same
/// noise, and returns (reports, allocations) of the counted part. The noise must be skipped.
pub fn stream<P: Protocol, M: DeviceModel>(
    line: &mut Line<P, M>,
    reports: &Cell<u64>,
    noise: &[u8],
    seconds: u32,
) -> (u64, u64) {
    line.split_reads = true;
    line.run_for(Duration::from_millis(700));
    assert!(line.driver.0.is_streaming());
    line.inject(noise);
    line.run_for(Duration::from_millis(1500));
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    for _ in 0..seconds {
        line.run_for(Duration::from_secs(1));
        line.inject(noise);
    }
    assert!(line.driver.0.stats().skipped_bytes > 0);
    (reports.get() - before, COUNT.with(Cell::get))
}

/// Streams `seconds` in steps of `step`, with `noise` on the line once a second and `each`
/// called before every step (a client asking for something), after two seconds of warm-up
/// doing the same; returns (reports, allocations) of the counted part and the bytes skipped
/// in all.
pub fn stream_steps<P: Protocol, M: DeviceModel>(
    line: &mut Line<P, M>,
    reports: &Cell<u64>,
    noise: &[u8],
    seconds: u32,
    step: Duration,
    mut each: impl FnMut(&mut Line<P, M>),
) -> (u64, u64, u64) {
    line.split_reads = true;
    let steps = (Duration::from_secs(1).as_micros() / step.as_micros()) as u32;
    let mut second = |line: &mut Line<P, M>| {
        for _ in 0..steps {
            each(line);
            line.run_for(step);
        }
        line.inject(noise);
    };
    line.run_for(Duration::from_millis(1200));
    assert!(line.driver.0.is_streaming());
    second(line);
    second(line);
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    for _ in 0..seconds {
        second(line);
    }
    let skipped = line.driver.0.stats().skipped_bytes;
    (reports.get() - before, COUNT.with(Cell::get), skipped)
}

/// A callback that adds one to `n` for each report it is given.
pub fn bump<T>(n: &Rc<Cell<u64>>) -> impl FnMut(&T) + 'static {
    let n = n.clone();
    move |_| n.set(n.get() + 1)
}

/// Streams 5 s with `noise` on the line once a second, after a warm-up of 3.5 s with the
/// same noise; returns (allocations, reports) of the counted part.
pub fn stream_after_warm_up<D: SerialDriver, M: DeviceModel>(
    line: &mut VirtualLine<Counted<D>, M>,
    reports: &Cell<u64>,
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

/// The checks after [`stream_after_warm_up`]: at least `least` reports, at least `skipped`
/// bytes of the noise skipped, and no allocation.
pub fn assert_streamed_skipping<P: Protocol, M: DeviceModel>(
    line: &Line<P, M>,
    (allocations, reports): (u64, u64),
    least: u64,
    skipped: u64,
) {
    assert!(reports >= least, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= skipped);
    assert_eq!(allocations, 0, "allocations while streaming");
}
