//! The Radamec SPI, TNG-3, raw SGI box, Tek4662 plotter and UNC Python drivers report without
//! allocating: a counting global allocator around every driver call while the simulators
//! stream through them (reads split at random points, garbage on the line; the plotter also
//! moved by pose requests), and around the Python box's samples while its buttons change and
//! bounce.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::devices::poser::PoserRemote;
use vrpn::devices::ServerDevice;
use vrpn::drivers::parport_python::source::StatusSource;
use vrpn::drivers::parport_python::{PythonButtons, READS_PER_SAMPLE, SAMPLE_PERIOD};
use vrpn::drivers::radamec::sim::{RadamecSim, SimConfig as RadamecConfig};
use vrpn::drivers::sgibox::sim::{SgiSim, SimConfig as SgiConfig};
use vrpn::drivers::tek4662::sim::{PlotterSim, SimConfig as PlotterConfig};
use vrpn::drivers::tng3::sim::{SimConfig as Tng3Config, Tng3Sim};
use vrpn::server::config::parse_one;
use vrpn::sim::VirtualLine;
use vrpn::{Connection, TrackerRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use counted_driver::{counted, start, Counted, COUNT};
use streaming_alloc::{assert_streamed, count_reports, quiet_texts, rig, stream};

#[test]
fn radamec_streams_without_allocating() {
    let cfg: vrpn::drivers::radamec::Radamec = parse_one("vrpn_Radamec_SPI R0 /dev/ttyS0 38400\n");
    let mut rig = rig("R0", RadamecSim::new(RadamecConfig::new()), 5, |conn| {
        cfg.lifecycle(conn)
    });
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x01, 0xA1, 0x33], 5);
    assert_streamed(n, 100, allocations);
}

#[test]
fn sgibox_streams_without_allocating() {
    // Toggles too: their presses make Alerts and light commands.
    let cfg: vrpn::drivers::sgibox::SgiBox = parse_one("vrpn_raw_SGIBox S0 /dev/ttyS0 0 1 2 3\n");
    let mut rig = rig("S0", SgiSim::new(SgiConfig::new()), 6, |conn| {
        cfg.lifecycle(conn)
    });
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x01, 0x45, 0xBF], 5);
    assert_streamed(n, 100, allocations);
}

#[test]
fn tng3_streams_without_allocating() {
    let cfg: vrpn::drivers::tng3::Tng3 = parse_one("vrpn_Tng3 T0 /dev/ttyS0 8 8\n");
    let mut rig = rig("T0", Tng3Sim::new(Tng3Config::new()), 6, |conn| {
        cfg.lifecycle(conn)
    });
    let (n, allocations) = stream(&mut rig.line, &rig.reports, &[0x33, 0x55, 0x12], 5);
    assert_streamed(n, 200, allocations);
}

#[test]
fn tek4662_follows_and_moves_the_pen_without_allocating() {
    quiet_texts();
    let cfg: vrpn::drivers::tek4662::Tek4662 = parse_one("vrpn_Tek4662 P0 /dev/ttyS0 1200\n");
    let conn = Connection::new_loopback();
    let reports = Rc::new(Cell::new(0u64));
    let tracker = TrackerRemote::on_connection("P0", &conn).unwrap();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let poser = PoserRemote::on_connection("P0", &conn).unwrap();
    let driver = cfg.lifecycle(&conn).unwrap();
    let mut sim = PlotterConfig::new(1200);
    sim.wander = true;
    let mut line = VirtualLine::new(Counted(driver), PlotterSim::new(sim), start(), 7);
    line.split_reads = true;
    // Each second: a pose request and garbage just after an answer, between two.
    let run = |line: &mut VirtualLine<_, PlotterSim>, seconds: u32| {
        for k in 0..seconds {
            let x = f64::from(k % 7) * 0.05;
            poser
                .request_pose(
                    line.now().wall,
                    [x, 0.2 - x / 2.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                )
                .unwrap();
            line.run_for(Duration::from_millis(400));
            let heard = reports.get();
            assert!(line.run_until(Duration::from_millis(600), |_| reports.get() > heard));
            line.inject(&[0x00, 0x7a, 0x31]);
            line.run_for(Duration::from_millis(300));
        }
    };
    run(&mut line, 3);
    assert!(line.driver.0.is_streaming());
    COUNT.with(|c| c.set(0));
    let (before, moves) = (reports.get(), line.device.moves());
    run(&mut line, 8);
    let n = reports.get() - before;
    assert!(n >= 24, "{n} reports");
    assert!(line.device.moves() - moves >= 6);
    assert!(line.driver.0.stats().skipped_bytes > 0);
    assert_eq!(
        COUNT.with(Cell::get),
        0,
        "allocations while sending {n} reports"
    );
}

/// A parallel port whose buttons change every few samples and bounce now and then, counting
/// nothing on the heap.
struct Pattern {
    reads: u64,
}

impl StatusSource for Pattern {
    fn open(&mut self) -> std::io::Result<()> {
        Ok(())
    }
    fn read_status(&mut self) -> std::io::Result<u8> {
        self.reads += 1;
        let sample = self.reads / READS_PER_SAMPLE as u64;
        // Every 7th sample bounces: one read of it differs.
        let bounce = sample % 7 == 3 && self.reads % READS_PER_SAMPLE as u64 == 5;
        let state = ((sample / 3) as u8) << 3 & 0xF8;
        Ok(if bounce { state ^ 0x40 } else { state })
    }
    fn close(&mut self) {}
    fn path(&self) -> &str {
        "/dev/parport0"
    }
}

#[test]
fn python_box_samples_without_allocating() {
    quiet_texts();
    let conn = Connection::new_loopback();
    let (reports, _a, _b) = count_reports("P0", &conn);
    let mut device = PythonButtons::new("P0", Pattern { reads: 0 }, &conn).unwrap();
    let mut now = start();
    let mut run = |device: &mut PythonButtons<Pattern>, samples: u32| {
        for _ in 0..samples {
            counted(|| device.mainloop(now));
            conn.mainloop().unwrap();
            now = now.plus(SAMPLE_PERIOD);
        }
    };
    run(&mut device, 200);
    COUNT.with(|c| c.set(0));
    let before = reports.get();
    run(&mut device, 1000);
    let n = reports.get() - before;
    let stats = device.stats();
    assert!(n >= 300, "{n} reports");
    assert!(stats.bouncing >= 100, "{stats:?}");
    assert_eq!(
        COUNT.with(Cell::get),
        0,
        "allocations while sending {n} reports"
    );
}
