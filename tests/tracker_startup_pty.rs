//! Start-up of the Fastrak and Flock drivers end to end: device simulators on pseudo-terminals,
//! a `vrpn_server` child running the driver from its vrpn.cfg line, and a client over a real
//! socket on 127.0.0.1. Each test measures the time from starting the server to the first
//! report's time stamp (the whole reset included), prints it (`--nocapture`), and checks it is
//! far below C++'s fixed sleeps (at least 7.2 s for a Fastrak, about 19 s for a Flock), and that
//! every sensor and station device reports. The tracker's text messages are printed too, with
//! their times, to show where the start-up went.

mod common;

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use vrpn::drivers::fastrak::sim::{FastrakSim, SimConfig as FastrakConfig};
use vrpn::drivers::flock::sim::{FlockSim, SimConfig as FlockConfig};
use vrpn::sim::DeviceModel;
use vrpn::sim::PtyDevice;
use vrpn::{AnalogRemote, ButtonRemote, Now, TextReceiver, TrackerPose, TrackerRemote};

/// The slowest start-up accepted: well under C++'s fastest (7.2 s for a Fastrak).
const MAX_STARTUP_S: f64 = 3.0;

/// Device models on pseudo-terminals, stepped in one thread until dropped. The models are built
/// inside that thread (a Flock's lines share state that cannot cross threads).
struct Simulated {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    paths: Vec<PathBuf>,
    dir: PathBuf,
}

impl Simulated {
    fn start<M, F>(name: &str, lines: usize, models: F) -> Simulated
    where
        M: DeviceModel + 'static,
        F: FnOnce() -> Vec<M> + Send + 'static,
    {
        let dir = std::env::temp_dir().join(format!("vrpn-start-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let paths: Vec<PathBuf> = (0..lines).map(|i| dir.join(format!("tty{i}"))).collect();
        let stop = Arc::new(AtomicBool::new(false));
        let (ready_tx, ready_rx) = mpsc::channel();
        let (s, p) = (stop.clone(), paths.clone());
        let thread = std::thread::spawn(move || {
            let mut devices: Vec<PtyDevice<M>> = models()
                .into_iter()
                .zip(&p)
                .map(|(m, path)| PtyDevice::open(m, path).unwrap())
                .collect();
            ready_tx.send(()).unwrap();
            while !s.load(Ordering::Relaxed) {
                for d in &mut devices {
                    let _ = d.step(Now::read());
                }
                std::thread::sleep(Duration::from_micros(200));
            }
        });
        ready_rx
            .recv_timeout(Duration::from_secs(10))
            .expect("simulator did not start");
        Simulated {
            stop,
            thread: Some(thread),
            paths,
            dir,
        }
    }

    fn path(&self, i: usize) -> String {
        self.paths[i].display().to_string()
    }
}

impl Drop for Simulated {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Runs `pump` until `done` or `max`; returns whether `done` held.
fn pump_until(pump: &dyn Fn(), max: Duration, done: &dyn Fn() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < max {
        pump();
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    done()
}

/// Starts `vrpn_server` on `cfg`, waits until every sensor `0..sensors` of `name` reported, and
/// returns the server-start-to-first-report time in seconds, the poses and the server.
fn start_and_collect(
    label: &str,
    cfg: &str,
    name: &str,
    sensors: usize,
    extra: &dyn Fn(&str) -> Box<dyn Fn() -> bool>,
) -> f64 {
    let t0 = Now::read();
    let server = common::start_server(cfg, 0);
    let at = format!("{name}@tcp://127.0.0.1:{}", server.port);
    let tracker = TrackerRemote::new(&at).unwrap();
    let poses: Rc<RefCell<Vec<TrackerPose>>> = Rc::default();
    let p = poses.clone();
    tracker.on_pose(move |pose| p.borrow_mut().push(*pose));
    let texts = TextReceiver::new(&at).unwrap();
    let said: Rc<RefCell<Vec<String>>> = Rc::default();
    let s = said.clone();
    texts.on_message(move |m| {
        let ms = m.time.seconds_since(t0.wall) * 1e3;
        s.borrow_mut().push(format!("{ms:.0} ms: {}", m.text()));
    });
    let more_done = extra(&format!("127.0.0.1:{}", server.port));
    let all_sensors = || {
        let seen = poses.borrow();
        (0..sensors).all(|s| seen.iter().any(|p| p.sensor == s)) && more_done()
    };
    let pump = || tracker.mainloop().unwrap();
    assert!(
        pump_until(&pump, Duration::from_secs(15), &all_sensors),
        "{label}: sensors seen {:?}; server said: {}",
        {
            let mut s: Vec<usize> = poses.borrow().iter().map(|p| p.sensor).collect();
            s.dedup();
            s
        },
        server.stderr.lock().unwrap()
    );
    let first = poses.borrow()[0].time.seconds_since(t0.wall);
    let wall = t0.mono.elapsed().as_secs_f64();
    eprintln!(
        "{label}: vrpn_server start to first report's time stamp {:.0} ms \
         (every sensor seen after {:.0} ms)",
        first * 1e3,
        wall * 1e3
    );
    for line in said.borrow().iter() {
        eprintln!("  {label}: {line}");
    }
    assert!(poses.borrow().iter().all(|p| p.sensor < sensors));
    first
}

/// No station devices to wait for.
fn nothing(_: &str) -> Box<dyn Fn() -> bool> {
    Box::new(|| true)
}

#[test]
fn fastrak_starts_in_well_under_a_second() {
    let sim = Simulated::start("fastrak", 1, || {
        vec![FastrakSim::new(FastrakConfig::new(19200))]
    });
    let cfg = format!("vrpn_Tracker_Fastrak Tracker0 {} 19200\n", sim.path(0));
    let startup = start_and_collect("Fastrak, 19200 baud", &cfg, "Tracker0", 4, &nothing);
    assert!(startup > 0.0 && startup < MAX_STARTUP_S, "{startup} s");
}

#[test]
fn is900_with_wand_and_stylus_starts_and_reports_every_device() {
    let sim = Simulated::start("is900", 1, || {
        vec![FastrakSim::new(FastrakConfig::new(115200))]
    });
    let cfg = format!(
        "vrpn_Tracker_Fastrak Isense900 {} 115200 IS900time /\n\
         Wand Wand0 0 -1.0 0.0 0.0 1.0 -1.0 0.0 0.0 1.0 /\n\
         Stylus Stylus0 1\n",
        sim.path(0)
    );
    // The wand's joystick and buttons, and the stylus's buttons, must all report.
    let devices = |host: &str| -> Box<dyn Fn() -> bool> {
        let wand_analog = AnalogRemote::new(&format!("Wand0@tcp://{host}")).unwrap();
        let wand_buttons = ButtonRemote::new(&format!("Wand0@tcp://{host}")).unwrap();
        let stylus = ButtonRemote::new(&format!("Stylus0@tcp://{host}")).unwrap();
        let seen = Rc::new(RefCell::new([false; 3]));
        let s = seen.clone();
        wand_analog.on_report(move |_| s.borrow_mut()[0] = true);
        let s = seen.clone();
        wand_buttons.on_change(move |_| s.borrow_mut()[1] = true);
        let s = seen.clone();
        stylus.on_change(move |_| s.borrow_mut()[2] = true);
        Box::new(move || {
            wand_analog.mainloop().unwrap();
            wand_buttons.mainloop().unwrap();
            stylus.mainloop().unwrap();
            seen.borrow().iter().all(|&b| b)
        })
    };
    let startup = start_and_collect(
        "IS-900 with wand and stylus, 115200 baud",
        &cfg,
        "Isense900",
        4,
        &devices,
    );
    assert!(startup > 0.0 && startup < MAX_STARTUP_S, "{startup} s");
}

#[test]
fn flock_on_one_line_starts_in_about_a_second() {
    let sim = Simulated::start("flock", 1, || {
        let mut c = FlockConfig::new(4, true, 115200);
        // RTS does not reach a device through a pseudo-terminal.
        c.rts_wired = false;
        vec![FlockSim::new(c)]
    });
    let cfg = format!("vrpn_Tracker_Flock Flock0 4 {} 115200 0\n", sim.path(0));
    let startup = start_and_collect("Flock, 4 receivers + ERT", &cfg, "Flock0", 4, &nothing);
    assert!(startup > 0.0 && startup < MAX_STARTUP_S, "{startup} s");
}

#[test]
fn flock_parallel_starts_in_about_a_second() {
    let sim = Simulated::start("flockpar", 3, || {
        let mut c = FlockConfig::new(2, true, 115200);
        c.rts_wired = false;
        FlockSim::parallel(c)
    });
    let cfg = format!(
        "vrpn_Tracker_Flock_Parallel Flock1 2 {} 115200 0 {} {}\n",
        sim.path(0),
        sim.path(1),
        sim.path(2)
    );
    let startup = start_and_collect("Flock_Parallel, 2 receivers", &cfg, "Flock1", 2, &nothing);
    assert!(startup > 0.0 && startup < MAX_STARTUP_S, "{startup} s");
}
