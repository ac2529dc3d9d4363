//! `vrpn_Tracker_Flock_Parallel`: a Flock with one serial line per receiver, besides the
//! master's.
//!
//! A [`SerialDriver`] serves one port, so the Flock is a group of drivers, one per line,
//! sharing one state (and the one [`TrackerServer`]): [`FlockParallelPort::new_group`] returns
//! them, master first, each with the path of its port.
//!
//! * The master's line runs the reset of the whole Flock (see the reset module: extended-range
//!   transmitter, `+z` hemisphere, group mode on) and stays in point mode; it reports nothing.
//!   Opening it (at start, after it closed, after a failure) resets the Flock.
//! * When that reset is done, each receiver's line starts on its own: `'B'` (stop a stream),
//!   [`SLAVE_SETTLE`] for a record in flight to land, discard the input, `'@'`. A receiver's
//!   line that reopens while the Flock runs does just this. Its records (14 bytes, no address
//!   byte) are reported as sensor = the line's index, with the extended-range scale, never
//!   inverted.
//! * A receiver's line silent for [`WATCHDOG`] (or a failed master reset) fails the whole
//!   Flock: the master asks the Flock for its error code (reported as text), then every port is
//!   reopened and the Flock reset; after [`FAILURES_BEFORE_PAUSE`] failures in a row the group
//!   sends advice and waits [`RETRY_PAUSE`] first.
//!
//! Messages all go out from the tracker's name (C++ registers internal senders
//! `flockSlave0`, `flockSlave1`, … for the receivers but sends with the master's id; the
//! names are registered here too, so a client sees the same sender list).
//!
//! Differences from C++: the receivers' watchdog is [`WATCHDOG`] (2 s), not 13 s (C++ allowed
//! for its blocking reset of every line, one after the other); the receivers' lines start
//! together, 0.1 s after the master's reset, instead of 0.5 s each in turn.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::{self, Hemisphere};
use super::framer::Framer;
use super::notes::{say, FailureText};
use super::record::{PosQuat, Transmitter, RECORD_LEN};
use super::reset::{
    ErrorQuery, Outcome, Progress, QueryProgress, ResetPlan, ResetSequence, POINT, STREAM,
};
use super::{SkipNotes, ADVICE, FAILURES_BEFORE_PAUSE, RETRY_PAUSE, TRYING_TO_RESET, WATCHDOG};
use crate::devices::text::TextSeverity;
use crate::serial::{PortKind, PortOps, PortSettings, SerialDriver};
use crate::time::Now;
use crate::{Connection, Error, TrackerServer};

/// Time between stopping a receiver's stream and restarting it: a 14-byte record in flight
/// takes 58 ms at 2400 baud (C++ sleeps 0.5 s).
pub const SLAVE_SETTLE: Duration = Duration::from_millis(100);

/// Which line a [`FlockParallelPort`] serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The master bird's line: resets and supervises the Flock.
    Master,
    /// Receiver `i`'s own line (sensor `i`).
    Receiver(usize),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// The master's port is not open (at start, after it closed, during a restart).
    WaitingForMaster,
    /// The master's reset runs.
    MasterReset,
    /// The Flock is configured; receivers' lines stream.
    Running,
    /// Something failed at `at`; the master asks why when it next runs.
    Failing { at: Instant },
    /// The master asks the Flock for its error code.
    ErrorQuery,
    /// Waiting after repeated failures.
    Pausing { until: Instant },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SlaveState {
    /// Waiting for the Flock (or the port).
    Idle,
    /// Stop the stream at `at`.
    Start { at: Instant },
    /// `'B'` sent; restart the stream at `until`.
    Settling { until: Instant },
    /// Records flow.
    Streaming,
}

struct Slave {
    open: bool,
    generation_seen: u64,
    state: SlaveState,
    framer: Framer,
    last_record: Option<Now>,
}

struct Group {
    tracker: TrackerServer,
    phase: Phase,
    reset: ResetSequence,
    query: ErrorQuery,
    master_open: bool,
    master_generation_seen: u64,
    slaves: Vec<Slave>,
    /// Bumped by every restart; a port that saw less reopens.
    generation: u64,
    restart_at: Option<Instant>,
    failures: u32,
    records: u64,
    skips: SkipNotes,
    rate: Option<(u8, f64)>,
}

impl Group {
    fn stop_slaves(&mut self) {
        for s in &mut self.slaves {
            s.state = SlaveState::Idle;
            s.framer.clear();
            s.last_record = None;
        }
    }

    /// Marks the Flock failed; the master acts on it at its next poll.
    fn fail(&mut self, now: Instant) {
        if !matches!(self.phase, Phase::MasterReset | Phase::Running) {
            return;
        }
        self.phase = Phase::Failing { at: now };
        self.reset.stop();
        self.stop_slaves();
    }

    /// After the error query (or without one): reopen everything, or pause first.
    fn give_up(&mut self, now: Instant) {
        say(
            &self.tracker,
            TextSeverity::Error,
            format_args!("{TRYING_TO_RESET}"),
        );
        self.failures += 1;
        if self.failures % FAILURES_BEFORE_PAUSE == 0 {
            say(&self.tracker, TextSeverity::Error, format_args!("{ADVICE}"));
            self.phase = Phase::Pausing {
                until: now + RETRY_PAUSE,
            };
        } else {
            self.restart(now);
        }
    }

    fn restart(&mut self, now: Instant) {
        self.generation += 1;
        self.restart_at = Some(now);
        self.phase = Phase::WaitingForMaster;
        self.stop_slaves();
    }

    fn reset_done(&mut self, outcome: Outcome, now: Now) {
        self.phase = Phase::Running;
        self.rate = outcome.rate;
        for s in self.slaves.iter_mut().filter(|s| s.open) {
            s.state = SlaveState::Start { at: now.mono };
        }
        let receivers = self.slaves.len();
        match outcome.rate {
            Some((mhz, hz)) => say(
                &self.tracker,
                TextSeverity::Normal,
                format_args!(
                    "Flock reset: {receivers} receivers, measurement rate {hz:.2} Hz \
                     ({mhz} MHz crystal)"
                ),
            ),
            None => say(
                &self.tracker,
                TextSeverity::Warning,
                format_args!(
                    "Flock reset: {receivers} receivers; the measurement rate did not arrive"
                ),
            ),
        }
    }

    fn master_progress(&mut self, p: Progress, now: Now) {
        match p {
            Progress::Working => {}
            Progress::Done(outcome) => self.reset_done(outcome, now),
            Progress::Failed(failure) => {
                let units = self.reset.plan().units();
                say(
                    &self.tracker,
                    TextSeverity::Error,
                    format_args!("{}", FailureText { failure, units }),
                );
                self.fail(now.mono);
            }
        }
    }

    fn query_done(&mut self, code: Option<[u8; 2]>, now: Instant) {
        match code {
            Some([0, _]) => say(
                &self.tracker,
                TextSeverity::Warning,
                format_args!("Flock reports no error code"),
            ),
            Some([code, expanded]) => say(
                &self.tracker,
                TextSeverity::Error,
                format_args!(
                    "Flock error code {code} (expanded: address {}, command {})",
                    expanded & 0x0F,
                    expanded >> 4
                ),
            ),
            None => say(
                &self.tracker,
                TextSeverity::Error,
                format_args!("Flock did not answer the error-code request"),
            ),
        }
        self.give_up(now);
    }
}

/// One serial line of a `vrpn_Tracker_Flock_Parallel`: the master's or a receiver's.
pub struct FlockParallelPort {
    name: String,
    path: String,
    baud: u32,
    role: Role,
    group: Rc<RefCell<Group>>,
}

impl FlockParallelPort {
    /// The drivers for a `vrpn_Tracker_Flock_Parallel` entry: the master's line first, then
    /// receiver 0's, 1's, …; the tracker (one sensor per receiver) is served on `conn`.
    pub fn new_group(
        cfg: &config::FlockParallel,
        conn: &Connection,
    ) -> Result<Vec<FlockParallelPort>, Error> {
        let receivers = u8::try_from(cfg.sensors)
            .ok()
            .filter(|n| (1..=config::MAX_FLOCK_SENSORS as u8).contains(n))
            .ok_or(Error::Unsupported("a Flock has 1 to 13 receivers"))?;
        if cfg.slave_ports.len() != usize::from(receivers) {
            return Err(Error::Unsupported(
                "a parallel Flock needs one serial port per receiver",
            ));
        }
        let tracker = TrackerServer::new(&cfg.name, conn, usize::from(receivers))?;
        for i in 0..receivers {
            conn.register_sender(&format!("flockSlave{i}"))?;
        }
        let slaves = (0..receivers)
            .map(|_| Slave {
                open: false,
                generation_seen: 0,
                state: SlaveState::Idle,
                framer: Framer::new(RECORD_LEN),
                last_record: None,
            })
            .collect();
        let group = Rc::new(RefCell::new(Group {
            tracker,
            phase: Phase::WaitingForMaster,
            reset: ResetSequence::new(ResetPlan {
                receivers,
                transmitter: Transmitter::ExtendedRange,
                hemisphere: Hemisphere::PosZ,
                stream: false,
            }),
            query: ErrorQuery::default(),
            master_open: false,
            master_generation_seen: 0,
            slaves,
            generation: 0,
            restart_at: None,
            failures: 0,
            records: 0,
            skips: SkipNotes::default(),
            rate: None,
        }));
        let port = |role, path: &str| FlockParallelPort {
            name: cfg.name.clone(),
            path: path.to_owned(),
            baud: cfg.baud,
            role,
            group: group.clone(),
        };
        let mut ports = vec![port(Role::Master, &cfg.master_port)];
        for (i, path) in cfg.slave_ports.iter().enumerate() {
            ports.push(port(Role::Receiver(i), path));
        }
        Ok(ports)
    }

    /// The serial port to open, as the configuration gives it.
    pub fn port(&self) -> &str {
        &self.path
    }

    /// The line this driver serves.
    pub fn role(&self) -> Role {
        self.role
    }

    /// True when the Flock is configured and every open receiver's line streams.
    pub fn is_streaming(&self) -> bool {
        let g = self.group.borrow();
        g.phase == Phase::Running
            && g.slaves
                .iter()
                .filter(|s| s.open)
                .all(|s| s.state == SlaveState::Streaming)
    }

    /// True while receiver `i`'s line streams.
    pub fn receiver_streaming(&self, i: usize) -> bool {
        self.group
            .borrow()
            .slaves
            .get(i)
            .is_some_and(|s| s.state == SlaveState::Streaming)
    }

    /// Records reported since construction (all lines).
    pub fn records(&self) -> u64 {
        self.group.borrow().records
    }

    /// Bytes skipped while looking for records (all lines).
    pub fn skipped_bytes(&self) -> u64 {
        self.group.borrow().skips.total
    }

    /// Failed attempts since the last record.
    pub fn failures(&self) -> u32 {
        self.group.borrow().failures
    }

    /// Restarts (reopen of every port) since construction.
    pub fn restarts(&self) -> u64 {
        self.group.borrow().generation
    }

    /// The crystal speed (MHz) and measurement rate (Hz) the last reset read, if it could.
    pub fn measurement_rate(&self) -> Option<(u8, f64)> {
        self.group.borrow().rate
    }

    fn master_poll(&mut self, now: Now, port: &mut PortOps) {
        let mut g = self.group.borrow_mut();
        if g.master_generation_seen < g.generation {
            g.master_generation_seen = g.generation;
            g.master_open = false;
            port.reopen();
            return;
        }
        match g.phase {
            Phase::MasterReset => {
                let p = g.reset.poll(now, port);
                g.master_progress(p, now);
            }
            Phase::Failing { at } if now.mono >= at => {
                if g.master_open {
                    g.query.start(now, port);
                    g.phase = Phase::ErrorQuery;
                } else {
                    g.give_up(now.mono);
                }
            }
            Phase::ErrorQuery => {
                if let QueryProgress::Done(code) = g.query.poll(now, port) {
                    g.query_done(code, now.mono);
                }
            }
            Phase::Pausing { until } if now.mono >= until => g.restart(now.mono),
            _ => {}
        }
    }

    fn slave_poll(&mut self, i: usize, now: Now, port: &mut PortOps) {
        let mut g = self.group.borrow_mut();
        let generation = g.generation;
        let s = &mut g.slaves[i];
        if s.generation_seen < generation {
            s.generation_seen = generation;
            s.open = false;
            port.reopen();
            return;
        }
        match s.state {
            SlaveState::Idle => {}
            SlaveState::Start { at } if now.mono >= at => {
                port.write(&[POINT]);
                s.state = SlaveState::Settling {
                    until: now.mono + SLAVE_SETTLE,
                };
            }
            SlaveState::Settling { until } if now.mono >= until => {
                port.flush_input();
                port.write(&[STREAM]);
                s.state = SlaveState::Streaming;
                s.framer.clear();
                s.last_record = Some(now);
            }
            SlaveState::Streaming
                if s.last_record.is_some_and(|t| now.mono >= t.mono + WATCHDOG) =>
            {
                say(
                    &g.tracker,
                    TextSeverity::Error,
                    format_args!("Too long since last report, resetting (receiver {i})"),
                );
                g.fail(now.mono);
            }
            _ => {}
        }
    }

    fn slave_received(&mut self, i: usize, bytes: &[u8], arrived: Now) {
        let mut g = self.group.borrow_mut();
        let g = &mut *g;
        let s = &mut g.slaves[i];
        if s.state != SlaveState::Streaming {
            return;
        }
        for &b in bytes {
            let Some(framed) = s.framer.push(b, arrived) else {
                continue;
            };
            if framed.skipped > 0 {
                g.skips
                    .add(framed.skipped, framed.first_byte.mono, &g.tracker);
            }
            let r = PosQuat::decode(&framed.bytes);
            s.last_record = Some(framed.first_byte);
            g.records += 1;
            g.failures = 0;
            // A failed send is the connection's business (it reports and drops the peer).
            let _ = g.tracker.report_pose(
                i as i32,
                framed.first_byte.wall,
                r.position_m(Transmitter::ExtendedRange),
                r.quat_xyzw(),
            );
        }
    }
}

impl SerialDriver for FlockParallelPort {
    fn name(&self) -> &str {
        &self.name
    }

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn opened(&mut self, now: Now, port: &mut PortOps) {
        let mut g = self.group.borrow_mut();
        match self.role {
            Role::Master => {
                g.master_open = true;
                g.master_generation_seen = g.generation;
                g.query.stop();
                g.stop_slaves();
                g.phase = Phase::MasterReset;
                g.reset.start(now, port);
            }
            Role::Receiver(i) => {
                let running = g.phase == Phase::Running;
                let generation = g.generation;
                let s = &mut g.slaves[i];
                s.open = true;
                s.generation_seen = generation;
                s.framer.clear();
                s.last_record = None;
                s.state = if running {
                    SlaveState::Start { at: now.mono }
                } else {
                    SlaveState::Idle
                };
            }
        }
    }

    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        match self.role {
            Role::Master => {
                let mut g = self.group.borrow_mut();
                match g.phase {
                    Phase::MasterReset => {
                        let p = g.reset.received(bytes, arrived, port);
                        g.master_progress(p, arrived);
                    }
                    Phase::ErrorQuery => {
                        if let QueryProgress::Done(code) = g.query.received(bytes, arrived) {
                            g.query_done(code, arrived.mono);
                        }
                    }
                    _ => {}
                }
            }
            Role::Receiver(i) => self.slave_received(i, bytes, arrived),
        }
    }

    fn poll(&mut self, now: Now, port: &mut PortOps) {
        match self.role {
            Role::Master => self.master_poll(now, port),
            Role::Receiver(i) => self.slave_poll(i, now, port),
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let g = self.group.borrow();
        match self.role {
            Role::Master => {
                if g.master_generation_seen < g.generation {
                    return g.restart_at;
                }
                match g.phase {
                    Phase::MasterReset => g.reset.deadline(),
                    Phase::Failing { at } => Some(at),
                    Phase::ErrorQuery => g.query.deadline(),
                    Phase::Pausing { until } => Some(until),
                    Phase::WaitingForMaster | Phase::Running => None,
                }
            }
            Role::Receiver(i) => {
                let s = &g.slaves[i];
                if s.generation_seen < g.generation {
                    return g.restart_at;
                }
                match s.state {
                    SlaveState::Idle => None,
                    SlaveState::Start { at } => Some(at),
                    SlaveState::Settling { until } => Some(until),
                    SlaveState::Streaming => s.last_record.map(|t| t.mono + WATCHDOG),
                }
            }
        }
    }

    fn closed(&mut self, _now: Now) {
        let mut g = self.group.borrow_mut();
        match self.role {
            Role::Master => {
                g.master_open = false;
                match g.phase {
                    Phase::MasterReset => {
                        g.reset.stop();
                        g.phase = Phase::WaitingForMaster;
                    }
                    Phase::Failing { .. } | Phase::ErrorQuery => {
                        // Reopening the master's port resets the whole Flock anyway.
                        g.query.stop();
                        g.phase = Phase::WaitingForMaster;
                    }
                    _ => {}
                }
            }
            Role::Receiver(i) => {
                let s = &mut g.slaves[i];
                s.open = false;
                s.state = SlaveState::Idle;
                s.framer.clear();
                s.last_record = None;
            }
        }
    }
}
