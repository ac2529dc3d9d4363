//! The AD-Box and the Atmel board report without allocating: a counting global allocator
//! around every driver call while the simulators stream through them (reads split at random
//! points, garbage on the line), and, for the Atmel, while a client keeps asking for writes.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::driver::{Lifecycle, Protocol};
use vrpn::drivers::adbox::sim::{AdBoxSim, SimConfig as AdBoxConfig};
use vrpn::drivers::atmel::sim::{AtmelSim, SimConfig as AtmelConfig};
use vrpn::server::config::parse_one;
use vrpn::sim::{DeviceModel, VirtualLine};
use vrpn::{AnalogRemote, ButtonRemote, Connection};

#[path = "common/counted_driver.rs"]
mod counted_driver;
use counted_driver::{start, Counted, COUNT};

type Line<P, M> = VirtualLine<Counted<Lifecycle<P>>, M>;

/// Counts every Analog and Button report `name` sends on `conn`.
fn count_reports(name: &str, conn: &Connection) -> (Rc<Cell<u64>>, AnalogRemote, ButtonRemote) {
    let n = Rc::new(Cell::new(0u64));
    let analog = AnalogRemote::on_connection(name, conn).unwrap();
    let buttons = ButtonRemote::on_connection(name, conn).unwrap();
    let (a, b) = (n.clone(), n.clone());
    analog.on_report(move |_| a.set(a.get() + 1));
    buttons.on_change(move |_| b.set(b.get() + 1));
    (n, analog, buttons)
}

/// Streams 5 s in steps of `step`, with `noise` on the line once a second and `each` called
/// before every step, after two seconds of warm-up doing the same; returns the reports and
/// allocations of the counted part.
fn stream<P: Protocol, M: DeviceModel>(
    line: &mut Line<P, M>,
    reports: &Cell<u64>,
    noise: &[u8],
    step: Duration,
    mut each: impl FnMut(&mut Line<P, M>),
) -> (u64, u64) {
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
    for _ in 0..5 {
        second(line);
    }
    (reports.get() - before, COUNT.with(Cell::get))
}

fn quiet_texts() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
}

#[test]
fn adbox_streams_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::adbox::AdBox = parse_one("vrpn_ADBox A0 /dev/ttyS0 19200\n");
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("A0", &conn);
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = AdBoxSim::new(AdBoxConfig::new(19200));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 3);
    let step = Duration::from_millis(100);
    let (n, allocations) = stream(&mut line, &reports, &[0x41, 0x7F], step, |_| {});
    // About 75 answers a second, each an Analog report (and button changes).
    assert!(n >= 300, "{n} reports");
    assert!(line.driver.0.stats().skipped_bytes > 0);
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}

#[test]
fn atmel_reads_and_writes_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::atmel::Atmel = parse_one(
        "vrpn_Atmel A0 /dev/ttyS0 9600 4\nvrpn_Atmel 0 RO\nvrpn_Atmel 1 RO\n\
         vrpn_Atmel 2 RW\nvrpn_Atmel 3 WO\nvrpn_Atmel -1 END\n",
    );
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("A0", &conn);
    let out = AnalogOutputRemote::on_connection("A0", &conn).unwrap();
    let driver = cfg.lifecycle(&conn).unwrap();
    let sim = AtmelSim::new(AtmelConfig::new(9600));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 4);
    // A write to channel 2 or 3 asked for every 50 ms, the reads going on between.
    let mut k = 0u32;
    let step = Duration::from_millis(50);
    let (n, allocations) = stream(&mut line, &reports, &[0x00, 0x7F, 0x41], step, |_| {
        k += 1;
        out.request_change_channel_value(2 + (k % 2) as i32, f64::from(k % 256))
            .unwrap();
    });
    assert!(n >= 300, "{n} reports");
    // 20 requests a second for 7 s, each written once.
    let writes = line.device.writes().len();
    assert!((130..=140).contains(&writes), "{writes} writes");
    assert_eq!(allocations, 0, "allocations while sending {n} reports");
}
