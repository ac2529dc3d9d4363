//! The NDI Polaris driver end to end: the simulator on a pseudo-terminal (which carries no
//! RTS, so the tracker keeps its speed across resets, as through some USB adapters), a
//! `vrpn_server` child serving the driver's vrpn.cfg line with two tools, and a TCP client on
//! 127.0.0.1. Checked against the simulator's own log (see `common/tracker_e2e.rs`): exact
//! values in order with first-byte stamps, garbage between replies, silence and the
//! watchdog's reset, unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::drivers::polaris::sim::{PolarisSim, SimConfig};
use vrpn::sim::rig::ServerProcess;
use vrpn::sim::SimulatedDevice;
use vrpn::Now;

#[path = "common/tracker_e2e.rs"]
mod tracker_e2e;
use tracker_e2e::{tracker_client, values, Rig, Values};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn sent(sim: &SimulatedDevice<PolarisSim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| m.sent().iter().map(|r| (r.values, r.first_byte)).unzip())
}

fn rom(dir: &std::path::Path, name: &str, len: usize) -> String {
    let path = dir.join(name);
    let bytes: Vec<u8> = (0..len).map(|i| (i * 13 + len) as u8).collect();
    std::fs::write(&path, bytes).unwrap();
    path.display().to_string()
}

#[test]
fn polaris_with_two_tools_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("polaris", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        cfg.missing_every = Some(7);
        PolarisSim::new(cfg)
    })
    .unwrap();
    let dir = std::env::temp_dir().join(format!("vrpn-polaris-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let line = format!(
        "vrpn_Tracker_NDI_Polaris Tracker0 {} 2\n{}\n{}\n",
        sim.path().display(),
        rom(&dir, "pointer.rom", 600),
        rom(&dir, "reference.rom", 64)
    );
    let t0 = Now::read();
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = tracker_client("Tracker0", &server);
    let rig = Rig {
        sim: &sim,
        server: &server,
        client: &client,
        t0,
        what: "Polaris",
        sent: &sent,
        seen: &values,
    };
    rig.start(60, 3.0);
    rig.garbage(&[b"xx\r", b"01+0000", &[0x00, 0xFF, b'\n']], 30);
    rig.silence(
        "Tracker failed, trying to reset",
        30,
        Duration::from_secs(10),
    );
    rig.unplug(30, Duration::from_secs(10));
    let _ = std::fs::remove_dir_all(&dir);
}
