//! The YEI 3-Space Sensor driver end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_YEI_3Space_Sensor`, and a TCP client of its Tracker,
//! Analog and Button on 127.0.0.1: exact reports in order with first-byte stamps, garbage
//! between records, silence (the 2 s timeout's reset), unplugging and reopening.

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

/// What the client must hear for the records `sent`, from all buttons released on.
fn expected(sent: &[Sent]) -> (Vec<Value>, Vec<Instant>) {
    let mut out = Vec::new();
    let mut buttons = 0u8;
    for s in sent {
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
    let count = |c: &Client, from: usize| heard(c, from).0.len();
    client.wait_until(Duration::from_secs(10), "reports", &server, |c| {
        count(c, 0) >= 200
    });
    let started = Instant::now();
    let check = || {
        let (want, at) = sim.model(|m| expected(m.sent()));
        let (got, stamps) = heard(&client, 0);
        let runs = assert_run_of(&got, &want, 0, "YEI");
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            t0,
            Duration::from_millis(250),
            "YEI",
        );
    };
    check();
    let setup = sim.model(|m| {
        let u = &m.units[0];
        (u.calibrations, u.tares, u.ascii.clone(), m.bad_commands)
    });
    assert_eq!(setup, (1, 0, vec!["238,1,1,0".to_owned()], 0));
    let junk: [&[u8]; 3] = [b"A", &[0x7F, 0x55], &[0x3F, 0x80, 0, 0, 0x20]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let have = count(&client, 0);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| count(c, 0) >= have + 100,
    );
    check();
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);
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
    let from = client.len();
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(8),
        "reports after plugging back",
        &server,
        |c| count(c, from) >= 100,
    );
    client.wait_text(from, "is open again", Duration::from_secs(1), &server);
    assert_eq!(sim.model(|m| m.units[0].calibrations), 2);
}
