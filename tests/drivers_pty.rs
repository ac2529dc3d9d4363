//! Drivers end to end: a device simulator on a pseudo-terminal, a `vrpn_server` child process
//! running the driver from a vrpn.cfg line, and a client over a real socket on 127.0.0.1.

mod common;

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use vrpn::drivers::fastrak::sim::{FastrakSim, SimConfig};
use vrpn::sim::DeviceModel;
use vrpn::sim::PtyDevice;
use vrpn::{Now, TrackerRemote};

/// Runs a device model on a pseudo-terminal in a thread until dropped.
struct Simulated<M: DeviceModel + Send + 'static> {
    device: Arc<Mutex<PtyDevice<M>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    path: PathBuf,
}

impl<M: DeviceModel + Send + 'static> Simulated<M> {
    fn start(model: M, name: &str) -> Simulated<M> {
        let dir = std::env::temp_dir().join(format!("vrpn-pty-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tty");
        let device = Arc::new(Mutex::new(PtyDevice::open(model, &path).unwrap()));
        let stop = Arc::new(AtomicBool::new(false));
        let (d, s) = (device.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                let _ = d.lock().unwrap().step(Now::read());
                std::thread::sleep(Duration::from_micros(200));
            }
        });
        Simulated {
            device,
            stop,
            thread: Some(thread),
            path,
        }
    }
}

impl<M: DeviceModel + Send + 'static> Simulated<M> {
    /// Unplugs the simulated device (the server's port fails) or plugs it back.
    #[allow(dead_code)]
    fn set_plugged(&self, plugged: bool) {
        let mut d = self.device.lock().unwrap();
        if plugged {
            d.plug().unwrap();
        } else {
            d.unplug();
        }
    }
}

impl<M: DeviceModel + Send + 'static> Drop for Simulated<M> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

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
