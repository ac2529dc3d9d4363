//! The `trackers` part of the `first_byte` bench: first-byte stamp accuracy and start-up of
//! the streaming serial trackers besides the Fastrak — Polaris, Liberty, ISOTRAK, 3SPACE —
//! each on its simulator on a pseudo-terminal, served by our server in a thread and read by a
//! `TrackerRemote` on 127.0.0.1 (UDP path).
//!
//! A simulator step notes the wall time just before its write for every record it logged in
//! that step (the write that carries the record's first byte); each pose the client receives
//! is matched to its record by its exact values. Printed per tracker: report timestamp −
//! first-byte write (p50 / p90 / p99 / max), and the time from the server's start to the
//! first pose. Compare with the bare-pty baseline the bench prints first.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use vrpn::drivers::liberty::sim::{Kind, LibertySim, SimConfig as LibertyConfig};
use vrpn::drivers::polaris::sim::{PolarisSim, SimConfig as PolarisConfig};
use vrpn::drivers::threespace::record::Model;
use vrpn::drivers::threespace::sim::{SimConfig as ThreeSpaceConfig, ThreeSpaceSim};
use vrpn::sim::{DeviceModel, PtyDevice};
use vrpn::{TimeVal, TrackerRemote};

use super::{micros, print_us, tty_dir, tty_path, ServerThread, SimThread};

/// Poses measured per tracker (override with `FIRST_BYTE_RECORDS`).
const POSES: usize = 1500;

type Values = (usize, [f64; 3], [f64; 4]);
type Log = Arc<Mutex<Vec<(Values, TimeVal)>>>;

/// Runs the simulator `model` with the log reader `logged`, serves it with `cfg` (`PATH` is
/// the pseudo-terminal), and prints the figures.
fn measure<M: DeviceModel + 'static>(
    label: &str,
    cfg: &str,
    model: impl FnOnce() -> M + Send + 'static,
    logged: fn(&PtyDevice<M>) -> Vec<Values>,
) {
    let poses: usize = std::env::var("FIRST_BYTE_RECORDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(POSES);
    let path = tty_path(label.split_whitespace().next().unwrap_or("tracker"));
    let sent: Log = Arc::default();
    let s = sent.clone();
    let mut seen = 0usize;
    let _sim = SimThread::start(&path, model, move |dev, now| {
        let all = logged(dev);
        if all.len() > seen {
            s.lock()
                .unwrap()
                .extend(all[seen..].iter().map(|&v| (v, now.wall)));
            seen = all.len();
        }
    });
    let cfg = cfg.replace("PATH", &path.display().to_string());
    let server = ServerThread::start(&cfg);
    let tracker =
        TrackerRemote::new(&format!("Tracker0@127.0.0.1:{}", server.port)).expect("client");
    let got: Rc<RefCell<Vec<(Values, TimeVal)>>> = Rc::default();
    let g = got.clone();
    tracker.on_pose(move |p| {
        let q = p.quat.into_inner();
        g.borrow_mut().push((
            (p.sensor, [p.pos.x, p.pos.y, p.pos.z], [q.i, q.j, q.k, q.w]),
            p.time,
        ))
    });
    let limit = Instant::now() + Duration::from_secs(120);
    let mut first = None;
    while got.borrow().len() < poses {
        assert!(
            Instant::now() < limit,
            "{label}: {} poses",
            got.borrow().len()
        );
        tracker.mainloop().expect("client mainloop");
        if first.is_none() && !got.borrow().is_empty() {
            first = Some(server.started.elapsed());
        }
        let _ = tracker.connection().wait(Duration::from_millis(2));
    }
    drop(server);
    let sent = sent.lock().unwrap();
    let (mut lags, mut unmatched, mut cursor) = (Vec::new(), 0, 0);
    for (values, stamp) in got.borrow().iter() {
        match sent[cursor..]
            .iter()
            .take(400)
            .position(|(v, _)| v == values)
        {
            Some(i) => {
                lags.push(micros(*stamp, sent[cursor + i].1));
                cursor += i + 1;
            }
            None => unmatched += 1,
        }
    }
    println!(
        "{label}: {} poses, {} matched, {unmatched} unmatched; server start to first pose \
         {:.0} ms",
        got.borrow().len(),
        lags.len(),
        first.unwrap_or_default().as_secs_f64() * 1e3
    );
    print_us("  report timestamp - first-byte write", lags);
}

/// Polaris, Liberty, ISOTRAK and 3SPACE, one after the other.
pub fn run() {
    let dir = tty_dir();
    std::fs::create_dir_all(&dir).expect("temp dir");
    let rom = |name: &str| {
        let p = dir.join(name);
        std::fs::write(&p, [0x5Au8; 300]).expect("a .rom file");
        p.display().to_string()
    };
    let polaris = format!(
        "vrpn_Tracker_NDI_Polaris Tracker0 PATH 2\n{}\n{}\n",
        rom("a.rom"),
        rom("b.rom")
    );
    measure(
        "Polaris (2 tools, 60 Hz, polled at 115200 baud)",
        &polaris,
        || {
            let mut c = PolarisConfig::new();
            c.keep_log = true;
            PolarisSim::new(c)
        },
        |d| d.model.sent().iter().map(|s| s.values).collect(),
    );
    measure(
        "Liberty (2 stations, 60 Hz, 115200 baud)",
        "vrpn_Tracker_Liberty Tracker0 PATH 115200\n",
        || {
            let mut c = LibertyConfig::new(Kind::Liberty, 115_200);
            c.keep_log = true;
            c.stations = vec![1, 2];
            LibertySim::new(c)
        },
        |d| d.model.sent().iter().map(|s| s.sample.expected()).collect(),
    );
    for (label, line, model) in [
        (
            "ISOTRAK (2 stations, 19200 baud)",
            "vrpn_Tracker_Isotrak Tracker0 PATH 19200\n",
            Model::Isotrak,
        ),
        (
            "3SPACE (2 stations, 19200 baud)",
            "vrpn_Tracker_3Space Tracker0 PATH 19200\n",
            Model::ThreeSpace,
        ),
    ] {
        measure(
            label,
            line,
            move || {
                let mut c = ThreeSpaceConfig::new(model, 19_200);
                c.keep_log = true;
                c.stations = vec![1, 2];
                ThreeSpaceSim::new(c)
            },
            |d| d.model.sent().iter().map(|s| s.sample.expected()).collect(),
        );
    }
}
