//! A simulated Ascension Flock of Birds: the device end of its serial line(s), for tests and
//! for a simulator program on a pseudo-terminal.
//!
//! One [`SimFlock`] holds the state of the whole bus (which units are running, group mode,
//! each bird's output format and hemisphere, errors); each serial line is a [`FlockSim`] (a
//! [`DeviceModel`]) sharing it. [`FlockSim::new`] is a Flock on one line (the master bird's);
//! [`FlockSim::parallel`] gives the master's line and one line per receiver.
//!
//! What it does, as the real device does:
//!
//! * RTS up holds the master in reset (everything returns to its power-on state); after RTS
//!   drops it ignores commands for [`SimConfig::boot_time`].
//! * Commands (see the reset module's table): `'B'` (stop streaming; it also sends one point
//!   record when the Flock is running), `'@'`, `'G'` (sleep), `'F'` (run), `'O'` examine
//!   (bird status, crystal speed, rate count, error code, expanded error code, system status),
//!   `'P'` change (group mode, auto-configuration), `']'`, `'L'`, and the `0xF0 + a` prefix
//!   that forwards the next command to bird `a`. During an auto-configuration
//!   ([`SimConfig::autoconfig_time`]) commands are ignored; afterwards the configured units
//!   are running and measure at the rate the crystal speed and rate count give.
//! * A running bird streams one record per measurement cycle: position/quaternion (seven
//!   words) once `']'` selected it, else its power-on format, position/angles (six words).
//!   On the master line in group mode every receiver's record follows, each with its address
//!   byte; a receiver's own line carries its record alone.
//! * Bytes leave at the line's baud rate (ten bit times each, on whole microseconds), so the
//!   first and last bytes of a record arrive at different times.
//!
//! The values are known: [`pose`] gives the 14-bit numbers of every record (by bird address
//! and measurement cycle) and [`RawPose`] what a VRPN client must receive for them, computed
//! here independently of the driver. With [`SimConfig::keep_log`] every record put on a line
//! is logged ([`SimFlock::sent`]) with the time of its first byte.

use std::cell::{Ref, RefCell, RefMut};
use std::collections::VecDeque;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config;
use super::record::{Transmitter, METRES_PER_INCH, PHASING_BIT};
use super::reset::{
    self, AUTOCONFIG, BIRD_STATUS, CRYSTAL_SPEED, EXPANDED_ERROR, GROUP_MODE, RATE_COUNT,
    STATUS_LEN, SYSTEM_STATUS, UNIT_ACCESSIBLE, UNIT_RECEIVER, UNIT_RUNNING,
};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim flock PATH`: a Flock of Birds with two receivers and an extended-range
/// transmitter on one line (RTS does not reach a device through a pseudo-terminal).
pub static SIMULATOR: Simulator = Simulator {
    name: "flock",
    about: "Ascension Flock of Birds: 2 receivers, extended-range transmitter, one line",
    baud: 115_200,
    line: "vrpn_Tracker_Flock Tracker0 2 {PATH} {BAUD} 0",
    make: |baud| {
        let mut cfg = SimConfig::new(2, true, baud);
        cfg.rts_wired = false;
        Box::new(FlockSim::new(cfg))
    },
};

/// Highest bus address.
const MAX_ADDRESS: usize = 14;
/// Examine: error code (1 byte).
const ERROR_CODE: u8 = 10;
/// Run (wake from sleep).
const RUN: u8 = b'F';
/// Error code for a command the Flock does not know.
const INVALID_COMMAND: u8 = 6;
/// Error code for an auto-configuration asking for units that are not there.
const CONFIGURATION_ERROR: u8 = 33;

/// How the simulated Flock is built and behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Receivers (birds with a sensor), 1..=13 (14 without an extended-range controller).
    pub receivers: u8,
    /// The transmitter; an extended-range one has its controller at address 1.
    pub transmitter: Transmitter,
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Crystal speed in MHz (examine value 2).
    pub crystal_mhz: u8,
    /// Measurement-rate count (examine value 6); with the crystal it sets the rate.
    pub rate_count: u16,
    /// How long the master ignores commands after RTS drops or power returns.
    pub boot_time: Duration,
    /// How long an auto-configuration takes (commands are ignored meanwhile).
    pub autoconfig_time: Duration,
    /// Time from the end of a command to the first byte of its answer.
    pub reply_delay: Duration,
    /// The Flock was left configured and streaming by an earlier program.
    pub streaming_at_start: bool,
    /// RTS reaches the master (false: a three-wire cable, or a pseudo-terminal).
    pub rts_wired: bool,
    /// Log every record put on a line ([`SimFlock::sent`]). Off for long-running simulators.
    pub keep_log: bool,
}

impl SimConfig {
    /// A Flock with `receivers` receivers, with or without an extended-range transmitter, on
    /// lines at `baud`: 25 MHz crystal, a 100 Hz measurement rate, 0.5 s to start after a
    /// reset, 0.3 s per auto-configuration, answers after 2 ms, RTS wired, freshly powered
    /// (not streaming), no log.
    pub fn new(receivers: u8, ert: bool, baud: u32) -> SimConfig {
        SimConfig {
            receivers,
            transmitter: Transmitter::from_ert(ert),
            baud,
            crystal_mhz: 25,
            // 1000 / (4 × (7578 × 8 / 25) / 1000 + 0.3) ≈ 100.0 Hz
            rate_count: 7578,
            boot_time: Duration::from_millis(500),
            autoconfig_time: Duration::from_millis(300),
            reply_delay: Duration::from_millis(2),
            streaming_at_start: false,
            rts_wired: true,
            keep_log: false,
        }
    }

    /// The Flock a `vrpn_Tracker_Flock` entry describes.
    pub fn for_flock(cfg: &config::Flock) -> SimConfig {
        SimConfig::new(cfg.sensors as u8, cfg.use_ert, cfg.baud)
    }

    /// The Flock a `vrpn_Tracker_Flock_Parallel` entry describes (always extended range).
    pub fn for_parallel(cfg: &config::FlockParallel) -> SimConfig {
        SimConfig::new(cfg.sensors as u8, true, cfg.baud)
    }

    /// Units on the bus.
    pub fn units(&self) -> u8 {
        self.transmitter.units(self.receivers)
    }

    /// Measurement rate in Hz.
    pub fn rate_hz(&self) -> f64 {
        reset::measurement_rate(self.crystal_mhz, self.rate_count).unwrap_or(100.0)
    }

    /// One measurement cycle, on whole microseconds.
    pub fn period(&self) -> Duration {
        Duration::from_micros((1e6 / self.rate_hz()).round().max(1.0) as u64)
    }

    /// Time on the line of byte `i` of a burst, from the burst's start, on whole microseconds.
    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The 14-bit numbers (−8192..=8191) of one record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RawPose {
    /// X, Y, Z position.
    pub position: [i16; 3],
    /// Quaternion W, X, Y, Z (the Flock's order).
    pub quat_wxyz: [i16; 4],
}

impl RawPose {
    /// The position a VRPN client must receive, in metres.
    pub fn expected_position_m(&self, transmitter: Transmitter) -> [f64; 3] {
        let inches = transmitter.full_scale_inches();
        self.position
            .map(|v| f64::from(v) * inches / 8192.0 * METRES_PER_INCH)
    }

    /// The quaternion a VRPN client must receive (x, y, z, w); `invert` as the driver's
    /// invert-quaternion option (conjugate over squared length, quatlib's way).
    pub fn expected_quat_xyzw(&self, invert: bool) -> [f64; 4] {
        let [w, x, y, z] = self.quat_wxyz.map(|v| f64::from(v) / 8192.0);
        if !invert {
            return [x, y, z, w];
        }
        let n = 1.0 / (x * x + y * y + z * z + w * w);
        [-x * n, -y * n, -z * n, w * n]
    }

    /// Appends the position/quaternion record (14 bytes, phasing bit on the first).
    pub fn encode_pos_quat(&self, out: &mut Vec<u8>) {
        let words = [
            self.position[0],
            self.position[1],
            self.position[2],
            self.quat_wxyz[0],
            self.quat_wxyz[1],
            self.quat_wxyz[2],
            self.quat_wxyz[3],
        ];
        encode_words(&words, out);
    }

    /// Appends a position/angles record (12 bytes): the power-on output format.
    pub fn encode_pos_angles(&self, out: &mut Vec<u8>) {
        let words = [
            self.position[0],
            self.position[1],
            self.position[2],
            self.quat_wxyz[1],
            self.quat_wxyz[2],
            self.quat_wxyz[3],
        ];
        encode_words(&words, out);
    }
}

fn encode_words(words: &[i16], out: &mut Vec<u8>) {
    for (i, &v) in words.iter().enumerate() {
        let u = (v as u16) & 0x3FFF;
        let low = (u & 0x7F) as u8;
        out.push(if i == 0 { low | PHASING_BIT } else { low });
        out.push(((u >> 7) & 0x7F) as u8);
    }
}

/// The numbers the bird at `address` measures in measurement cycle `cycle`: positions sweep
/// the whole 14-bit range (both signs, both extremes), the orientation turns about a tilted
/// axis.
pub fn pose(address: u8, cycle: u64) -> RawPose {
    let a = u64::from(address);
    let position = [0u64, 1, 2].map(|i| {
        let v = (cycle.wrapping_mul(131 + 2 * i) + a * 1237 + i * 4099) % 16384;
        (v as i64 - 8192) as i16
    });
    let angle = (cycle as f64 * 1.7 + a as f64 * 40.0).to_radians();
    let axis = [1.0, f64::from(address), 2.0];
    let len = axis.iter().map(|c| c * c).sum::<f64>().sqrt();
    let (s, c) = (angle / 2.0).sin_cos();
    let q = [c, s * axis[0] / len, s * axis[1] / len, s * axis[2] / len];
    let quat_wxyz = q.map(|v| (v * 8191.0).round().clamp(-8192.0, 8191.0) as i16);
    RawPose {
        position,
        quat_wxyz,
    }
}

/// A record the simulator put on a line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentRecord {
    /// The line: 0 for the master's, `i + 1` for receiver `i`'s own line.
    pub line: usize,
    /// The bird's bus address.
    pub address: u8,
    /// Measurement cycle.
    pub cycle: u64,
    /// The numbers sent.
    pub pose: RawPose,
    /// True for the position/quaternion format (else position/angles).
    pub pos_quat: bool,
    /// When its first byte left the device.
    pub first_byte_at: Instant,
}

/// The state of the whole simulated Flock, shared by its lines.
#[derive(Debug)]
pub struct SimFlock {
    cfg: SimConfig,
    parallel: bool,
    started: bool,
    powered: bool,
    rts_up: bool,
    booting_until: Option<Instant>,
    /// An auto-configuration in progress: when it ends, and the units it covers.
    autoconfig: Option<(Instant, u8)>,
    running: bool,
    configured_units: u8,
    /// Start of measurement cycle 0.
    epoch: Option<Instant>,
    /// Bumped whenever every stream must stop (reset, auto-configuration, sleep).
    generation: u64,
    group_mode: bool,
    pos_quat: [bool; MAX_ADDRESS + 1],
    hemisphere: [Option<[u8; 2]>; MAX_ADDRESS + 1],
    error: [u8; 2],
    log: Vec<SentRecord>,
    resets: u32,
    autoconfigs: u32,
}

impl SimFlock {
    fn new(cfg: SimConfig, parallel: bool) -> SimFlock {
        SimFlock {
            cfg,
            parallel,
            started: false,
            powered: true,
            rts_up: false,
            booting_until: None,
            autoconfig: None,
            running: false,
            configured_units: 0,
            epoch: None,
            generation: 0,
            group_mode: false,
            pos_quat: [false; MAX_ADDRESS + 1],
            hemisphere: [None; MAX_ADDRESS + 1],
            error: [0; 2],
            log: Vec::new(),
            resets: 0,
            autoconfigs: 0,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    fn power_on_state(&mut self) {
        self.autoconfig = None;
        self.running = false;
        self.configured_units = 0;
        self.epoch = None;
        self.generation += 1;
        self.group_mode = false;
        self.pos_quat = [false; MAX_ADDRESS + 1];
        self.hemisphere = [None; MAX_ADDRESS + 1];
        self.error = [0; 2];
    }

    /// First contact: a Flock left streaming by an earlier program is configured already.
    fn touch(&mut self, now: Instant) {
        if !self.started {
            self.started = true;
            if self.cfg.streaming_at_start {
                self.running = true;
                self.configured_units = self.cfg.units();
                self.epoch = Some(now);
                self.group_mode = !self.parallel;
                for a in self.receiver_addresses() {
                    self.pos_quat[usize::from(a)] = true;
                }
            }
        }
        if let Some((done, units)) = self.autoconfig {
            if done <= now {
                self.autoconfig = None;
                self.running = true;
                self.configured_units = units;
                self.epoch = Some(done);
            }
        }
        if self.booting_until.is_some_and(|b| b <= now) {
            self.booting_until = None;
        }
    }

    /// True when the master takes commands.
    fn listening(&self) -> bool {
        self.powered && !self.rts_up && self.booting_until.is_none() && self.autoconfig.is_none()
    }

    fn receiver_addresses(&self) -> std::ops::Range<u8> {
        let first = self.cfg.transmitter.first_receiver_address();
        first..first + self.cfg.receivers
    }

    fn is_receiver(&self, address: u8) -> bool {
        self.receiver_addresses().contains(&address)
    }

    /// True when the bird at `address` is measuring.
    fn measuring(&self, address: u8) -> bool {
        self.powered && self.running && address >= 1 && address <= self.configured_units
    }

    fn start_time(&self, cycle: u64) -> Option<Instant> {
        let period = self.cfg.period().as_micros() as u64;
        self.epoch
            .map(|e| e + Duration::from_micros(period.saturating_mul(cycle)))
    }

    /// First cycle starting at or after `t`.
    fn cycle_at_or_after(&self, t: Instant) -> u64 {
        let Some(e) = self.epoch else { return 0 };
        let since = t.saturating_duration_since(e).as_micros() as u64;
        let period = self.cfg.period().as_micros() as u64;
        since.div_ceil(period)
    }

    /// The last cycle started at or before `t`.
    fn cycle_before(&self, t: Instant) -> u64 {
        let Some(e) = self.epoch else { return 0 };
        let since = t.saturating_duration_since(e).as_micros() as u64;
        since / self.cfg.period().as_micros() as u64
    }

    /// Powers the Flock off (silent, deaf) or on (power-on state, starting for the boot time).
    pub fn set_powered(&mut self, on: bool, now: Now) {
        if on == self.powered {
            return;
        }
        self.powered = on;
        self.power_on_state();
        self.booting_until = on.then(|| now.mono + self.cfg.boot_time);
    }

    /// Sets the error code and its expansion the Flock reports next (as a fault would).
    pub fn set_error(&mut self, code: u8, expanded: u8) {
        self.error = [code, expanded];
    }

    /// True while running (auto-configured and not asleep).
    pub fn is_running(&self) -> bool {
        self.running
    }

    /// Units the last auto-configuration covered.
    pub fn configured_units(&self) -> u8 {
        self.configured_units
    }

    /// Group mode.
    pub fn group_mode(&self) -> bool {
        self.group_mode
    }

    /// True when the bird at `address` outputs position/quaternion records.
    pub fn pos_quat_format(&self, address: u8) -> bool {
        self.pos_quat
            .get(usize::from(address))
            .copied()
            .unwrap_or(false)
    }

    /// The hemisphere bytes last set on the bird at `address`.
    pub fn hemisphere(&self, address: u8) -> Option<[u8; 2]> {
        self.hemisphere.get(usize::from(address)).copied().flatten()
    }

    /// Times RTS reset the master.
    pub fn resets(&self) -> u32 {
        self.resets
    }

    /// Auto-configurations started.
    pub fn autoconfigs(&self) -> u32 {
        self.autoconfigs
    }

    /// Every record put on a line so far (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentRecord] {
        &self.log
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.log.clear();
    }

    fn system_status(&self) -> [u8; STATUS_LEN] {
        let mut s = [0u8; STATUS_LEN];
        for address in 1..=self.cfg.units() {
            let mut b = UNIT_ACCESSIBLE;
            if self.measuring(address) {
                b |= UNIT_RUNNING;
            }
            if self.is_receiver(address) {
                b |= UNIT_RECEIVER;
            }
            s[usize::from(address - 1)] = b;
        }
        s
    }
}

/// One serial line of a simulated Flock (a [`DeviceModel`]).
pub struct FlockSim {
    flock: Rc<RefCell<SimFlock>>,
    line: usize,
    own_address: u8,
    /// A command being received, and the address a `0xF0 + a` prefix chose.
    pending: [u8; 4],
    pending_len: usize,
    target: Option<u8>,
    out: VecDeque<(Instant, u8)>,
    tail: Option<Instant>,
    streaming: bool,
    stream_generation: u64,
    next_cycle: u64,
    stalled: bool,
    started: bool,
    scratch: Vec<u8>,
}

impl FlockSim {
    /// A Flock on one serial line: the master bird's (address 1).
    pub fn new(cfg: SimConfig) -> FlockSim {
        let flock = Rc::new(RefCell::new(SimFlock::new(cfg, false)));
        FlockSim::line_of(flock, 0, 1)
    }

    /// A Flock with a line per receiver: `[master line, receiver 0's line, …]`. The
    /// receivers' lines stream their own records (no address byte).
    pub fn parallel(cfg: SimConfig) -> Vec<FlockSim> {
        let first = cfg.transmitter.first_receiver_address();
        let receivers = cfg.receivers;
        let flock = Rc::new(RefCell::new(SimFlock::new(cfg, true)));
        let mut lines = vec![FlockSim::line_of(flock.clone(), 0, 1)];
        for i in 0..receivers {
            lines.push(FlockSim::line_of(
                flock.clone(),
                usize::from(i) + 1,
                first + i,
            ));
        }
        lines
    }

    fn line_of(flock: Rc<RefCell<SimFlock>>, line: usize, own_address: u8) -> FlockSim {
        FlockSim {
            flock,
            line,
            own_address,
            pending: [0; 4],
            pending_len: 0,
            target: None,
            out: VecDeque::new(),
            tail: None,
            streaming: false,
            stream_generation: 0,
            next_cycle: 0,
            stalled: false,
            started: false,
            scratch: Vec::new(),
        }
    }

    /// The shared Flock.
    pub fn flock(&self) -> Ref<'_, SimFlock> {
        self.flock.borrow()
    }

    /// The shared Flock, to change (power, log).
    pub fn flock_mut(&self) -> RefMut<'_, SimFlock> {
        self.flock.borrow_mut()
    }

    /// This line's bird address (1 for the master's line).
    pub fn address(&self) -> u8 {
        self.own_address
    }

    /// True while this line streams.
    pub fn is_streaming(&self) -> bool {
        self.streaming && self.stream_generation == self.flock.borrow().generation
    }

    /// True when nothing is queued on this line and its last byte had left by `t`.
    pub fn is_quiet_at(&self, t: Instant) -> bool {
        self.out.is_empty() && self.tail.map_or(true, |tail| tail <= t)
    }

    /// This line's stream dies silently (a hung device); `'@'` or a reset revives it.
    pub fn stall(&mut self) {
        self.stalled = true;
    }

    fn touch(&mut self, now: Instant) {
        let mut f = self.flock.borrow_mut();
        f.touch(now);
        if !self.started {
            self.started = true;
            // A stream left running: the master's line of a one-line Flock, or each
            // receiver's own line.
            if f.cfg.streaming_at_start && (f.parallel != (self.line == 0)) {
                self.streaming = true;
                self.stream_generation = f.generation;
                self.next_cycle = f.cycle_at_or_after(now);
            }
        }
        if self.stream_generation != f.generation {
            self.streaming = false;
        }
        if !f.powered {
            self.out.clear();
            self.tail = None;
        }
    }

    /// Queues `bytes` to leave at `at` (or when the line is free), paced at the baud rate.
    fn send(&mut self, at: Instant, bytes: &[u8], cfg: &SimConfig) -> Instant {
        let start = self.tail.map_or(at, |t| t.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + cfg.byte_offset(i), b));
        }
        let end = start + cfg.byte_offset(bytes.len());
        self.tail = Some(end);
        start
    }

    /// The addresses whose records this line carries, and whether with the address byte.
    fn record_addresses(&self, f: &SimFlock) -> (Vec<u8>, bool) {
        if self.line == 0 && f.group_mode {
            (f.receiver_addresses().collect(), true)
        } else if f.is_receiver(self.own_address) {
            (vec![self.own_address], false)
        } else {
            (Vec::new(), false)
        }
    }

    /// Queues the records of measurement cycle `cycle` starting at `at`.
    fn send_records(&mut self, cycle: u64, at: Instant) {
        let flock = self.flock.clone();
        let mut f = flock.borrow_mut();
        let (addresses, with_address) = self.record_addresses(&f);
        let cfg = f.cfg.clone();
        for address in addresses {
            if !f.measuring(address) {
                continue;
            }
            let raw = pose(address, cycle);
            let pos_quat = f.pos_quat_format(address);
            let mut bytes = std::mem::take(&mut self.scratch);
            bytes.clear();
            if pos_quat {
                raw.encode_pos_quat(&mut bytes);
            } else {
                raw.encode_pos_angles(&mut bytes);
            }
            if with_address {
                bytes.push(address);
            }
            // Records of one cycle follow each other as fast as the line allows.
            let first = self.send(at, &bytes, &cfg);
            self.scratch = bytes;
            if cfg.keep_log {
                f.log.push(SentRecord {
                    line: self.line,
                    address,
                    cycle,
                    pose: raw,
                    pos_quat,
                    first_byte_at: first,
                });
            }
        }
    }

    /// Queues stream records for every cycle that started by `now`.
    fn stream_until(&mut self, now: Instant) {
        loop {
            if !self.is_streaming() || self.stalled {
                return;
            }
            let start = {
                let f = self.flock.borrow();
                if !f.running || !f.powered {
                    return;
                }
                f.start_time(self.next_cycle)
            };
            let Some(start) = start.filter(|&s| s <= now) else {
                return;
            };
            // A line too slow for the rate skips the measurements it has no time for.
            let busy = self.tail.is_some_and(|t| t > start);
            if !busy {
                self.send_records(self.next_cycle, start);
            }
            self.next_cycle += 1;
        }
    }

    fn command(&mut self, now: Instant) {
        let cmd = self.pending;
        let target = self.target.take().unwrap_or(self.own_address);
        let reply_at = now + self.flock.borrow().cfg.reply_delay;
        let cfg = self.flock.borrow().cfg.clone();
        match cmd[0] {
            reset::POINT => {
                // Stops a stream; either way the latest measurement goes out once (nothing
                // when the birds are not measuring).
                self.streaming = false;
                let cycle = self.flock.borrow().cycle_before(now);
                self.send_records(cycle, reply_at);
            }
            reset::STREAM => {
                let f = self.flock.borrow();
                self.streaming = true;
                self.stalled = false;
                self.stream_generation = f.generation;
                self.next_cycle = f.cycle_at_or_after(reply_at);
            }
            reset::SLEEP => {
                let mut f = self.flock.borrow_mut();
                f.running = false;
                f.generation += 1;
            }
            RUN => {
                let mut f = self.flock.borrow_mut();
                if f.configured_units > 0 && !f.running {
                    f.running = true;
                    f.epoch = Some(now);
                }
            }
            reset::POSITION_QUATERNION => {
                self.flock.borrow_mut().pos_quat[usize::from(target).min(MAX_ADDRESS)] = true;
            }
            reset::HEMISPHERE => {
                self.flock.borrow_mut().hemisphere[usize::from(target).min(MAX_ADDRESS)] =
                    Some([cmd[1], cmd[2]]);
            }
            reset::EXAMINE_VALUE => {
                let f = self.flock.borrow();
                let mut answer = [0u8; STATUS_LEN];
                let n = match cmd[1] {
                    BIRD_STATUS => {
                        answer[..2]
                            .copy_from_slice(&[0x00, 0x80 | if f.running { 0x40 } else { 0 }]);
                        2
                    }
                    CRYSTAL_SPEED => {
                        answer[..2].copy_from_slice(&[cfg.crystal_mhz, 0]);
                        2
                    }
                    RATE_COUNT => {
                        answer[..2].copy_from_slice(&cfg.rate_count.to_le_bytes());
                        2
                    }
                    ERROR_CODE => {
                        answer[0] = f.error[0];
                        1
                    }
                    EXPANDED_ERROR => {
                        answer[..2].copy_from_slice(&f.error);
                        2
                    }
                    SYSTEM_STATUS => {
                        answer = f.system_status();
                        STATUS_LEN
                    }
                    _ => 0,
                };
                drop(f);
                if matches!(cmd[1], ERROR_CODE | EXPANDED_ERROR) {
                    self.flock.borrow_mut().error = [0; 2];
                }
                if n == 0 {
                    self.flock.borrow_mut().error = [INVALID_COMMAND, 0];
                } else {
                    self.send(reply_at, &answer[..n], &cfg);
                }
            }
            reset::CHANGE_VALUE => {
                let mut f = self.flock.borrow_mut();
                match cmd[1] {
                    GROUP_MODE => f.group_mode = cmd[2] != 0,
                    AUTOCONFIG => {
                        f.autoconfigs += 1;
                        f.running = false;
                        f.configured_units = 0;
                        f.generation += 1;
                        if cmd[2] == 0 || cmd[2] > cfg.units() {
                            f.error = [CONFIGURATION_ERROR, 0];
                        } else {
                            f.autoconfig = Some((now + cfg.autoconfig_time, cmd[2]));
                        }
                    }
                    _ => f.error = [INVALID_COMMAND, 0],
                }
            }
            _ => self.flock.borrow_mut().error = [INVALID_COMMAND, 0],
        }
    }

    /// Bytes a command starting with `first` has (0: unknown).
    fn command_len(first: u8, second: Option<u8>) -> usize {
        match first {
            reset::POINT | reset::STREAM | reset::SLEEP | RUN | reset::POSITION_QUATERNION => 1,
            reset::EXAMINE_VALUE => 2,
            reset::HEMISPHERE => 3,
            reset::CHANGE_VALUE => match second {
                None => 2,
                Some(GROUP_MODE | AUTOCONFIG) => 3,
                Some(_) => 2,
            },
            _ => 0,
        }
    }
}

impl DeviceModel for FlockSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        let t = now.mono;
        self.touch(t);
        for &b in bytes {
            // Commands reach the bus only while the master listens.
            if !self.flock.borrow().listening() {
                self.pending_len = 0;
                self.target = None;
                continue;
            }
            if self.pending_len == 0 && b >= reset::TO_ADDRESS {
                self.target = Some(b - reset::TO_ADDRESS);
                continue;
            }
            self.pending[self.pending_len] = b;
            self.pending_len += 1;
            let second = (self.pending_len > 1).then(|| self.pending[1]);
            let need = FlockSim::command_len(self.pending[0], second);
            if need == 0 {
                self.flock.borrow_mut().error = [INVALID_COMMAND, 0];
                self.pending_len = 0;
                self.target = None;
                continue;
            }
            if self.pending_len >= need {
                self.command(t);
                self.pending_len = 0;
            }
        }
    }

    fn set_rts(&mut self, on: bool, now: Now) {
        if self.line != 0 || !self.flock.borrow().cfg.rts_wired {
            return;
        }
        self.touch(now.mono);
        let mut f = self.flock.borrow_mut();
        if on && !f.rts_up {
            f.rts_up = true;
            f.resets += 1;
            f.power_on_state();
            drop(f);
            self.out.clear();
            self.tail = None;
            self.pending_len = 0;
            self.target = None;
        } else if !on && f.rts_up {
            f.rts_up = false;
            f.booting_until = Some(now.mono + f.cfg.boot_time);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let t = now.mono;
        self.touch(t);
        self.stream_until(t);
        while let Some(&(at, b)) = self.out.front() {
            if at > t {
                break;
            }
            out.push(b);
            self.out.pop_front();
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let queued = self.out.front().map(|&(t, _)| t);
        let f = self.flock.borrow();
        let stream = (self.streaming
            && !self.stalled
            && self.stream_generation == f.generation
            && f.running
            && f.powered)
            .then(|| f.start_time(self.next_cycle))
            .flatten();
        // An auto-configuration or a boot ending changes nothing on the line by itself.
        [queued, stream].into_iter().flatten().min()
    }
}
