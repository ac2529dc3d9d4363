//! The inertia mouse driver end to end: the simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_inertiamouse`, and a TCP client of its Analog and Button on
//! 127.0.0.1: exact channels and button changes in order with first-byte stamps, garbage
//! between records, silence (no watchdog: the reports resume), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::inertiamouse::sim::{InertiaSim, Sent, SimConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// A report without its time, for comparing runs.
#[derive(Clone, Debug, PartialEq)]
enum Value {
    Analog(Vec<f64>),
    Button(usize, bool),
}

fn sent(sim: &SimulatedDevice<InertiaSim>) -> (Vec<Value>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|s| match s {
                Sent::Analog(v, t) => (Value::Analog(v.to_vec()), *t),
                Sent::Button(i, p, t) => (Value::Button(*i, *p), *t),
            })
            .unzip()
    })
}

/// What the client heard from `from` on: every Analog report and every button change (the
/// states a server sends a client when it connects are not changes).
fn heard(client: &Client, from: usize) -> (Vec<Value>, Vec<TimeVal>) {
    let mut state = [false; 2];
    client
        .heard()
        .into_iter()
        .enumerate()
        .filter_map(|(i, h)| {
            let v = match h {
                Heard::Analog { channels, time } => Some((Value::Analog(channels), time)),
                Heard::Button {
                    button,
                    pressed,
                    time,
                } => {
                    let changed = state.get(button).is_some_and(|&s| s != pressed);
                    if let Some(s) = state.get_mut(button) {
                        *s = pressed;
                    }
                    changed.then_some((Value::Button(button, pressed), time))
                }
                _ => None,
            };
            v.filter(|_| i >= from)
        })
        .unzip()
}

fn check(sim: &SimulatedDevice<InertiaSim>, client: &Client, from: usize, after: usize, t0: Now) {
    let (want, at) = sent(sim);
    let (got, stamps) = heard(client, from);
    let runs = assert_run_of(&got, &want, after, "inertia mouse");
    assert_first_byte_stamps(
        &stamps,
        &at[runs[0]..],
        t0,
        Duration::from_millis(250),
        "inertia mouse",
    );
}

#[test]
fn inertia_mouse_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("inertiamouse", || {
        let mut cfg = SimConfig::new(115_200);
        cfg.keep_log = true;
        cfg.wait_for_host = true;
        InertiaSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_inertiamouse Mouse0 {} 115200\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "Mouse0",
        server.port(),
        &[Interface::Analog, Interface::Button],
    )
    .unwrap();
    let count = |c: &Client| heard(c, 0).0.len();
    client.wait_until(Duration::from_secs(10), "reports", &server, |c| {
        count(c) >= 100
    });
    check(&sim, &client, 0, 0, t0);
    // Garbage between records.
    let junk: [&[u8]; 3] = [b"Dxx\n", b"B\x01", b"\n\nQ"];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let have = count(&client);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| count(c) >= have + 50,
    );
    check(&sim, &client, 0, 0, t0);
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);
    // Silence: nothing invented; the reports resume.
    let (from, logged) = (client.len(), sent(&sim).0.len().saturating_sub(3));
    sim.set_mute(true);
    client.pump_until(Duration::from_millis(500), |_| false);
    let quiet = client.len();
    client.pump_until(Duration::from_millis(500), |_| false);
    assert_eq!(client.len(), quiet, "reports while silent");
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &server,
        |c| heard(c, quiet).0.len() >= 50,
    );
    let _ = (from, logged);
    // Unplugged: reported, reopened, resumed.
    let from = client.len();
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(8),
        "reports after plugging back",
        &server,
        |c| heard(c, from).0.len() >= 50,
    );
    client.wait_text(from, "is open again", Duration::from_secs(1), &server);
}
