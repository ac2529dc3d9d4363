//! The Tek4662 plotter driver end to end: the simulated plotter on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_Tek4662`, a TCP client of its Tracker and a Poser remote
//! asking for poses on 127.0.0.1: the pen's positions reported exactly, in order, with
//! first-byte stamps; each requested pose carried out and reported; garbage between answers;
//! silence (a reset after 5 s); unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::devices::poser::PoserRemote;
use vrpn::driver::Interface;
use vrpn::drivers::tek4662::sim::{count_metres, PlotterSim, SimConfig};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/output_rig.rs"]
mod output_rig;
use output_rig::{Device, OutputRig};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// 4095 counts per 15 inches, as the plotter's manual gives them.
const COUNTS_PER_METER: f64 = 4095.0 / (15.0 * 0.0254);

fn poses(client: &Client, from: usize) -> (Vec<[f64; 3]>, Vec<TimeVal>) {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Pose(p) => {
                let q = p.quat.coords;
                assert_eq!([q.x, q.y, q.z, q.w], [0.0, 0.0, 0.0, 1.0]);
                assert_eq!(p.sensor, 0);
                Some(([p.pos.x, p.pos.y, p.pos.z], p.time))
            }
            _ => None,
        })
        .unzip()
}

fn sent(sim: &SimulatedDevice<PlotterSim>) -> (Vec<[f64; 3]>, Vec<Instant>) {
    sim.model(|m| m.sent().iter().map(|s| (s.metres, s.at)).unzip())
}

type Rig = OutputRig<PlotterSim, [f64; 3], PoserRemote>;

/// Asks for `n` poses, each once the previous was carried out and reported.
fn moves(r: &mut Rig, n: usize) {
    r.sim.model(|m| m.set_wander(false));
    for _ in 0..n {
        let k = r.moves as u16;
        r.moves += 1;
        let (x, y) = ((k * 997 + 13) % 4096, (k * 613 + 7) % 2731);
        // The middle of the count: the driver rounds down to it.
        let m = |c: u16| (f64::from(c) + 0.5) / COUNTS_PER_METER;
        r.out
            .request_pose(TimeVal::now(), [m(x), m(y), 0.0], [0.0, 0.0, 0.0, 1.0])
            .unwrap();
        let want = [count_metres(x), count_metres(y), 0.0];
        let poser = &r.out;
        r.client.wait_until(
            Duration::from_secs(10),
            &format!("the pen at ({x}, {y})"),
            &r.server,
            |c| {
                let _ = poser.mainloop();
                poses(c, 0).0.last() == Some(&want)
            },
        );
        assert_eq!(r.sim.model(|m| m.pen()), (x, y));
    }
}

/// Lets the joystick wander for `n` answers.
fn wander(r: &mut Rig, n: usize) {
    r.sim.model(|m| m.set_wander(true));
    let heard = poses(&r.client, 0).0.len();
    r.client.wait_until(
        Duration::from_secs(10),
        "the wandering pen",
        &r.server,
        |c| poses(c, 0).0.len() >= heard + n,
    );
}

#[test]
fn tek4662_plotter_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("tek4662", || {
        let mut cfg = SimConfig::new(1200);
        cfg.keep_log = true;
        PlotterSim::new(cfg)
    })
    .unwrap();
    // Bytes of an answer come 8.3 ms apart at 1200 baud.
    sim.set_junk_idle(Duration::from_millis(40));
    let device = Device {
        what: "Tek4662 pen",
        reports: poses,
        sent,
        request: |_| unreachable!("the plotter is asked for poses, through its Poser"),
    };
    let mut r = OutputRig::start_with(
        sim,
        SERVER,
        "vrpn_Tek4662 Tek0 {PATH} 1200\n",
        "Tek0",
        &[Interface::Tracker],
        device,
        |at| PoserRemote::new(at).unwrap(),
    );
    let t0 = r.t0;

    // 1. Start-up: the pen where it was; the joystick's wandering followed; poses.
    r.client
        .wait_until(Duration::from_secs(10), "the pen", &r.server, |c| {
            !poses(c, 0).0.is_empty()
        });
    let (first, stamps) = poses(&r.client, 0);
    eprintln!(
        "Tek4662: vrpn_server start to the first position {:.0} ms",
        stamps[0].seconds_since(t0.wall) * 1e3
    );
    assert_eq!(first[0], [count_metres(1000), count_metres(500), 0.0]);
    r.client
        .wait_text(0, "Reset correctly", Duration::from_secs(1), &r.server);
    wander(&mut r, 8);
    moves(&mut r, 12);
    r.check(0, 0);

    // 2. Garbage between answers.
    let junk: [&[u8]; 3] = [b"zz", b"\x00\xff", b"12"];
    r.sim.inject_between_records(&junk);
    wander(&mut r, 1);
    r.client.wait_until(
        Duration::from_secs(10),
        "the garbage sent",
        &r.server,
        |_| r.sim.injected() == junk.len(),
    );
    wander(&mut r, 4);
    moves(&mut r, 4);
    r.check(0, 0);
    r.client
        .wait_text(0, "skipped", Duration::from_secs(2), &r.server);

    // 3. Silence: reset on the open port after 5 s; positions and poses again.
    r.silence_then(
        "Device timeout (resetting)",
        Duration::from_secs(8),
        "Reset correctly",
        Duration::from_secs(5),
        |r| {
            moves(r, 4);
            wander(r, 4);
        },
    );

    // 4. Unplugged: reported, reopened when back, reset, poses again.
    r.unplug_then("Reset correctly", |r| {
        moves(r, 4);
        wander(r, 4);
    });
}
