//! The AD-Box driver end to end: the simulator on a pseudo-terminal, a `vrpn_server` child
//! serving `vrpn_ADBox`, and a TCP client of its Button and Analog on 127.0.0.1: exact
//! reports in order with first-byte stamps, garbage between answers, silence (the layout
//! detected again), unplugging and reopening.
//!
//! Two timing facts of a loaded machine shape it: the start-up detection may end before the
//! client's handshake (a server sends texts only to connected clients, so the start-up text
//! is not waited for: the detection after the silence is), and the simulator's thread may be
//! descheduled mid-answer (so it writes each answer whole, `SimConfig::burst`).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::adbox::sim::{AdBoxSim, Sent, SimConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

#[derive(Clone, Debug, PartialEq)]
enum Value {
    Button(usize, bool),
    Analog(Vec<f64>),
}

fn sent(sim: &SimulatedDevice<AdBoxSim>) -> (Vec<Value>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|s| match s {
                Sent::Button(i, p, t) => (Value::Button(*i, *p), *t),
                Sent::Analog(v, t) => (Value::Analog(v.clone()), *t),
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
            _ => None,
        })
        .unzip()
}

#[test]
fn adbox_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("adbox", || {
        let mut cfg = SimConfig::new(19_200);
        cfg.keep_log = true;
        cfg.burst = true;
        AdBoxSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_ADBox ADBox0 {} 19200\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "ADBox0",
        server.port(),
        &[Interface::Button, Interface::Analog],
    )
    .unwrap();
    let count = |c: &Client, from: usize| heard(c, from).0.len();
    client.wait_until(Duration::from_secs(10), "reports", &server, |c| {
        count(c, 0) >= 150
    });
    let (_, stamps) = heard(&client, 0);
    eprintln!(
        "ADBox: vrpn_server start to the first report {:.0} ms",
        stamps[0].seconds_since(t0.wall) * 1e3
    );
    let check = |from: usize| {
        let (want, at) = sent(&sim);
        let (got, stamps) = heard(&client, from);
        let runs = assert_run_of(&got, &want, 0, "ADBox");
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            t0,
            Duration::from_millis(250),
            "ADBox",
        );
    };
    check(0);
    // Garbage: answers out of step are dropped; the next ones are exact again.
    let junk: [&[u8]; 3] = [&[0x41], &[0x7F, 0x55], &[0xC8]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let settle = |what: &str| {
        let have = client.len();
        client.wait_until(Duration::from_secs(8), what, &server, |c| {
            count(c, have) >= 30
        });
        let from = client.len();
        client.wait_until(Duration::from_secs(8), what, &server, |c| {
            count(c, from) >= 100
        });
        check(from);
    };
    settle("reports after garbage");
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);
    // Silence: the layout is detected again; answers resume.
    let from = client.len();
    sim.set_mute(true);
    client.wait_text(
        from,
        "no answer for 1 s, detecting the box again",
        Duration::from_secs(4),
        &server,
    );
    sim.set_mute(false);
    client.wait_text(
        from,
        "ad-box with 24 digital and 8 analog ports detected",
        Duration::from_secs(4),
        &server,
    );
    settle("reports after silence");
    // Unplugged: reported, reopened, detected, resumed.
    let from = client.len();
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    sim.plug().unwrap();
    client.wait_text(from, "is open again", Duration::from_secs(8), &server);
    client.wait_text(
        from,
        "analog ports detected",
        Duration::from_secs(4),
        &server,
    );
    settle("reports after plugging back");
}
