//! A serial port that cannot be opened, through `vrpn_server`: reported on the server's
//! standard error once (with the reason), not at every retry; told to a client that connects
//! later; and the device is served once it appears. Also `vrpn_device_sim`, the simulators as
//! a program.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::dyna::sim::{DynaSim, SimConfig};
use vrpn::sim::rig::{Client, ServerProcess};
use vrpn::sim::SimulatedDevice;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const DEVICE_SIM: &str = env!("CARGO_BIN_EXE_vrpn_device_sim");

#[test]
fn a_missing_port_is_reported_once_told_to_later_clients_and_served_when_it_appears() {
    // The device's path exists only while it is plugged in.
    let sim = SimulatedDevice::start("status", || DynaSim::new(SimConfig::new(19200))).unwrap();
    sim.unplug();
    let line = format!("vrpn_Tracker_Dyna Dyna0 1 {} 19200\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    // Three retries (one a second): still one line on standard error, with the reason.
    std::thread::sleep(Duration::from_millis(3300));
    let said = server.stderr();
    let cannot: Vec<&str> = said.lines().filter(|l| l.contains("cannot open")).collect();
    assert_eq!(cannot.len(), 1, "{said}");
    assert!(
        cannot[0].contains("Dyna0") && cannot[0].contains("no such file"),
        "{said}"
    );
    // A client that connects now learns why nothing arrives.
    let client = Client::connect("Dyna0", server.port(), &[Interface::Tracker]).unwrap();
    client.wait_text(
        0,
        "cannot open serial port",
        Duration::from_secs(5),
        &server,
    );
    assert!(client.poses().is_empty());
    // Plugged in: opened, reported once more on standard error, served.
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(6),
        "poses once plugged in",
        &server,
        |c| c.poses().len() >= 10,
    );
    let said = server.stderr();
    assert_eq!(
        said.lines().filter(|l| l.contains("cannot open")).count(),
        1,
        "{said}"
    );
    assert_eq!(
        said.lines()
            .filter(|l| l.contains("Dyna0") && l.contains("is open"))
            .count(),
        1,
        "{said}"
    );
    // Unplugged while open: reported once as lost (the retries that follow, of a port that
    // is missing again, once more), then served again when it is back.
    sim.unplug();
    client.wait_text(0, "failed", Duration::from_secs(3), &server);
    std::thread::sleep(Duration::from_millis(2300));
    let said = server.stderr();
    assert_eq!(
        said.lines().filter(|l| l.contains("failed (")).count(),
        1,
        "{said}"
    );
    assert_eq!(
        said.lines().filter(|l| l.contains("cannot open")).count(),
        2,
        "{said}"
    );
}

#[test]
fn the_simulators_run_as_a_program_and_print_the_line_that_serves_them() {
    let list = Command::new(DEVICE_SIM).arg("--list").output().unwrap();
    assert!(list.status.success());
    let text = String::from_utf8(list.stdout).unwrap();
    for kind in [
        "fastrak",
        "flock",
        "magellan",
        "cerealbox",
        "dyna",
        "joylin",
    ] {
        assert!(text.lines().any(|l| l.starts_with(kind)), "{kind}: {text}");
    }
    let bad = Command::new(DEVICE_SIM)
        .args(["nope", "/tmp/x"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("no simulator \"nope\""));

    let dir = std::env::temp_dir().join(format!("vrpn-device-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("tty");
    let mut sim = Command::new(DEVICE_SIM)
        .arg("fastrak")
        .arg(&path)
        .args(["-b", "115200", "-s", "20"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(sim.stdout.take().unwrap());
    let (mut first, mut line) = (String::new(), String::new());
    out.read_line(&mut first).unwrap();
    out.read_line(&mut line).unwrap();
    assert!(first.contains("115200 baud"), "{first}");
    assert_eq!(
        line.trim(),
        format!("vrpn_Tracker_Fastrak Tracker0 {} 115200", path.display())
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("Tracker0", server.port(), &[Interface::Tracker]).unwrap();
    let start = Instant::now();
    client.wait_until(
        Duration::from_secs(10),
        "poses from the simulator",
        &server,
        |c| c.poses().len() >= 40,
    );
    let sensors: std::collections::BTreeSet<usize> =
        client.poses().iter().map(|p| p.sensor).collect();
    assert_eq!(sensors.len(), 4, "four stations");
    eprintln!(
        "vrpn_device_sim fastrak: 40 poses {:?} after connecting",
        start.elapsed()
    );
    let _ = sim.kill();
    let _ = sim.wait();
    let _ = std::fs::remove_dir_all(&dir);
}
