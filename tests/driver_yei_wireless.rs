//! The YEI 3-Space wireless driver end to end: the dongle simulator (two units paired) on a
//! pseudo-terminal, a `vrpn_server` child serving two `vrpn_YEI_3Space_Sensor_Wireless` units
//! on it (the second after a `/`), and a TCP client of each unit's Tracker, Analog and Button
//! on 127.0.0.1: exact reports of each unit in order with first-byte stamps, garbage between
//! the dongle's frames, silence (the 2 s timeout's reset), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::yei::sim::{Sent, SimConfig, YeiSim};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

#[derive(Clone, Debug, PartialEq)]
enum Value {
    Pose(usize, [f64; 4]),
    Analog(Vec<f64>),
    Button(usize, bool),
}

/// What the client of `unit` must hear for the records `sent`, from all buttons released on.
fn expected(sent: &[Sent], unit: usize) -> (Vec<Value>, Vec<Instant>) {
    let mut out = Vec::new();
    let mut buttons = 0u8;
    for s in sent.iter().filter(|s| s.unit == unit) {
        let t = s.first_byte;
        out.push((Value::Pose(0, s.quats[0]), t));
        out.push((Value::Pose(1, s.quats[1]), t));
        out.push((Value::Analog(s.channels.to_vec()), t));
        for i in 0..8 {
            if (buttons ^ s.buttons) & (1 << i) != 0 {
                out.push((Value::Button(i, s.buttons & (1 << i) != 0), t));
            }
        }
        buttons = s.buttons;
    }
    out.into_iter().unzip()
}

fn heard(client: &Client, from: usize) -> (Vec<Value>, Vec<TimeVal>) {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Pose(p) => {
                let q = p.quat.coords;
                Some((Value::Pose(p.sensor, [q.x, q.y, q.z, q.w]), p.time))
            }
            Heard::Analog { channels, time } => Some((Value::Analog(channels), time)),
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((Value::Button(button, pressed), time)),
            _ => None,
        })
        .unzip()
}

fn count(c: &Client, from: usize) -> usize {
    heard(c, from).0.len()
}

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
            let what = format!("YEI{u}");
            let (want, at) = sim.model(move |m| expected(m.sent(), u));
            let (got, stamps) = heard(client, 0);
            let runs = assert_run_of(&got, &want, 0, &what);
            assert_first_byte_stamps(
                &stamps,
                &at[runs[0]..],
                t0,
                Duration::from_millis(250),
                &what,
            );
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
