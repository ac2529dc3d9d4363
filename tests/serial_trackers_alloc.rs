//! The serial trackers of the 3SPACE family, the Liberty, the Polaris, the Crossbow and the
//! GPS, the Logitech 3D mouse, the inertia mouse and the Global Haptics Orb report without allocating: a counting global allocator around
//! every driver call while the simulators stream through them, with reads split at random
//! points and damage on the line.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use vrpn::drivers::crossbow::sim::{CrossbowSim, SimConfig as CrossbowSimConfig};
use vrpn::drivers::crossbow::Crossbow;
use vrpn::drivers::gps::sim::{GpsSim, SimConfig as GpsSimConfig};
use vrpn::drivers::gps::Gps;
use vrpn::drivers::inertiamouse::sim::{InertiaSim, SimConfig as InertiaSimConfig};
use vrpn::drivers::inertiamouse::InertiaMouse;
use vrpn::drivers::liberty::sim::{Kind, LibertySim, SimConfig as LibertySimConfig};
use vrpn::drivers::liberty::Liberty;
use vrpn::drivers::orb::sim::{OrbSim, SimConfig as OrbSimConfig};
use vrpn::drivers::orb::Orb;
use vrpn::drivers::polaris::sim::{PolarisSim, SimConfig as PolarisSimConfig};
use vrpn::drivers::polaris::Polaris;
use vrpn::drivers::threedmouse::sim::{SimConfig as ThreeDMouseSimConfig, ThreeDMouseSim};
use vrpn::drivers::threedmouse::ThreeDMouse;
use vrpn::drivers::threespace::record::Model;
use vrpn::drivers::threespace::sim::{SimConfig as ThreeSpaceSimConfig, ThreeSpaceSim};
use vrpn::drivers::threespace::ThreeSpace;
use vrpn::serial::SerialDriver;
use vrpn::server::config::parse_one;
use vrpn::sim::{DeviceModel, VirtualLine};
use vrpn::{AnalogRemote, ButtonRemote, Connection, DialRemote, TrackerRemote};

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

fn counter() -> Rc<Cell<u64>> {
    Rc::new(Cell::new(0))
}

#[test]
fn isotrak_and_3space_stream_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    for (text, model) in [
        (
            "vrpn_Tracker_Isotrak Iso0 /dev/ttyS0 38400 /\nStylus Pen 0\n",
            Model::Isotrak,
        ),
        (
            "vrpn_Tracker_3Space T0 /dev/ttyS0 38400\n",
            Model::ThreeSpace,
        ),
    ] {
        let cfg: ThreeSpace = parse_one(text);
        let conn = Connection::new_loopback();
        let driver = cfg.lifecycle(&conn).unwrap();
        let tracker = TrackerRemote::on_connection(&cfg.name, &conn).unwrap();
        let reports = counter();
        let r = reports.clone();
        tracker.on_pose(move |_| r.set(r.get() + 1));
        let pen = ButtonRemote::on_connection("Pen", &conn).unwrap();
        let r = reports.clone();
        pen.on_change(move |_| r.set(r.get() + 1));
        let mut sim = ThreeSpaceSimConfig::new(model, cfg.baud);
        sim.stations = vec![1, 2];
        let mut line = VirtualLine::new(Counted(driver), ThreeSpaceSim::new(sim), start(), 3);
        let (allocations, reports) = stream(&mut line, &reports, &[0x01, 0x85, 0x02, 0x7F]);
        assert!(reports >= 295, "{model:?}: {reports} reports");
        assert!(line.driver.0.stats().skipped_bytes >= 20);
        assert_eq!(allocations, 0, "{model:?}: allocations while streaming");
    }
}

#[test]
fn liberty_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let text = "vrpn_Tracker_Liberty L /dev/ttyS0 115200 /\nStylus Pen 1\n";
    let cfg: Liberty = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("L", &conn).unwrap();
    let reports = counter();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let pen = ButtonRemote::on_connection("Pen", &conn).unwrap();
    let r = reports.clone();
    pen.on_change(move |_| r.set(r.get() + 1));
    let mut sim = LibertySimConfig::new(Kind::Liberty, cfg.baud);
    sim.stations = vec![1, 2];
    let mut line = VirtualLine::new(Counted(driver), LibertySim::new(sim), start(), 4);
    let (allocations, reports) = stream(&mut line, &reports, b"LYx\x02PA ");
    assert!(reports >= 590, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 20);
    assert_eq!(allocations, 0, "allocations while streaming");
}

#[test]
fn polaris_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let dir = std::env::temp_dir().join(format!("vrpn-polaris-alloc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b) = (dir.join("a.rom"), dir.join("b.rom"));
    std::fs::write(&a, [7u8; 200]).unwrap();
    std::fs::write(&b, [9u8; 64]).unwrap();
    let text = format!(
        "vrpn_Tracker_NDI_Polaris P /dev/ttyUSB0 2\n{}\n{}\n",
        a.display(),
        b.display()
    );
    let cfg: Polaris = parse_one(&text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("P", &conn).unwrap();
    let reports = counter();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let mut sim = PolarisSimConfig::new();
    sim.missing_every = Some(5);
    let mut line = VirtualLine::new(Counted(driver), PolarisSim::new(sim), start(), 5);
    let (allocations, reports) = stream(&mut line, &reports, b"01+0\r\x00");
    // 60 frames a second, two tools, one frame in five of each missing; a reply the noise
    // breaks costs the wait for the next TX.
    assert!(reports >= 350, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 20);
    assert_eq!(allocations, 0, "allocations while streaming");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn crossbow_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: Crossbow = parse_one("vrpn_Tracker_Crossbow X /dev/ttyS0 38400 2.0 100\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("X", &conn).unwrap();
    let reports = counter();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let r = reports.clone();
    tracker.on_acceleration(move |_| r.set(r.get() + 1));
    let r = reports.clone();
    tracker.on_velocity(move |_| r.set(r.get() + 1));
    let sim = CrossbowSim::new(CrossbowSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 6);
    let (allocations, reports) = stream(&mut line, &reports, &[0xAA, 0x55, 0x01]);
    assert!(reports >= 3 * 500, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 10);
    assert_eq!(allocations, 0, "allocations while streaming");
}

#[test]
fn threedmouse_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: ThreeDMouse = parse_one("vrpn_Tracker_3DMouse M /dev/ttyS0 19200 3\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("M", &conn).unwrap();
    let reports = counter();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let buttons = ButtonRemote::on_connection("M", &conn).unwrap();
    let r = reports.clone();
    buttons.on_change(move |_| r.set(r.get() + 1));
    let sim = ThreeDMouseSim::new(ThreeDMouseSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 8);
    let (allocations, reports) = stream(&mut line, &reports, &[0x01, 0xC5, 0x12]);
    // About 85 records a second (16 bytes at 19200 baud, a 3 ms answer delay).
    assert!(reports >= 350, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 10);
    assert_eq!(allocations, 0, "allocations while streaming");
}

#[test]
fn gps_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: Gps = parse_one("vrpn_Tracker_GPS G /dev/ttyS0 38400\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("G", &conn).unwrap();
    let reports = counter();
    let r = reports.clone();
    tracker.on_pose(move |_| r.set(r.get() + 1));
    let mut sim = GpsSimConfig::new(cfg.baud);
    sim.no_fix_every = Some(4);
    let mut line = VirtualLine::new(Counted(driver), GpsSim::new(sim), start(), 7);
    let (allocations, reports) = stream(&mut line, &reports, b"$GPGGA,1*77\r\n$x");
    // Ten epochs a second, three in four with a fix.
    assert!(reports >= 30, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 20);
    assert_eq!(allocations, 0, "allocations while streaming");
}

#[test]
fn inertia_mouse_streams_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: InertiaMouse = parse_one("vrpn_inertiamouse M /dev/ttyS0 115200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = counter();
    let analog = AnalogRemote::on_connection("M", &conn).unwrap();
    let r = reports.clone();
    analog.on_report(move |_| r.set(r.get() + 1));
    let buttons = ButtonRemote::on_connection("M", &conn).unwrap();
    let r = reports.clone();
    buttons.on_change(move |_| r.set(r.get() + 1));
    let sim = InertiaSim::new(InertiaSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 8);
    let (allocations, reports) = stream(&mut line, &reports, b"Dx\nBB");
    // A record every 10 ms; most change a channel.
    assert!(reports >= 300, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 10);
    assert_eq!(allocations, 0, "allocations while streaming");
}

#[test]
fn orb_reports_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let cfg: Orb = parse_one("vrpn_GlobalHapticsOrb O /dev/ttyS0 19200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = counter();
    let analog = AnalogRemote::on_connection("O", &conn).unwrap();
    let r = reports.clone();
    analog.on_report(move |_| r.set(r.get() + 1));
    let buttons = ButtonRemote::on_connection("O", &conn).unwrap();
    let r = reports.clone();
    buttons.on_change(move |_| r.set(r.get() + 1));
    let dials = DialRemote::on_connection("O", &conn).unwrap();
    let r = reports.clone();
    dials.on_update(move |_| r.set(r.get() + 1));
    let sim = OrbSim::new(OrbSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 9);
    let (allocations, reports) = stream(&mut line, &reports, &[0x41, 0x7F]);
    // An event every 5 ms.
    assert!(reports >= 900, "{reports} reports");
    assert!(line.driver.0.stats().skipped_bytes >= 10);
    assert_eq!(allocations, 0, "allocations while streaming");
}
