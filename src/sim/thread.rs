//! A device model on a pseudo-terminal, stepped in its own thread until dropped, with the
//! faults an end-to-end test needs: garbage between records, silence, unplugging.

use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::line::DeviceModel;
use super::pty::PtyDevice;
use crate::time::Now;

/// A model with the faults every driver is tested against, whatever the device:
///
/// * garbage put on the line between records ([`junk`](Self::junk)): a piece goes out only
///   after [`idle`](Self::idle) without output from the model and at most one per
///   [`APART`](Self::APART), so it falls between records, never inside one, and the driver
///   must lose no record to it;
/// * silence ([`mute`](Self::mute)): the device hears everything and answers as usual, but
///   nothing it sends reaches the line (a hung device, a cut wire).
pub struct Noisy<M> {
    /// The device.
    pub inner: M,
    /// Garbage still to put on the line, one piece per idle gap, in order.
    pub junk: Vec<Vec<u8>>,
    /// Pieces of garbage sent so far.
    pub injected: usize,
    /// While true, the device's output is lost.
    pub mute: bool,
    /// Silence that marks a gap between records ([`IDLE`](Self::IDLE) unless set): longer
    /// than the time between two bytes of a record.
    pub idle: Duration,
    last_out: Option<Instant>,
    last_junk: Option<Instant>,
}

impl<M> Noisy<M> {
    /// Far longer than the gaps inside a record at 9600 baud and up (a byte every < 1 ms).
    pub const IDLE: Duration = Duration::from_millis(2);
    /// At most one piece of garbage per this time.
    pub const APART: Duration = Duration::from_millis(40);

    /// `inner` without faults.
    pub fn new(inner: M) -> Noisy<M> {
        Noisy {
            inner,
            junk: Vec::new(),
            injected: 0,
            mute: false,
            idle: Self::IDLE,
            last_out: None,
            last_junk: None,
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
    fn set_baud(&mut self, baud: u32, now: Now) {
        self.inner.set_baud(baud, now);
    }
    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let before = out.len();
        self.inner.transmit(now, out);
        if self.mute {
            out.truncate(before);
            return;
        }
        if out.len() > before {
            self.last_out = Some(now.mono);
            return;
        }
        let idle = self.last_out.is_some_and(|t| now.mono >= t + self.idle);
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

type Job<M> = Box<dyn FnOnce(&mut [PtyDevice<Noisy<M>>]) + Send>;

/// Device models on pseudo-terminals, stepped in their own thread (every 200 µs, at the
/// wall clock) until dropped. The models are built inside that thread (devices on several
/// lines may share state that cannot cross threads) and reached through
/// [`with`](Self::with) and the helpers below; each line's path is what a `vrpn.cfg` line
/// names.
///
/// ```no_run
/// # use vrpn::sim::{DeviceModel, SimulatedDevice};
/// # fn example<M: DeviceModel + Send + 'static>(my_model: fn() -> M, sent: fn(&M) -> usize) {
/// // `my_model` builds the device's simulator (a driver's `sim.rs`).
/// let sim = SimulatedDevice::start("mydevice", my_model).unwrap();
/// let line = format!("vrpn_MyDevice Device0 {} 19200\n", sim.path().display());
/// sim.set_mute(true); // silence: the driver's watchdog must notice
/// let count = sim.model(move |m| sent(m)); // what the device has sent so far
/// # }
/// ```
pub struct SimulatedDevice<M: DeviceModel + 'static> {
    jobs: mpsc::Sender<Job<M>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    paths: Vec<PathBuf>,
    dir: PathBuf,
}

static NEXT_DIR: AtomicUsize = AtomicUsize::new(0);

impl<M: DeviceModel + 'static> SimulatedDevice<M> {
    /// Plugs the model `model()` builds in on a new pseudo-terminal (`path()`).
    pub fn start(name: &str, model: impl FnOnce() -> M + Send + 'static) -> io::Result<Self> {
        SimulatedDevice::start_lines(name, 1, move || vec![model()])
    }

    /// Plugs `lines` models in, one pseudo-terminal each (`paths()[i]` for `models()[i]`).
    pub fn start_lines(
        name: &str,
        lines: usize,
        models: impl FnOnce() -> Vec<M> + Send + 'static,
    ) -> io::Result<Self> {
        let n = NEXT_DIR.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("vrpn-sim-{}-{n}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let paths: Vec<PathBuf> = (0..lines).map(|i| dir.join(format!("tty{i}"))).collect();
        let stop = Arc::new(AtomicBool::new(false));
        let (jobs, inbox) = mpsc::channel::<Job<M>>();
        let (ready_tx, ready_rx) = mpsc::channel::<io::Result<()>>();
        let (s, p) = (stop.clone(), paths.clone());
        let thread = std::thread::spawn(move || {
            let opened: io::Result<Vec<PtyDevice<Noisy<M>>>> = models()
                .into_iter()
                .zip(&p)
                .map(|(m, path)| PtyDevice::open(Noisy::new(m), path))
                .collect();
            let mut devices = match opened {
                Ok(d) => d,
                Err(e) => {
                    let _ = ready_tx.send(Err(e));
                    return;
                }
            };
            let _ = ready_tx.send(Ok(()));
            while !s.load(Ordering::Relaxed) {
                while let Ok(job) = inbox.try_recv() {
                    job(&mut devices);
                }
                let now = Now::read();
                for d in &mut devices {
                    let _ = d.step(now);
                }
                std::thread::sleep(Duration::from_micros(200));
            }
        });
        let started = ready_rx
            .recv_timeout(Duration::from_secs(10))
            .map_err(|_| io::Error::other("the simulator thread did not start"))?;
        let sim = SimulatedDevice {
            jobs,
            stop,
            thread: Some(thread),
            paths,
            dir,
        };
        started.map(|()| sim)
    }

    /// The path of the (first) line, for the `vrpn.cfg` line.
    pub fn path(&self) -> &Path {
        &self.paths[0]
    }

    /// The paths of every line.
    pub fn paths(&self) -> &[PathBuf] {
        &self.paths
    }

    /// Runs `f` on every line's device in the simulator's thread and returns its result.
    pub fn with_all<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut [PtyDevice<Noisy<M>>]) -> R + Send + 'static,
    ) -> R {
        let (tx, rx) = mpsc::channel();
        self.jobs
            .send(Box::new(move |d| {
                let _ = tx.send(f(d));
            }))
            .expect("the simulator thread runs");
        rx.recv_timeout(Duration::from_secs(10))
            .expect("the simulator thread answers")
    }

    /// Runs `f` on the (first) line's device in the simulator's thread.
    pub fn with<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut PtyDevice<Noisy<M>>) -> R + Send + 'static,
    ) -> R {
        self.with_all(move |d| f(&mut d[0]))
    }

    /// Runs `f` on the (first) line's model.
    pub fn model<R: Send + 'static>(&self, f: impl FnOnce(&mut M) -> R + Send + 'static) -> R {
        self.with(move |d| f(&mut d.model.inner))
    }

    /// Silences the (first) device, or lets it speak again (see [`Noisy::mute`]).
    pub fn set_mute(&self, mute: bool) {
        self.with(move |d| d.model.mute = mute);
    }

    /// Queues garbage for the (first) line, one piece per gap between records.
    pub fn inject_between_records(&self, junk: &[&[u8]]) {
        let junk: Vec<Vec<u8>> = junk.iter().map(|j| j.to_vec()).collect();
        self.with(move |d| d.model.junk.extend(junk));
    }

    /// Sets the silence that marks a gap between records on the (first) line, for slow lines
    /// whose bytes come further apart than [`Noisy::IDLE`].
    pub fn set_junk_idle(&self, idle: Duration) {
        self.with(move |d| d.model.idle = idle);
    }

    /// Pieces of garbage put on the (first) line so far.
    pub fn injected(&self) -> usize {
        self.with(|d| d.model.injected)
    }

    /// Unplugs the (first) device: the driver's port fails and the path disappears.
    pub fn unplug(&self) {
        self.with(|d| d.unplug());
    }

    /// Plugs the (first) device back in, under the same path.
    pub fn plug(&self) -> io::Result<()> {
        self.with(|d| d.plug())
    }
}

impl<M: DeviceModel + 'static> Drop for SimulatedDevice<M> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
