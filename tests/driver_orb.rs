//! The Global Haptics Orb driver end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_GlobalHapticsOrb`, and a TCP client of its Button,
//! Analog and Dial on 127.0.0.1: exact reports in order with first-byte stamps, garbage
//! between events, silence (the watchdog's reset after 10 s), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::orb::sim::{OrbSim, Sent, SimConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/faults.rs"]
mod faults;
use faults::{garbage_costs_nothing, unplugged_and_reopened};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

#[derive(Clone, Debug, PartialEq)]
enum Value {
    Button(usize, bool),
    Analog(Vec<f64>),
    Dial(usize, f64),
}

fn sent(sim: &SimulatedDevice<OrbSim>) -> (Vec<Value>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|s| match *s {
                Sent::Button(i, p, t) => (Value::Button(i, p), t),
                Sent::Analog(v, t) => (Value::Analog(v.to_vec()), t),
                Sent::Dial(i, r, t) => (Value::Dial(i, r), t),
            })
            .unzip()
    })
}

fn heard(client: &Client, from: usize) -> (Vec<Value>, Vec<TimeVal>) {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((Value::Button(button, pressed), time)),
            Heard::Analog { channels, time } => Some((Value::Analog(channels), time)),
            Heard::Dial { dial, change, time } => Some((Value::Dial(dial, change), time)),
            _ => None,
        })
        .unzip()
}

#[test]
fn orb_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("orb", || {
        let mut cfg = SimConfig::new(19_200);
        cfg.keep_log = true;
        OrbSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_GlobalHapticsOrb Orb0 {} 19200\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "Orb0",
        server.port(),
        &[Interface::Button, Interface::Analog, Interface::Dial],
    )
    .unwrap();
    let count = |c: &Client, from: usize| heard(c, from).0.len();
    client.wait_until(Duration::from_secs(10), "reports", &server, |c| {
        count(c, 0) >= 200
    });
    let check = |from: usize| {
        let (want, at) = sent(&sim);
        let (got, stamps) = heard(&client, from);
        let runs = assert_run_of(&got, &want, 0, "Orb");
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            t0,
            Duration::from_millis(250),
            "Orb",
        );
    };
    check(0);
    let junk: [&[u8]; 3] = [&[0x41], &[0x7F, 0x55], &[0x20]];
    garbage_costs_nothing(&sim, &client, &server, &junk, count, 100);
    check(0);
    // Silence: probed at 5 s, reset at 10 s; events resume when it speaks again.
    let from = client.len();
    sim.set_mute(true);
    client.wait_text(
        from,
        "Too long since last report, resetting",
        Duration::from_secs(13),
        &server,
    );
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(8),
        "reports after silence",
        &server,
        |c| count(c, from) >= 100,
    );
    // Unplugged: reported, reopened, resumed.
    unplugged_and_reopened(&sim, &client, &server, count, 100);
}
