//! The YEI 3-Space wireless driver end to end: the dongle simulator (two units paired) on a
//! pseudo-terminal, a `vrpn_server` child serving two `vrpn_YEI_3Space_Sensor_Wireless` units
//! on it (the second after a `/`), and a TCP client of each unit's Tracker, Analog and Button
//! on 127.0.0.1: exact reports of each unit in order with first-byte stamps, garbage between
//! the dongle's frames, silence (the 2 s timeout's reset), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::yei::sim::{SimConfig, YeiSim};
use vrpn::sim::rig::{Client, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::Now;

#[path = "common/yei_reports.rs"]
mod yei_reports;
use yei_reports::count;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

#[test]
fn two_wireless_units_through_vrpn_server_to_clients() {
    let sim = SimulatedDevice::start("yei_wireless", || {
        let mut cfg = SimConfig::wireless(115_200, &[0, 1]);
        cfg.keep_log = true;
        YeiSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_YEI_3Space_Sensor_Wireless YEI0 0 {} 115200 1 0 50.0 0 0 1 1 \\\n\
         238,1,1,0 /\n\
         vrpn_YEI_3Space_Sensor_Wireless YEI1 1 0 1 50.0 0 1 0 1\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let all = [Interface::Tracker, Interface::Analog, Interface::Button];
    let clients = [
        Client::connect("YEI0", server.port(), &all).unwrap(),
        Client::connect("YEI1", server.port(), &all).unwrap(),
    ];
    let wait_all = |what: &str, max: Duration, from: [usize; 2], n: usize| {
        for (c, from) in clients.iter().zip(from) {
            c.wait_until(max, what, &server, |c| count(c, from) >= n);
        }
    };
    wait_all("reports", Duration::from_secs(10), [0, 0], 200);
    let started = Instant::now();
    let check = || {
        for (u, client) in clients.iter().enumerate() {
            yei_reports::check(&sim, client, u, t0, &format!("YEI{u}"));
        }
    };
    check();
    let setup = sim.model(|m| {
        let u = &m.units;
        (
            m.manual_flush,
            m.bad_commands,
            (u[0].calibrations, u[0].tares, u[0].ascii.clone()),
            (u[1].calibrations, u[1].tares, u[1].led_color),
        )
    });
    assert_eq!(
        setup,
        (
            true,
            0,
            (1, 0, vec!["238,1,1,0".to_owned()]),
            (0, 1, [0.0, 1.0, 0.0])
        )
    );
    let junk: [&[u8]; 3] = [b"A", &[0x00, 0x07, 0x59], &[0x01, 0x00]];
    sim.inject_between_records(&junk);
    clients[0].wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let have = [count(&clients[0], 0), count(&clients[1], 0)];
    for (c, have) in clients.iter().zip(have) {
        c.wait_until(
            Duration::from_secs(5),
            "reports after garbage",
            &server,
            |c| count(c, 0) >= have + 100,
        );
    }
    check();
    clients[0].wait_text(0, "skipped", Duration::from_secs(2), &server);
    assert!(started.elapsed() < Duration::from_secs(60));
    // Silence: the 2 s timeout, dongle resets (failing while it is mute), records again.
    let from = [clients[0].len(), clients[1].len()];
    sim.set_mute(true);
    clients[0].wait_text(
        from[0],
        "vrpn_YEI_3Space::mainloop: Timeout",
        Duration::from_secs(5),
        &server,
    );
    sim.set_mute(false);
    wait_all("reports after silence", Duration::from_secs(15), from, 100);
    // Unplugged: reported, reopened, set up again, resumed.
    let from = [clients[0].len(), clients[1].len()];
    sim.unplug();
    clients[0].wait_text(from[0], "failed", Duration::from_secs(3), &server);
    sim.plug().unwrap();
    wait_all(
        "reports after plugging back",
        Duration::from_secs(10),
        from,
        100,
    );
    clients[0].wait_text(from[0], "is open again", Duration::from_secs(1), &server);
    assert_eq!(
        sim.model(|m| (m.units[0].calibrations, m.units[1].tares)),
        (2, 2)
    );
}
