//! The DynaSight driver end to end, the test every driver has (copy it for a new one): its
//! simulator on a pseudo-terminal, a `vrpn_server` child serving the driver's vrpn.cfg line,
//! and a TCP client on 127.0.0.1. Checked against the simulator's own log:
//!
//! 1. exact values, in order, each stamped with the arrival of its record's first byte;
//! 2. garbage between records: reported, and not one record lost;
//! 3. silence: the watchdog resets the device, records resume, and nothing the device did not
//!    send is reported meanwhile (a reset never invents data);
//! 4. unplugging: reported, the port is reopened under the same path once the device is
//!    back, records resume, again with nothing invented.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::dyna::sim::{DynaSim, SimConfig};
use vrpn::sim::rig::{
    assert_first_byte_stamps, assert_run_of, resume_after, Client, ServerProcess,
};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TrackerPose};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// What a client must see of one record: sensor, position, quaternion (x, y, z, w).
type Values = (usize, [f64; 3], [f64; 4]);

fn values(p: &TrackerPose) -> Values {
    let q = p.quat.into_inner();
    (p.sensor, [p.pos.x, p.pos.y, p.pos.z], [q.i, q.j, q.k, q.w])
}

/// Every record the simulator sent, as the client must see it, and when its first byte left.
fn sent(sim: &SimulatedDevice<DynaSim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|r| {
                let pos = r.sample.expected_position_m();
                ((0, pos, [0.0, 0.0, 0.0, 1.0]), r.first_byte)
            })
            .unzip()
    })
}

/// Checks the poses heard from log index `from` against the records sent from `after` on:
/// a contiguous run (nothing lost, added or changed), each stamped with its first byte.
/// Where the records the client has not heard yet start in the simulator's log.
fn resume(client: &Client, sim: &SimulatedDevice<DynaSim>) -> usize {
    let want = sent(sim).0;
    let heard: Vec<Values> = client.poses().iter().map(values).collect();
    resume_after(&heard, &want, want.len())
}

fn check(client: &Client, sim: &SimulatedDevice<DynaSim>, from: usize, after: usize, t0: Now) {
    let (want, at) = sent(sim);
    let poses = client.poses_from(from);
    let got: Vec<Values> = poses.iter().map(values).collect();
    let runs = assert_run_of(&got, &want, after, "DynaSight poses");
    let stamps: Vec<_> = poses.iter().map(|p| p.time).collect();
    assert_first_byte_stamps(
        &stamps,
        &at[runs[0]..],
        t0,
        Duration::from_millis(250),
        "DynaSight",
    );
}

#[test]
fn dynasight_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("dyna", || {
        let mut cfg = SimConfig::new(19200);
        cfg.keep_log = true;
        DynaSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_Tracker_Dyna Dyna0 1 {} 19200\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("Dyna0", server.port(), &[Interface::Tracker]).unwrap();
    let poses = |c: &Client| c.poses().len();

    // 1. Start-up and exact values.
    client.wait_until(Duration::from_secs(10), "a first pose", &server, |c| {
        poses(c) >= 1
    });
    let startup = client.poses()[0].time.seconds_since(t0.wall);
    eprintln!(
        "DynaSight: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    assert!(startup < 2.0, "{startup} s");
    client.wait_until(Duration::from_secs(5), "60 poses", &server, |c| {
        poses(c) >= 60
    });
    check(&client, &sim, 0, 0, t0);

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 4] = [
        &[0x00, 0x7F, 0xFF, 0x41],
        &[0x85, 0x12, 0x80, 0x33, 0x22],
        &[0x8A, 0x00, 0x8B, 0x7F, 0x9C],
        &[0x55],
    ];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = poses(&client);
    client.wait_until(
        Duration::from_secs(5),
        "poses after garbage",
        &server,
        |c| poses(c) >= n + 30,
    );
    check(&client, &sim, 0, 0, t0);
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: the watchdog resets the device; what follows is what it sends.
    let (from, logged) = (client.len(), resume(&client, &sim));
    sim.set_mute(true);
    client.wait_text(
        from,
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
        &server,
    );
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(8),
        "poses after silence",
        &server,
        |c| c.poses_from(from).len() >= 30,
    );
    check(&client, &sim, from, logged, t0);

    // 4. Unplugged: reported, reopened when back, resumed with nothing invented.
    let (from, logged) = (client.len(), resume(&client, &sim));
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    let while_unplugged = client.poses_from(from).len();
    client.pump_until(Duration::from_millis(300), |_| false);
    assert_eq!(
        client.poses_from(from).len(),
        while_unplugged,
        "poses while unplugged"
    );
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(6),
        "poses after plugging back",
        &server,
        |c| c.poses_from(from).len() >= while_unplugged + 30,
    );
    client.wait_text(from, "is open again", Duration::from_secs(1), &server);
    check(&client, &sim, from, logged, t0);
}
