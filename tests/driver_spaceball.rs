//! The Spaceball driver end to end: its simulator (a 4000 FLX) on a pseudo-terminal, a
//! `vrpn_server` child serving the driver's vrpn.cfg line, and a TCP client of its Analog and
//! Button on 127.0.0.1. Checked against the simulator's own log:
//!
//! 1. exact values (six axes, twelve buttons), in order, each stamped with the arrival of its
//!    packet's first byte;
//! 2. garbage between packets: reported, and not one packet lost;
//! 3. silence (the ball left alone, or a cut wire): nothing is reported, and the packets that
//!    follow are exactly what the device sent (the Spaceball has no watchdog, as in C++);
//! 4. unplugging: reported, the port is reopened under the same path and the device set up
//!    again, packets resume with nothing invented.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::spaceball::sim::{Event, Listener, SimConfig, SpaceballSim};
use vrpn::drivers::spaceball::INIT;
use vrpn::sim::rig::{
    assert_first_byte_stamps, assert_run_of, resume_after, Client, Heard, ServerProcess,
};
use vrpn::sim::SimulatedDevice;
use vrpn::Now;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// What the client heard, one event per packet.
fn heard(client: &Client) -> Listener {
    let mut l = Listener::default();
    for h in client.heard() {
        match h {
            Heard::Analog { channels, time } => l.analog(&channels, time),
            Heard::Button {
                button,
                pressed,
                time,
            } => l.button(button, pressed, time),
            _ => {}
        }
    }
    l
}

fn sent(sim: &SimulatedDevice<SpaceballSim>) -> (Vec<Event>, Vec<Instant>) {
    sim.model(|m| m.sent().iter().map(|p| (p.event, p.first_byte)).unzip())
}

/// Where the events the client has not heard yet start in the simulator's log.
fn resume(client: &Client, sim: &SimulatedDevice<SpaceballSim>) -> usize {
    let want = sent(sim).0;
    let heard: Vec<Event> = heard(client).events.iter().map(|e| e.0).collect();
    resume_after(&heard, &want, want.len())
}

/// The events heard from event `from` on are a contiguous run of those sent from log index
/// `after` on, each stamped with its first byte.
fn check(client: &Client, sim: &SimulatedDevice<SpaceballSim>, from: usize, after: usize, t0: Now) {
    let (want, at) = sent(sim);
    let l = heard(client);
    let got: Vec<Event> = l.events[from..].iter().map(|e| e.0).collect();
    let runs = assert_run_of(&got, &want, after, "Spaceball packets");
    let stamps: Vec<_> = l.events[from..].iter().map(|e| e.1).collect();
    assert_first_byte_stamps(
        &stamps,
        &at[runs[0]..],
        t0,
        Duration::from_millis(250),
        "Spaceball",
    );
}

#[test]
fn spaceball_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("spaceball", || {
        let mut cfg = SimConfig::new(9600);
        cfg.keep_log = true;
        SpaceballSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_Spaceball Spaceball0 {} 9600\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "Spaceball0",
        server.port(),
        &[Interface::Analog, Interface::Button],
    )
    .unwrap();
    let events = |c: &Client| heard(c).events.len();

    // 1. Start-up and exact values.
    client.wait_until(Duration::from_secs(10), "set up", &server, |_| {
        sim.model(|m| m.heard().len()) >= INIT.len()
    });
    let set_up = sim.model(|m| m.heard_at().last().copied()).unwrap();
    eprintln!(
        "Spaceball: vrpn_server start to the end of the set-up string {:.0} ms",
        (set_up - t0.mono).as_secs_f64() * 1e3
    );
    assert_eq!(sim.model(|m| m.heard().to_vec()), INIT);
    client.wait_until(Duration::from_secs(5), "60 packets", &server, |c| {
        events(c) >= 60
    });
    check(&client, &sim, 0, 0, t0);

    // 2. Garbage between packets: reported, nothing lost.
    let junk: [&[u8]; 4] = [b"\x01\x02xyz", b"D\x00\x01\x02", b"K\xFF", b"^"];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = events(&client);
    client.wait_until(
        Duration::from_secs(5),
        "packets after garbage",
        &server,
        |c| events(c) >= n + 30,
    );
    check(&client, &sim, 0, 0, t0);
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: nothing reported meanwhile; what follows is what the device sends.
    sim.set_mute(true);
    client.pump_until(Duration::from_millis(200), |_| false);
    let (from, logged) = (events(&client), resume(&client, &sim));
    client.pump_until(Duration::from_millis(500), |_| false);
    assert_eq!(events(&client), from, "packets while silent");
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(5),
        "packets after silence",
        &server,
        |c| events(c) >= from + 30,
    );
    check(&client, &sim, from, logged, t0);

    // 4. Unplugged: reported, reopened and set up again, resumed with nothing invented.
    let texts_from = client.len();
    sim.unplug();
    client.wait_text(texts_from, "failed", Duration::from_secs(3), &server);
    client.pump_until(Duration::from_millis(100), |_| false);
    let (from, logged) = (events(&client), resume(&client, &sim));
    client.pump_until(Duration::from_millis(300), |_| false);
    assert_eq!(events(&client), from, "packets while unplugged");
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(6),
        "packets after plugging back",
        &server,
        |c| events(c) >= from + 30,
    );
    client.wait_text(texts_from, "is open again", Duration::from_secs(1), &server);
    assert_eq!(sim.model(|m| m.heard().to_vec()), [INIT, INIT].concat());
    check(&client, &sim, from, logged, t0);
}
