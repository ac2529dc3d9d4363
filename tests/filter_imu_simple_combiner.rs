//! vrpn_IMU_SimpleCombiner end to end: this test serves a 9-channel analog `Feed` on a port of
//! its own; a `vrpn_server` serves two combiners reading it (`Feed@127.0.0.1:PORT`, the remote
//! kind of source), one with a magnetometer and one without, reporting at every pass; a
//! client reads both. Every report heard must be, bit for bit, what the model (the one the
//! unit tests hold to C++ VRPN's captured output) computes from the inputs the test sent, in
//! order, stepped by the time between two reports; and every input must be taken in.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::drivers::imu_simple_combiner::model::{replay, Heard};
use vrpn::sim::rig::ServerProcess;
use vrpn::{AnalogServer, Connection, TimeVal, TrackerRemote};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(20);

fn listen(remote: &TrackerRemote) -> Rc<RefCell<Vec<Heard>>> {
    let heard: Rc<RefCell<Vec<Heard>>> = Rc::default();
    let h = heard.clone();
    remote.on_pose(move |p| {
        let q = p.quat.quaternion();
        assert_eq!((p.sensor, p.pos.norm()), (0, 0.0));
        h.borrow_mut()
            .push((p.sender_time, [q.i, q.j, q.k, q.w], [f64::NAN; 4]));
    });
    let h = heard.clone();
    remote.on_velocity(move |v| {
        let q = v.vel_quat.quaternion();
        assert_eq!((v.sensor, v.vel.norm(), v.vel_quat_dt), (0, 0.0, 0.01));
        if let Some(last) = h.borrow_mut().last_mut() {
            assert_eq!(last.0, v.sender_time, "a velocity follows its pose");
            last.2 = [q.i, q.j, q.k, q.w];
        }
    });
    heard
}

#[test]
fn reports_follow_from_the_inputs_over_the_pass_times() {
    let feed_conn = Connection::server(None, 0).unwrap();
    let feed_port = feed_conn.local_port().unwrap();
    let mut feed = AnalogServer::new("Feed", &feed_conn, 9).unwrap();
    let f = format!("Feed@127.0.0.1:{feed_port}");
    let cfg = format!(
        "vrpn_IMU_SimpleCombiner Comb 1000000.0\n\
         {f} 3 0.05 1.0 4 0 1.0 5 0 -1.0\n\
         {f} 6 0 1.0 7 0 1.0 8 0 1.0\n\
         {f}\n\
         vrpn_IMU_SimpleCombiner Gyro 1000000.0\n\
         {f} 3 0 1.0 4 0 1.0 5 0 1.0\n\
         {f} 8 0 -1.0 7 0.1 2.0 6 0 1.0\n\
         NULL\n"
    );
    let server = ServerProcess::start(SERVER.as_ref(), &cfg).unwrap();
    let at = |n: &str| format!("{n}@tcp://127.0.0.1:{}", server.port());
    let comb = TrackerRemote::new(&at("Comb")).unwrap();
    let gyro = TrackerRemote::new(&at("Gyro")).unwrap();
    let (comb_heard, gyro_heard) = (listen(&comb), listen(&gyro));
    let pump = |d: Duration| {
        let start = Instant::now();
        while start.elapsed() < d {
            let _ = feed_conn.mainloop();
            let _ = comb.mainloop();
            let _ = gyro.mainloop();
            std::thread::sleep(Duration::from_millis(1));
        }
    };
    // The combiners connected to the feed (the server opens one connection to it) and heard.
    let start = Instant::now();
    while comb_heard.borrow().is_empty()
        || gyro_heard.borrow().is_empty()
        || feed_conn.connected_peers() == 0
    {
        assert!(
            start.elapsed() < WAIT,
            "heard {} and {}, feed peers {}; server said {}",
            comb_heard.borrow().len(),
            gyro_heard.borrow().len(),
            feed_conn.connected_peers(),
            server.stderr()
        );
        pump(Duration::from_millis(5));
    }
    pump(Duration::from_millis(50));
    let mut sent = vec![];
    let mut seed = 99u64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for k in 0..40 {
        let far = if k % 7 == 6 { 1.5 } else { 1.0 };
        let c = [
            0.2 + 0.6 * rnd(),
            -0.4 + 0.6 * rnd(),
            -0.8 + 0.6 * rnd(),
            far * (0.3 + 2.0 * rnd()),
            far * (-9.7 + 0.6 * rnd()),
            far * 0.6 * rnd(),
            3.0 * rnd(),
            3.0 * rnd(),
            3.0 * rnd(),
        ];
        feed.channels_mut().copy_from_slice(&c);
        feed.report(Some(TimeVal::now())).unwrap();
        sent.push(c);
        pump(Duration::from_millis(15));
    }
    pump(Duration::from_millis(200));
    for (heard, magnetometer, accel, rot) in [
        (
            &comb_heard,
            true,
            ([3, 4, 5], [0.05, 0.0, 0.0], [1.0, 1.0, -1.0]),
            ([6, 7, 8], [0.0; 3], [1.0; 3]),
        ),
        (
            &gyro_heard,
            false,
            ([3, 4, 5], [0.0; 3], [1.0; 3]),
            ([8, 7, 6], [0.0, 0.1, 0.0], [-1.0, 2.0, 1.0]),
        ),
    ] {
        // The axis lines, computed here in single precision offsets and scales as C++ reads
        // them.
        let axis = |c: &[f64; 9], (ch, off, sc): ([usize; 3], [f32; 3], [f32; 3])| {
            [0, 1, 2].map(|i| (c[ch[i]] - off[i] as f64) * sc[i] as f64)
        };
        let inputs: Vec<[[f64; 3]; 3]> = sent
            .iter()
            .map(|c| [axis(c, accel), axis(c, rot), [c[0], c[1], c[2]]])
            .collect();
        let heard = heard.borrow();
        assert!(heard.len() > 300, "{} reports", heard.len());
        let advanced = match replay(magnetometer, &inputs, &heard) {
            Ok(a) => a,
            Err(e) => {
                let n: usize = e.split_whitespace().nth(1).unwrap().parse().unwrap();
                for h in &heard[n.saturating_sub(8)..(n + 3).min(heard.len())] {
                    eprintln!("report time around it: {:?}", h.0);
                }
                panic!("{e}");
            }
        };
        assert!(
            advanced + 2 >= inputs.len(),
            "{advanced} of {}",
            inputs.len()
        );
    }
}
