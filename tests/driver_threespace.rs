//! The Polhemus 3SPACE and ISOTRAK drivers end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving the driver's vrpn.cfg line, and a TCP client on 127.0.0.1.
//! Checked against the simulator's own log (see `common/tracker_e2e.rs`): exact values in
//! order with first-byte stamps (and the ISOTRAK's stylus switch as a button), garbage between
//! records, silence and the watchdog's reset, unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::threespace::record::Model;
use vrpn::drivers::threespace::sim::{SimConfig, ThreeSpaceSim};
use vrpn::sim::rig::Client;
use vrpn::sim::SimulatedDevice;

#[path = "common/tracker_e2e.rs"]
mod tracker_e2e;
use tracker_e2e::{assert_stylus_toggles, serve, values, Rig, Values};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn sent(sim: &SimulatedDevice<ThreeSpaceSim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|r| (r.sample.expected(), r.first_byte))
            .unzip()
    })
}

fn run(model: Model, line: &str, name: &str, stations: Vec<u8>, stylus: Option<&str>) {
    let sim = SimulatedDevice::start(model.label(), move || {
        let mut cfg = SimConfig::new(model, 38400);
        cfg.keep_log = true;
        cfg.stations = stations;
        ThreeSpaceSim::new(cfg)
    })
    .unwrap();
    let (t0, server, client) = serve(SERVER, &sim, line, name);
    let pen = stylus.map(|p| Client::connect(p, server.port(), &[Interface::Button]).unwrap());
    let rig = Rig {
        sim: &sim,
        server: &server,
        client: &client,
        t0,
        what: model.label(),
        sent: &sent,
        seen: &values,
    };
    rig.start(60, 3.0);
    // The stylus changes every 7 records.
    if let Some(pen) = &pen {
        assert_stylus_toggles(pen);
    }
    rig.garbage(&[&[0x00, 0x7F, 0x41], &[0x85, 0x12, 0x33], &[0xFF]], 30);
    rig.silence(
        "Tracker failed, trying to reset",
        30,
        Duration::from_secs(8),
    );
    rig.unplug(30, Duration::from_secs(6));
}

#[test]
fn isotrak_with_a_stylus_through_vrpn_server_to_a_client() {
    run(
        Model::Isotrak,
        "vrpn_Tracker_Isotrak Iso0 {PATH} 38400 /\nStylus Pen0 1\n",
        "Iso0",
        vec![1, 2],
        Some("Pen0"),
    );
}

#[test]
fn threespace_through_vrpn_server_to_a_client() {
    run(
        Model::ThreeSpace,
        "vrpn_Tracker_3Space Tracker0 {PATH} 38400\n",
        "Tracker0",
        vec![1, 3],
        None,
    );
}
