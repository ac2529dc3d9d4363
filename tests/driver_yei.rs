//! The YEI 3-Space Sensor driver end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_YEI_3Space_Sensor`, and a TCP client of its Tracker,
//! Analog and Button on 127.0.0.1: exact reports in order with first-byte stamps, garbage
//! between records, silence (the 2 s timeout's reset), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::yei::sim::{SimConfig, YeiSim};
use vrpn::sim::rig::{Client, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::Now;

#[path = "common/faults.rs"]
mod faults;
#[path = "common/yei_reports.rs"]
mod yei_reports;
use yei_reports::count;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

#[test]
fn yei_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("yei", || {
        let mut cfg = SimConfig::new(115_200);
        cfg.keep_log = true;
        YeiSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_YEI_3Space_Sensor YEI0 {} 115200 1 0 50.0 0 0 1 0 \\\n238,1,1,0\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "YEI0",
        server.port(),
        &[Interface::Tracker, Interface::Analog, Interface::Button],
    )
    .unwrap();
    client.wait_until(Duration::from_secs(10), "reports", &server, |c| {
        count(c, 0) >= 200
    });
    let started = Instant::now();
    let check = || yei_reports::check(&sim, &client, 0, t0, "YEI");
    check();
    let setup = sim.model(|m| {
        let u = &m.units[0];
        (u.calibrations, u.tares, u.ascii.clone(), m.bad_commands)
    });
    assert_eq!(setup, (1, 0, vec!["238,1,1,0".to_owned()], 0));
    let junk: [&[u8]; 3] = [b"A", &[0x7F, 0x55], &[0x3F, 0x80, 0, 0, 0x20]];
    faults::garbage_costs_nothing(&sim, &client, &server, &junk, count, 100);
    check();
    assert!(started.elapsed() < Duration::from_secs(60));
    // Silence: the 2 s timeout, a reset, records again when it speaks.
    let from = client.len();
    sim.set_mute(true);
    client.wait_text(
        from,
        "vrpn_YEI_3Space::mainloop: Timeout",
        Duration::from_secs(5),
        &server,
    );
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(8),
        "reports after silence",
        &server,
        |c| count(c, from) >= 100,
    );
    // Unplugged: reported, reopened, set up again, resumed.
    faults::unplugged_and_reopened(&sim, &client, &server, count, 100);
    assert_eq!(sim.model(|m| m.units[0].calibrations), 2);
}
