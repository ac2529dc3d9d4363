//! The `trackers` part of the `first_byte` bench: first-byte stamp accuracy and start-up of
//! the streaming serial trackers besides the Fastrak — Polaris, Liberty, ISOTRAK, 3SPACE —
//! each on its simulator on a pseudo-terminal, served by our server in a thread and read by a
//! `TrackerRemote` on 127.0.0.1 (UDP path).
//!
//! The simulators pace their bytes at the line's baud rate and log every record with the wall
//! time read just before the write that carried *that record's* first byte (`written`: for
//! the second station of a frame, a whole record's transmission after the first station's;
//! for the Polaris, whose tools share a reply, the reply's first byte). Each pose the client
//! receives is matched to its record by sensor and by its exact values (a function of the
//! record's sequence number), each sensor in its own order, so a pose lost on one station
//! never shifts the other's. The report timestamp is the server's own (`sender_time`, not
//! the clock-synchronised `time`, which moves by the estimate's microseconds). Printed per
//! tracker: report timestamp − first-byte write (p50 / p90 / p99 / max), how many stamps
//! came out earlier than their first byte's write (none can be right), and the time from the
//! server's start to the first pose. Compare with the bare-pty baseline (wake − write) the
//! bench prints first, in the same run.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use vrpn::drivers::liberty::sim::{Kind, LibertySim, SimConfig as LibertyConfig};
use vrpn::drivers::polaris::sim::{PolarisSim, SimConfig as PolarisConfig};
use vrpn::drivers::threespace::record::Model;
use vrpn::drivers::threespace::sim::{SimConfig as ThreeSpaceConfig, ThreeSpaceSim};
use vrpn::sim::DeviceModel;
use vrpn::{Now, TimeVal, TrackerRemote};

use super::{micros, print_us, tty_dir, tty_path, ServerThread, SimThread};

/// Poses measured per tracker (override with `FIRST_BYTE_RECORDS`).
const POSES: usize = 1500;

/// Sensor, position, quaternion (x, y, z, w): what a client receives.
type Values = (usize, [f64; 3], [f64; 4]);
type Log = Arc<Mutex<Vec<(Values, TimeVal)>>>;
/// The simulator's log entry `i`: what the client must receive for it and, once its first
/// byte has been written, when.
type Entry<M> = fn(&M, usize) -> Option<(Values, Option<Now>)>;

/// Runs the simulator `model` with the log reader `entry`, serves it with `cfg` (`PATH` is
/// the pseudo-terminal), and prints the figures.
fn measure<M: DeviceModel + 'static>(
    label: &str,
    cfg: &str,
    model: impl FnOnce() -> M + Send + 'static,
    entry: Entry<M>,
) {
    let poses: usize = std::env::var("FIRST_BYTE_RECORDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(POSES);
    let path = tty_path(label.split_whitespace().next().unwrap_or("tracker"));
    let sent: Log = Arc::default();
    let s = sent.clone();
    let mut seen = 0usize;
    let _sim = SimThread::start(&path, model, move |dev, _| {
        // Entries are taken in order once written (a record queued but not yet on the line
        // waits for a later step).
        let mut s = s.lock().unwrap();
        while let Some((values, Some(at))) = entry(&dev.model, seen) {
            s.push((values, at.wall));
            seen += 1;
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
            p.sender_time,
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
    let (lags, unmatched) = match_by_sensor(&sent, &got.borrow());
    println!(
        "{label}: {} poses, {} matched, {unmatched} unmatched; server start to first pose \
         {:.0} ms",
        got.borrow().len(),
        lags.len(),
        first.unwrap_or_default().as_secs_f64() * 1e3
    );
    // A stamp before the write that carried the first byte cannot be right (the clock the
    // bench and the server read is the same): counted apart, beside the quantiles.
    let early = lags.iter().filter(|&&l| l < 0).count();
    print_us("  report timestamp - first-byte write", lags);
    println!("  stamps earlier than their first byte's write: {early}");
}

/// Pairs each received pose with the logged record of the same sensor and values, searching
/// forward from that sensor's last match (records of a sensor arrive in order; a few may be
/// lost at start-up). Returns stamp − first-byte write per pair, in µs, and how many poses
/// matched nothing.
fn match_by_sensor(sent: &[(Values, TimeVal)], got: &[(Values, TimeVal)]) -> (Vec<i64>, usize) {
    let mut cursor: Vec<usize> = Vec::new();
    let (mut lags, mut unmatched) = (Vec::new(), 0);
    for (values, stamp) in got {
        let sensor = values.0;
        if cursor.len() <= sensor {
            cursor.resize(sensor + 1, 0);
        }
        let from = cursor[sensor];
        let hit = sent[from..]
            .iter()
            .enumerate()
            .filter(|(_, (v, _))| v.0 == sensor)
            .take(200)
            .find(|(_, (v, _))| v == values);
        match hit {
            Some((i, &(_, wrote))) => {
                lags.push(micros(*stamp, wrote));
                cursor[sensor] = from + i + 1;
            }
            None => unmatched += 1,
        }
    }
    (lags, unmatched)
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
        |m, i| m.sent().get(i).map(|s| (s.values, s.written)),
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
        |m, i| m.sent().get(i).map(|s| (s.sample.expected(), s.written)),
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
            |m, i| m.sent().get(i).map(|s| (s.sample.expected(), s.written)),
        );
    }
}
