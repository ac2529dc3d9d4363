//! For engines whose resources must be `Send`: the remotes live on a worker thread that
//! calls `mainloop()` and publishes the latest states; the main (render) thread reads a copy
//! once per frame. Only `std::sync` is used.
//!
//! Remotes and connections are not `Send`: they are created on the worker and never leave
//! it. What crosses threads are plain values (`TrackerPose` and `ConnectionState` are `Copy`
//! and `Send`).
//!
//! Against a running server: `cargo run --example worker_thread -- Tracker0@localhost`
//! Stand-alone (the worker also runs an in-process server on its own `loopback:`):
//! `cargo run --example worker_thread -- --demo`

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use vrpn::{Connection, ConnectionState, TrackerPose, TrackerRemote, TrackerServer};

/// What the worker publishes: the newest pose per sensor and the connection's state.
#[derive(Clone, Debug, Default)]
struct Snapshot {
    poses: Vec<Option<TrackerPose>>,
    state: Option<ConnectionState>,
    /// Bumped by the worker whenever something new was published.
    version: u64,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let demo = args.iter().any(|a| a == "--demo");
    let name = if demo {
        "Tracker0@loopback:".to_string()
    } else {
        args.first().cloned().unwrap_or("Tracker0@localhost".into())
    };

    let shared = Arc::new(Mutex::new(Snapshot::default()));
    let stop = Arc::new(AtomicBool::new(false));
    let worker = {
        let (shared, stop) = (shared.clone(), stop.clone());
        thread::spawn(move || {
            if let Err(e) = run_worker(&name, demo, &shared, &stop) {
                eprintln!("worker: {e}");
            }
        })
    };

    // The render loop: 60 frames a second for 3 seconds, reading the latest copy.
    let mut seen = 0;
    for frame in 0..180 {
        let snap = shared.lock().expect("worker panicked").clone();
        if snap.version != seen && frame % 30 == 0 {
            seen = snap.version;
            match snap.poses.first().copied().flatten() {
                Some(p) => println!(
                    "frame {frame}: pose #{} at ({:+.2}, {:+.2}, {:+.2}), {:?}",
                    p.seq, p.pos.x, p.pos.y, p.pos.z, snap.state
                ),
                None => println!("frame {frame}: no pose yet, {:?}", snap.state),
            }
        }
        thread::sleep(Duration::from_micros(16_667));
    }
    stop.store(true, Ordering::Relaxed);
    worker.join().expect("worker panicked");
}

/// The worker: owns the connection and remotes, services them, and copies what is new into
/// the shared snapshot (a short lock, once per pass with news).
fn run_worker(
    name: &str,
    demo: bool,
    shared: &Mutex<Snapshot>,
    stop: &AtomicBool,
) -> Result<(), vrpn::Error> {
    let tracker = TrackerRemote::new(name)?;
    // `loopback:` is this thread's in-process connection: a server made here is heard by
    // the remote above, and by no other thread.
    let server = if demo {
        Some(TrackerServer::new("Tracker0", &Connection::loopback(), 1)?)
    } else {
        None
    };
    let mut step = 0u64;
    while !stop.load(Ordering::Relaxed) {
        if let Some(s) = &server {
            let a = step as f64 / 100.0;
            s.report_pose(
                0usize,
                s.connection().now().wall,
                [a.cos(), a.sin(), 0.0],
                [0.0, 0.0, 0.0, 1.0],
            )?;
            step += 1;
        }
        tracker.mainloop()?;
        let mut news = false;
        for sensor in 0..tracker.sensor_count() {
            news |= tracker.take_pose(sensor).is_some();
        }
        let state = tracker.connection().state();
        let mut snap = shared.lock().expect("render thread panicked");
        if news || snap.state != Some(state) {
            // Refilled in place: no allocation once the vector has its size.
            snap.poses.clear();
            snap.poses
                .extend((0..tracker.sensor_count()).map(|s| tracker.pose(s)));
            snap.state = Some(state);
            snap.version += 1;
        }
        drop(snap);
        // Sleep until a socket is ready or 5 ms pass (the worker does not spin a core).
        tracker.connection().wait(Duration::from_millis(5))?;
    }
    Ok(())
}
