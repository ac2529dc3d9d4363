//! The serial trackers of the 3SPACE family, the Liberty, the Polaris, the Crossbow and the
//! GPS, the Logitech 3D mouse, the inertia mouse and the Global Haptics Orb report without allocating: a counting global allocator around
//! every driver call while the simulators stream through them, with reads split at random
//! points and damage on the line.

use std::cell::Cell;
use std::rc::Rc;

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
use vrpn::server::config::parse_one;
use vrpn::sim::VirtualLine;
use vrpn::{AnalogRemote, ButtonRemote, Connection, DialRemote, TrackerRemote};

#[path = "common/counted_driver.rs"]
mod counted_driver;
#[path = "common/streaming_alloc.rs"]
mod streaming_alloc;
use counted_driver::{start, Counted};
use streaming_alloc::{assert_streamed_skipping, bump, quiet_texts, stream_after_warm_up};

fn counter() -> Rc<Cell<u64>> {
    Rc::new(Cell::new(0))
}

#[test]
fn isotrak_and_3space_stream_without_allocating() {
    quiet_texts();
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
        tracker.on_pose(bump(&reports));
        let pen = ButtonRemote::on_connection("Pen", &conn).unwrap();
        pen.on_change(bump(&reports));
        let mut sim = ThreeSpaceSimConfig::new(model, cfg.baud);
        sim.stations = vec![1, 2];
        let mut line = VirtualLine::new(Counted(driver), ThreeSpaceSim::new(sim), start(), 3);
        let (allocations, reports) =
            stream_after_warm_up(&mut line, &reports, &[0x01, 0x85, 0x02, 0x7F]);
        assert!(reports >= 295, "{model:?}: {reports} reports");
        assert!(line.driver.0.stats().skipped_bytes >= 20);
        assert_eq!(allocations, 0, "{model:?}: allocations while streaming");
    }
}

#[test]
fn liberty_streams_without_allocating() {
    quiet_texts();
    let text = "vrpn_Tracker_Liberty L /dev/ttyS0 115200 /\nStylus Pen 1\n";
    let cfg: Liberty = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("L", &conn).unwrap();
    let reports = counter();
    tracker.on_pose(bump(&reports));
    let pen = ButtonRemote::on_connection("Pen", &conn).unwrap();
    pen.on_change(bump(&reports));
    let mut sim = LibertySimConfig::new(Kind::Liberty, cfg.baud);
    sim.stations = vec![1, 2];
    let mut line = VirtualLine::new(Counted(driver), LibertySim::new(sim), start(), 4);
    let streamed = stream_after_warm_up(&mut line, &reports, b"LYx\x02PA ");
    assert_streamed_skipping(&line, streamed, 590, 20);
}

#[test]
fn polaris_streams_without_allocating() {
    quiet_texts();
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
    tracker.on_pose(bump(&reports));
    let mut sim = PolarisSimConfig::new();
    sim.missing_every = Some(5);
    let mut line = VirtualLine::new(Counted(driver), PolarisSim::new(sim), start(), 5);
    let streamed = stream_after_warm_up(&mut line, &reports, b"01+0\r\x00");
    // 60 frames a second, two tools, one frame in five of each missing; a reply the noise
    // breaks costs the wait for the next TX.
    assert_streamed_skipping(&line, streamed, 350, 20);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn crossbow_streams_without_allocating() {
    quiet_texts();
    let cfg: Crossbow = parse_one("vrpn_Tracker_Crossbow X /dev/ttyS0 38400 2.0 100\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("X", &conn).unwrap();
    let reports = counter();
    tracker.on_pose(bump(&reports));
    tracker.on_acceleration(bump(&reports));
    tracker.on_velocity(bump(&reports));
    let sim = CrossbowSim::new(CrossbowSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 6);
    let streamed = stream_after_warm_up(&mut line, &reports, &[0xAA, 0x55, 0x01]);
    assert_streamed_skipping(&line, streamed, 3 * 500, 10);
}

#[test]
fn threedmouse_streams_without_allocating() {
    quiet_texts();
    let cfg: ThreeDMouse = parse_one("vrpn_Tracker_3DMouse M /dev/ttyS0 19200 3\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("M", &conn).unwrap();
    let reports = counter();
    tracker.on_pose(bump(&reports));
    let buttons = ButtonRemote::on_connection("M", &conn).unwrap();
    buttons.on_change(bump(&reports));
    let sim = ThreeDMouseSim::new(ThreeDMouseSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 8);
    let streamed = stream_after_warm_up(&mut line, &reports, &[0x01, 0xC5, 0x12]);
    // About 85 records a second (16 bytes at 19200 baud, a 3 ms answer delay).
    assert_streamed_skipping(&line, streamed, 350, 10);
}

#[test]
fn gps_streams_without_allocating() {
    quiet_texts();
    let cfg: Gps = parse_one("vrpn_Tracker_GPS G /dev/ttyS0 38400\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let tracker = TrackerRemote::on_connection("G", &conn).unwrap();
    let reports = counter();
    tracker.on_pose(bump(&reports));
    let mut sim = GpsSimConfig::new(cfg.baud);
    sim.no_fix_every = Some(4);
    let mut line = VirtualLine::new(Counted(driver), GpsSim::new(sim), start(), 7);
    let streamed = stream_after_warm_up(&mut line, &reports, b"$GPGGA,1*77\r\n$x");
    // Ten epochs a second, three in four with a fix.
    assert_streamed_skipping(&line, streamed, 30, 20);
}

#[test]
fn inertia_mouse_streams_without_allocating() {
    quiet_texts();
    let cfg: InertiaMouse = parse_one("vrpn_inertiamouse M /dev/ttyS0 115200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = counter();
    let analog = AnalogRemote::on_connection("M", &conn).unwrap();
    analog.on_report(bump(&reports));
    let buttons = ButtonRemote::on_connection("M", &conn).unwrap();
    buttons.on_change(bump(&reports));
    let sim = InertiaSim::new(InertiaSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 8);
    let streamed = stream_after_warm_up(&mut line, &reports, b"Dx\nBB");
    // A record every 10 ms; most change a channel.
    assert_streamed_skipping(&line, streamed, 300, 10);
}

#[test]
fn orb_reports_without_allocating() {
    quiet_texts();
    let cfg: Orb = parse_one("vrpn_GlobalHapticsOrb O /dev/ttyS0 19200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let reports = counter();
    let analog = AnalogRemote::on_connection("O", &conn).unwrap();
    analog.on_report(bump(&reports));
    let buttons = ButtonRemote::on_connection("O", &conn).unwrap();
    buttons.on_change(bump(&reports));
    let dials = DialRemote::on_connection("O", &conn).unwrap();
    dials.on_update(bump(&reports));
    let sim = OrbSim::new(OrbSimConfig::new(cfg.baud));
    let mut line = VirtualLine::new(Counted(driver), sim, start(), 9);
    let streamed = stream_after_warm_up(&mut line, &reports, &[0x41, 0x7F]);
    // An event every 5 ms.
    assert_streamed_skipping(&line, streamed, 900, 10);
}
