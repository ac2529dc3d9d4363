//! The Fastrak and single-line Flock drivers under faults, end to end: a simulator on a
//! pseudo-terminal, a `vrpn_server` child running the driver from its vrpn.cfg line, and a
//! TCP-only client on 127.0.0.1 (so no datagram can be lost on a busy machine). Each test
//! checks exact values in order against the simulator's log, then survives garbage on the
//! line (no later record lost), a silent device (the watchdog resets it and records resume)
//! and an unplugged port (reported with a text, reopened under the same path, resumed).

mod common;

use std::cell::RefCell;
use std::fmt::Debug;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use vrpn::drivers::fastrak::record::METRES_PER_INCH;
use vrpn::drivers::fastrak::sim::{self as fastrak_sim, FastrakSim, SimConfig as FastrakConfig};
use vrpn::drivers::flock::record::Transmitter;
use vrpn::drivers::flock::sim::{self as flock_sim, FlockSim, SimConfig as FlockConfig};
use vrpn::sim::DeviceModel;
use vrpn::sim::PtyDevice;
use vrpn::{Now, TextReceiver, TrackerPose, TrackerRemote};

/// A device model that puts queued garbage on the line, one piece per idle gap: only when
/// the model sent nothing in this step and nothing for [`Noisy::IDLE`] before, so the garbage
/// falls between records (never inside one) and the driver must lose no record to it.
struct Noisy<M> {
    inner: M,
    junk: Vec<Vec<u8>>,
    last_out: Option<Instant>,
    last_junk: Option<Instant>,
    injected: usize,
}

impl<M> Noisy<M> {
    /// Far longer than the gaps inside a record (a chunk or a byte every < 1 ms).
    const IDLE: Duration = Duration::from_millis(2);
    /// At most one piece of garbage per this time (one per gap between output cycles).
    const APART: Duration = Duration::from_millis(40);

    fn new(inner: M) -> Noisy<M> {
        Noisy {
            inner,
            junk: Vec::new(),
            last_out: None,
            last_junk: None,
            injected: 0,
        }
    }
}

impl<M: DeviceModel> DeviceModel for Noisy<M> {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        self.inner.receive(bytes, now);
    }
    fn set_rts(&mut self, on: bool, now: Now) {
        self.inner.set_rts(on, now);
    }
    fn set_dtr(&mut self, on: bool, now: Now) {
        self.inner.set_dtr(on, now);
    }
    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let before = out.len();
        self.inner.transmit(now, out);
        if out.len() > before {
            self.last_out = Some(now.mono);
            return;
        }
        let idle = self.last_out.is_some_and(|t| now.mono >= t + Self::IDLE);
        let apart = self.last_junk.map_or(true, |t| now.mono >= t + Self::APART);
        if idle && apart && !self.junk.is_empty() {
            out.extend_from_slice(&self.junk.remove(0));
            self.injected += 1;
            self.last_junk = Some(now.mono);
        }
    }
    fn next_deadline(&self) -> Option<Instant> {
        self.inner.next_deadline()
    }
}

type Job<M> = Box<dyn FnOnce(&mut PtyDevice<Noisy<M>>) + Send>;

/// A device model on a pseudo-terminal, stepped in its own thread until dropped. The model is
/// built in that thread (a Flock's line shares state that cannot cross threads) and is
/// reached through [`Simulated::with`].
struct Simulated<M: DeviceModel + 'static> {
    jobs: mpsc::Sender<Job<M>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    path: PathBuf,
}

impl<M: DeviceModel + 'static> Simulated<M> {
    fn start(name: &str, model: impl FnOnce() -> M + Send + 'static) -> Simulated<M> {
        let dir = std::env::temp_dir().join(format!("vrpn-faults-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tty");
        let stop = Arc::new(AtomicBool::new(false));
        let (jobs, inbox) = mpsc::channel::<Job<M>>();
        let (ready_tx, ready_rx) = mpsc::channel();
        let (s, p) = (stop.clone(), path.clone());
        let thread = std::thread::spawn(move || {
            let mut device = PtyDevice::open(Noisy::new(model()), &p).unwrap();
            ready_tx.send(()).unwrap();
            while !s.load(Ordering::Relaxed) {
                while let Ok(job) = inbox.try_recv() {
                    job(&mut device);
                }
                let _ = device.step(Now::read());
                std::thread::sleep(Duration::from_micros(200));
            }
        });
        ready_rx
            .recv_timeout(Duration::from_secs(10))
            .expect("simulator did not start");
        Simulated {
            jobs,
            stop,
            thread: Some(thread),
            path,
        }
    }

    /// Runs `f` on the device in the simulator's thread and returns its result.
    fn with<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut PtyDevice<Noisy<M>>) -> R + Send + 'static,
    ) -> R {
        let (tx, rx) = mpsc::channel();
        self.jobs
            .send(Box::new(move |d| {
                let _ = tx.send(f(d));
            }))
            .unwrap();
        rx.recv_timeout(Duration::from_secs(10))
            .expect("simulator thread answers")
    }
}

impl<M: DeviceModel + 'static> Drop for Simulated<M> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some(dir) = self.path.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// The tests run one at a time: a server started by one must not inherit the other's
/// pseudo-terminal before it is made close-on-exec (unplugging would then not hang up).
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// A TCP-only client of one tracker: its poses and its texts.
struct Client {
    tracker: TrackerRemote,
    _texts_rx: TextReceiver,
    poses: Rc<RefCell<Vec<TrackerPose>>>,
    texts: Rc<RefCell<Vec<String>>>,
    server: common::Server,
}

impl Client {
    fn start(cfg: &str, name: &str) -> Client {
        let server = common::start_server(cfg, 0);
        let at = format!("{name}@tcp://127.0.0.1:{}", server.port);
        let tracker = TrackerRemote::new(&at).unwrap();
        let poses: Rc<RefCell<Vec<TrackerPose>>> = Rc::default();
        let p = poses.clone();
        tracker.on_pose(move |pose| p.borrow_mut().push(*pose));
        let texts_rx = TextReceiver::new(&at).unwrap();
        let texts: Rc<RefCell<Vec<String>>> = Rc::default();
        let t = texts.clone();
        texts_rx.on_message(move |m| t.borrow_mut().push(m.text().to_string()));
        Client {
            tracker,
            _texts_rx: texts_rx,
            poses,
            texts,
            server,
        }
    }

    /// Pumps until `done` or `max`; returns whether `done` held.
    fn pump_until(&self, max: Duration, done: impl Fn(&Client) -> bool) -> bool {
        let start = Instant::now();
        while start.elapsed() < max {
            self.tracker.mainloop().unwrap();
            if done(self) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        done(self)
    }

    fn count(&self) -> usize {
        self.poses.borrow().len()
    }

    /// Pumps until `n` poses arrived, else panics with what the server and device said.
    fn wait_poses(&self, n: usize, max: Duration, what: &str) {
        assert!(
            self.pump_until(max, |c| c.count() >= n),
            "{what}: {} of {n} poses; texts {:?}; server said: {}",
            self.count(),
            self.texts.borrow(),
            self.server.stderr.lock().unwrap()
        );
    }

    /// Pumps until a text from index `from` on contains `part`.
    fn wait_text(&self, from: usize, part: &str, max: Duration) {
        assert!(
            self.pump_until(max, |c| c.texts.borrow()
                [from.min(c.texts.borrow().len())..]
                .iter()
                .any(|t| t.contains(part))),
            "no text with {part:?}: {:?}",
            self.texts.borrow()
        );
    }
}

/// What a client must see of one record: sensor, position, quaternion (x, y, z, w).
type Values = (usize, [f64; 3], [f64; 4]);

fn values(p: &TrackerPose) -> Values {
    let q = p.quat.into_inner();
    (p.sensor, [p.pos.x, p.pos.y, p.pos.z], [q.i, q.j, q.k, q.w])
}

/// Asserts `got` is a contiguous run of `sent[after..]` (the client joined mid-stream, and
/// the last records may still be on their way), each pose carrying the time its record left
/// the simulator or soon after. A device reset starts its values over, so the same run can
/// stand in the log more than once after the fault (`after`): the one whose send times fit is
/// the one received.
fn assert_timed_run_of<T: PartialEq + Debug>(
    got: &[T],
    sent: &[T],
    after: usize,
    poses: &[TrackerPose],
    sent_at: &[Instant],
    t0: Now,
    what: &str,
) {
    assert!(!got.is_empty(), "{what}: nothing received");
    let runs: Vec<usize> = (after..sent.len())
        .filter(|&i| {
            got.iter()
                .enumerate()
                .all(|(k, g)| sent.get(i + k) == Some(g))
        })
        .collect();
    assert!(
        !runs.is_empty(),
        "{what}: the {} values received are not a run of the {} sent (first {:?})",
        got.len(),
        sent.len() - after.min(sent.len()),
        got[0]
    );
    let lags = |i: usize| -> Vec<f64> {
        poses
            .iter()
            .zip(&sent_at[i..])
            .map(|(p, &at)| p.time.seconds_since(t0.wall.plus(at - t0.mono)))
            .collect()
    };
    assert!(
        runs.iter()
            .any(|&i| lags(i).iter().all(|l| (-0.002..0.5).contains(l))),
        "{what}: no run of the log has send times that fit the poses' times (lags of the \
         first: {:?})",
        &lags(runs[0])[..lags(runs[0]).len().min(5)]
    );
}

/// The garbage put between Fastrak records: a lone sync character, partial headers, a bad
/// station, a bad third character, control bytes.
const FASTRAK_JUNK: [&[u8]; 6] = [
    b"0",
    b"01 ",
    b"\x00\xff0",
    b"05",
    b"01\x01",
    b"01 \x11\x12\x13\x14\x15\x16\x17\x18\x19\x1a",
];

/// The Fastrak's binary records as the client must see them, with the time each left.
fn fastrak_sent(sim: &Simulated<FastrakSim>) -> (Vec<Values>, Vec<Instant>) {
    let log: Vec<fastrak_sim::SentRecord> = sim.with(|d| {
        d.model
            .inner
            .log
            .iter()
            .filter(|r| r.binary)
            .copied()
            .collect()
    });
    let want = log
        .iter()
        .map(|r| {
            let (pos, q) = fastrak_sim::pose(r.station, r.seq);
            (
                usize::from(r.station) - 1,
                pos.map(|v| f64::from(v) * METRES_PER_INCH),
                [q[1], q[2], q[3], q[0]].map(f64::from),
            )
        })
        .collect();
    (want, log.iter().map(|r| r.first_byte_at).collect())
}

/// Checks poses `from..` against the simulator's log from record `after` on: exact and
/// contiguous, each recent.
fn check_fastrak(
    c: &Client,
    sim: &Simulated<FastrakSim>,
    (from, after): (usize, usize),
    t0: Now,
    what: &str,
) {
    let (want, at) = fastrak_sent(sim);
    let poses = c.poses.borrow();
    let got: Vec<Values> = poses[from..].iter().map(values).collect();
    assert_timed_run_of(&got, &want, after, &poses[from..], &at, t0, what);
}

#[test]
fn fastrak_survives_garbage_silence_and_unplugging() {
    let _serial = one_at_a_time();
    let sim = Simulated::start("fastrak", || {
        let mut cfg = FastrakConfig::new(115_200);
        cfg.stations = 2;
        FastrakSim::new(cfg)
    });
    let t0 = Now::read();
    let c = Client::start(
        &format!(
            "vrpn_Tracker_Fastrak Tracker0 {} 115200\n",
            sim.path.display()
        ),
        "Tracker0",
    );
    c.wait_poses(60, Duration::from_secs(10), "start-up");
    check_fastrak(&c, &sim, (0, 0), t0, "streaming");
    let sensors: Vec<usize> = c.poses.borrow().iter().map(|p| p.sensor).collect();
    assert!(
        sensors.windows(2).all(|w| w[0] != w[1]),
        "stations alternate"
    );

    // Garbage between records: reported, and not one record lost.
    sim.with(|d| d.model.junk = FASTRAK_JUNK.iter().map(|j| j.to_vec()).collect());
    let injected = || sim.with(|d| d.model.injected);
    assert!(
        c.pump_until(Duration::from_secs(5), |_| injected() == FASTRAK_JUNK.len()),
        "garbage injected: {}",
        injected()
    );
    let n = c.count();
    c.wait_poses(n + 40, Duration::from_secs(5), "after garbage");
    check_fastrak(&c, &sim, (0, 0), t0, "through garbage");
    c.wait_text(
        0,
        "While syncing (looking for '0', got",
        Duration::from_secs(2),
    );

    // Silence: the watchdog resets the tracker; once it answers, records resume.
    let texts_before = c.texts.borrow().len();
    let logged = fastrak_sent(&sim).0.len();
    sim.with(|d| d.model.inner.set_silent(true));
    c.wait_text(
        texts_before,
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
    );
    let silent_poses = c.count();
    sim.with(|d| d.model.inner.set_silent(false));
    let woke = Instant::now();
    c.wait_poses(silent_poses + 1, Duration::from_secs(8), "after silence");
    eprintln!(
        "Fastrak: first pose {:.0} ms after the tracker woke",
        woke.elapsed().as_secs_f64() * 1e3
    );
    c.wait_poses(silent_poses + 40, Duration::from_secs(8), "after silence");
    check_fastrak(
        &c,
        &sim,
        (silent_poses, logged),
        t0,
        "after the watchdog's reset",
    );

    // Unplugged: reported, reopened under the same path once back, reset, streaming again.
    let texts_before = c.texts.borrow().len();
    let logged = fastrak_sent(&sim).0.len();
    sim.with(|d| d.unplug());
    c.wait_text(texts_before, "failed", Duration::from_secs(3));
    let unplugged = c.count();
    // Nothing arrives while unplugged.
    c.pump_until(Duration::from_millis(300), |_| false);
    assert_eq!(c.count(), unplugged, "poses while unplugged");
    sim.with(|d| d.plug()).unwrap();
    let plugged = Instant::now();
    c.wait_poses(unplugged + 1, Duration::from_secs(6), "after plugging back");
    eprintln!(
        "Fastrak: first pose {:.0} ms after plugging back",
        plugged.elapsed().as_secs_f64() * 1e3
    );
    c.wait_poses(
        unplugged + 40,
        Duration::from_secs(6),
        "after plugging back",
    );
    c.wait_text(texts_before, "is open again", Duration::from_secs(1));
    check_fastrak(&c, &sim, (unplugged, logged), t0, "after plugging back");
}

/// The garbage put between Flock records: bytes without the phasing bit, a record cut short
/// by the next, and whole records of addresses no receiver has.
const FLOCK_JUNK: [&[u8]; 4] = [
    &[0x01, 0x02, 0x7F, 0x00, 0x55],
    &[0x80, 0x10, 0x20, 0x30],
    &[0x80, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 0x09],
    &[0x81, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 0x01],
];

/// The Flock's position/quaternion records (the format the driver selects).
fn flock_sent(sim: &Simulated<FlockSim>) -> Vec<flock_sim::SentRecord> {
    sim.with(|d| {
        d.model
            .inner
            .flock()
            .sent()
            .iter()
            .filter(|r| r.pos_quat)
            .copied()
            .collect()
    })
}

/// Checks poses `from..` against the simulator's log from record `after` on: exact and
/// contiguous, each recent.
fn check_flock(
    c: &Client,
    sim: &Simulated<FlockSim>,
    (from, after): (usize, usize),
    t0: Now,
    what: &str,
) {
    let log = flock_sent(sim);
    let tx = Transmitter::from_ert(true);
    let first = tx.first_receiver_address();
    let want: Vec<Values> = log
        .iter()
        .map(|r| {
            (
                usize::from(r.address - first),
                r.pose.expected_position_m(tx),
                r.pose.expected_quat_xyzw(false),
            )
        })
        .collect();
    let at: Vec<Instant> = log.iter().map(|r| r.first_byte_at).collect();
    let poses = c.poses.borrow();
    let got: Vec<Values> = poses[from..].iter().map(values).collect();
    assert_timed_run_of(&got, &want, after, &poses[from..], &at, t0, what);
}

#[test]
fn flock_survives_garbage_silence_and_unplugging() {
    let _serial = one_at_a_time();
    let sim = Simulated::start("flock", || {
        let mut cfg = FlockConfig::new(4, true, 115_200);
        // RTS does not reach a device through a pseudo-terminal.
        cfg.rts_wired = false;
        cfg.keep_log = true;
        FlockSim::new(cfg)
    });
    let t0 = Now::read();
    let c = Client::start(
        &format!(
            "vrpn_Tracker_Flock Flock0 4 {} 115200 0\n",
            sim.path.display()
        ),
        "Flock0",
    );
    c.wait_poses(100, Duration::from_secs(10), "start-up");
    check_flock(&c, &sim, (0, 0), t0, "streaming");
    let sensors: Vec<usize> = c.poses.borrow().iter().take(8).map(|p| p.sensor).collect();
    assert!(
        sensors.windows(2).all(|w| w[1] == (w[0] + 1) % 4),
        "receivers in turn: {sensors:?}"
    );

    // Garbage between records: reported, and not one record lost.
    sim.with(|d| d.model.junk = FLOCK_JUNK.iter().map(|j| j.to_vec()).collect());
    let injected = || sim.with(|d| d.model.injected);
    assert!(
        c.pump_until(Duration::from_secs(5), |_| injected() == FLOCK_JUNK.len()),
        "garbage injected: {}",
        injected()
    );
    let n = c.count();
    c.wait_poses(n + 100, Duration::from_secs(5), "after garbage");
    check_flock(&c, &sim, (0, 0), t0, "through garbage");
    c.wait_text(0, "skipped", Duration::from_secs(2));

    // A hung device: the watchdog resets it, and records resume by themselves.
    let texts_before = c.texts.borrow().len();
    let logged = flock_sent(&sim).len();
    let stalled_at = Instant::now();
    sim.with(|d| d.model.inner.stall());
    c.wait_text(
        texts_before,
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
    );
    let stalled = c.count();
    c.wait_poses(stalled + 1, Duration::from_secs(8), "after the reset");
    eprintln!(
        "Flock: first pose {:.0} ms after the line stalled",
        stalled_at.elapsed().as_secs_f64() * 1e3
    );
    c.wait_poses(stalled + 100, Duration::from_secs(8), "after the reset");
    check_flock(
        &c,
        &sim,
        (stalled, logged),
        t0,
        "after the watchdog's reset",
    );
    // A second reset (RTS does not reach a pseudo-terminal: counted by auto-configurations).
    assert_eq!(sim.with(|d| d.model.inner.flock().autoconfigs()), 2);

    // Unplugged: reported, reopened under the same path once back, reset, streaming again.
    let texts_before = c.texts.borrow().len();
    let logged = flock_sent(&sim).len();
    sim.with(|d| d.unplug());
    c.wait_text(texts_before, "failed", Duration::from_secs(3));
    let unplugged = c.count();
    c.pump_until(Duration::from_millis(300), |_| false);
    assert_eq!(c.count(), unplugged, "poses while unplugged");
    sim.with(|d| d.plug()).unwrap();
    let plugged = Instant::now();
    c.wait_poses(unplugged + 1, Duration::from_secs(6), "after plugging back");
    eprintln!(
        "Flock: first pose {:.0} ms after plugging back",
        plugged.elapsed().as_secs_f64() * 1e3
    );
    c.wait_poses(
        unplugged + 100,
        Duration::from_secs(6),
        "after plugging back",
    );
    c.wait_text(texts_before, "is open again", Duration::from_secs(1));
    check_flock(&c, &sim, (unplugged, logged), t0, "after plugging back");
}
