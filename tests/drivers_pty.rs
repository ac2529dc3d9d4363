//! Drivers end to end: a device simulator on a pseudo-terminal, a `vrpn_server` child process
//! running the driver from a vrpn.cfg line, and a client over a real socket on 127.0.0.1.

mod common;
#[path = "common/pty_sim.rs"]
mod pty_sim;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use pty_sim::Simulated;
use vrpn::drivers::fastrak::sim::{FastrakSim, SimConfig};
use vrpn::TrackerRemote;

#[test]
fn fastrak_through_vrpn_server_to_a_client() {
    let sim = Simulated::start(FastrakSim::new(SimConfig::new(115200)), "fastrak");
    let cfg = format!(
        "vrpn_Tracker_Fastrak Tracker0 {} 115200\n",
        sim.path.display()
    );
    let server = common::start_server(&cfg, 0);
    let tracker = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{}", server.port)).unwrap();
    let poses = Rc::new(RefCell::new(Vec::new()));
    let p = poses.clone();
    tracker.on_pose(move |pose| p.borrow_mut().push(*pose));
    let start = Instant::now();
    while poses.borrow().len() < 40 && start.elapsed() < Duration::from_secs(10) {
        tracker.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    let n = poses.borrow().len();
    assert!(
        n >= 40,
        "{n} poses in 10 s; server said: {}",
        server.stderr.lock().unwrap()
    );
    // Every sensor 0..4 reports.
    let mut sensors: Vec<usize> = poses.borrow().iter().map(|p| p.sensor).collect();
    sensors.sort_unstable();
    sensors.dedup();
    assert_eq!(sensors, vec![0, 1, 2, 3]);
    drop(sim);
}
