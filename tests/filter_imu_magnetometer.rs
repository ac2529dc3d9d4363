//! vrpn_IMU_Magnetometer end to end: this test serves an analog `Feed` on a port of its own;
//! a `vrpn_server` serves a magnetometer of three of its channels (`Feed@127.0.0.1:PORT`, the
//! remote kind of source); a client reads the magnetometer. Every unit vector heard must be
//! what the test computes independently (nalgebra) after one of the inputs it sent (each axis
//! mapped into -1..1 by its extremes so far, zero counted, normalised), in order, and every
//! input must be reported.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::nalgebra::Vector3;
use vrpn::sim::rig::ServerProcess;
use vrpn::{AnalogRemote, AnalogServer, Connection, TimeVal};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(20);

#[test]
fn unit_vectors_match_an_independent_computation() {
    let feed_conn = Connection::server(None, 0).unwrap();
    let feed_port = feed_conn.local_port().unwrap();
    let mut feed = AnalogServer::new("Feed", &feed_conn, 4).unwrap();
    let cfg = format!(
        "vrpn_IMU_Magnetometer Mag 200.0\n\
         Feed@127.0.0.1:{feed_port} 2 0.25 2.0 0 0 -1.0 3 -0.5 0.5\n"
    );
    let server = ServerProcess::start(SERVER.as_ref(), &cfg).unwrap();
    let mag = AnalogRemote::new(&format!("Mag@tcp://127.0.0.1:{}", server.port())).unwrap();
    let heard: Rc<RefCell<Vec<Vec<f64>>>> = Rc::default();
    let h = heard.clone();
    mag.on_report(move |r| h.borrow_mut().push(r.channels().to_vec()));
    let pump = |d: Duration| {
        let start = Instant::now();
        while start.elapsed() < d {
            let _ = feed_conn.mainloop();
            let _ = mag.mainloop();
            std::thread::sleep(Duration::from_millis(1));
        }
    };
    // Both connections up: the magnetometer reports (1, 0, 0) before any input.
    let start = Instant::now();
    while heard.borrow().is_empty() || feed_conn.connected_peers() == 0 {
        assert!(start.elapsed() < WAIT, "server said {}", server.stderr());
        pump(Duration::from_millis(5));
    }
    assert_eq!(heard.borrow()[0], vec![1.0, 0.0, 0.0]);
    let (ch, off, sc) = ([2usize, 0, 3], [0.25, 0.0, -0.5], [2.0, -1.0, 0.5]);
    let mut lo = Vector3::zeros();
    let mut hi = Vector3::zeros();
    let mut after = vec![Vector3::new(1.0, 0.0, 0.0)];
    let mut seed = 7u64;
    for _ in 0..40 {
        let mut c = [0.0; 4];
        for x in c.iter_mut() {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            *x = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        }
        feed.channels_mut().copy_from_slice(&c);
        feed.report(Some(TimeVal::now())).unwrap();
        let v = Vector3::from_fn(|i, _| (c[ch[i]] - off[i]) * sc[i]);
        lo = lo.inf(&v);
        hi = hi.sup(&v);
        let mapped = Vector3::from_fn(|i, _| {
            if v[i] == lo[i] {
                0.0
            } else {
                -1.0 + 2.0 * (v[i] - lo[i]) / (hi[i] - lo[i])
            }
        });
        after.push(mapped.normalize());
        pump(Duration::from_millis(40));
    }
    pump(Duration::from_millis(200));
    let heard = heard.borrow();
    let mut k = 0;
    let mut reported = vec![false; after.len()];
    for u in heard.iter() {
        let got = Vector3::new(u[0], u[1], u[2]);
        k = (k..after.len())
            .find(|&j| (got - after[j]).norm() < 1e-12)
            .unwrap_or_else(|| panic!("{got:?} is no vector after input {k} or later"));
        reported[k] = true;
    }
    assert!(reported.iter().all(|r| *r), "{reported:?}");
    assert_eq!(k, after.len() - 1);
}
