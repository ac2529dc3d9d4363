//! The `DEVICE_SIM` mode of the `first_byte` bench: one of this crate's device simulators on a
//! pseudo-terminal, alone, so that any server can run the driver and any client (another
//! implementation's included) can read it, by hand.
//!
//! With `DEVICE_SIM_EXPECT=FILE`, the simulator also writes, when it stops, what a client
//! must have received for everything it streamed: one line per report, computed from the
//! simulator's own log and the documented scalings (never by asking the driver):
//!
//! ```text
//! analog V0 V1 …        an Analog report: every channel
//! button N STATE        a Button change (1 pressed, 0 released)
//! dial N CHANGE         a Dial update: revolutions turned
//! pose S X Y Z QX QY QZ QW   a Tracker pose of sensor S
//! ```
//!
//! Values have six decimals. A client that joined late sees a contiguous run of these lines
//! (per kind); over UDP, low-latency reports may be missing.
//!
//! With `DEVICE_SIM_MUTE=S` (not for `fastrak` and `flock`), the device neither answers nor
//! streams for its first S seconds: the driver's reset fails and is retried, and a client that
//! connected early hears the server's texts about it.
//!
//! With `DEVICE_SIM_REST=S` (`magellan` only), the puck rests for the first S seconds, so
//! that the device sends nothing but its answers during a reset; the simulator's puck
//! otherwise moves all the time, which C++'s Magellan driver (not this crate's) cannot reset
//! through.
//!
//! Entries to serve each simulator with (`PATH` is `FIRST_BYTE_TTY`):
//!
//! | `DEVICE_SIM` | vrpn.cfg line |
//! |---|---|
//! | `fastrak` | `vrpn_Tracker_Fastrak Tracker0 PATH 115200` |
//! | `flock` | `vrpn_Tracker_Flock Tracker0 2 PATH 115200 0` |
//! | `magellan` | `vrpn_Magellan Magellan0 PATH 9600` |
//! | `cerealbox` | `vrpn_CerealBox Cereal0 PATH 19200 24 8 8` |
//! | `dyna` | `vrpn_Tracker_Dyna Dyna0 1 PATH 19200` |
//! | `joylin` | `vrpn_Joylin Joy0 PATH` |
//! | `liberty` | `vrpn_Tracker_Liberty Tracker0 PATH 115200` (stations 1 and 2) |
//! | `isotrak` | `vrpn_Tracker_Isotrak Tracker0 PATH 19200` (stations 1 and 2) |
//! | `3space` | `vrpn_Tracker_3Space Tracker0 PATH 19200` (stations 1 and 2) |
//! | `polaris` | `vrpn_Tracker_NDI_Polaris Tracker0 PATH 2` and two lines naming `.rom` files (any contents, 1-1024 bytes) |
//! | `crossbow` | `vrpn_Tracker_Crossbow Tracker0 PATH 38400 2.0 100` |
//! | `gps` | `vrpn_Tracker_GPS Tracker0 PATH 4800` |

use std::fmt::Write as _;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use vrpn::drivers::cerealbox::record::revolutions;
use vrpn::drivers::cerealbox::sim::{self as cereal_sim, CerealSim};
use vrpn::drivers::crossbow::sim::{self as crossbow_sim, CrossbowSim};
use vrpn::drivers::dyna::sim::{self as dyna_sim, DynaSim};
use vrpn::drivers::gps::sim::{self as gps_sim, GpsSim};
use vrpn::drivers::joylin::event::Kind;
use vrpn::drivers::joylin::sim::{self as joy_sim, JoystickSim};
use vrpn::drivers::liberty::sim::{self as liberty_sim, LibertySim};
use vrpn::drivers::magellan::record::{axis_value, RESET_NULL_RADIUS};
use vrpn::drivers::magellan::sim::{self as magellan_sim, MagellanSim, Sent};
use vrpn::drivers::polaris::sim::{self as polaris_sim, PolarisSim};
use vrpn::drivers::threespace::record::Model;
use vrpn::drivers::threespace::sim::{self as threespace_sim, ThreeSpaceSim};
use vrpn::sim::DeviceModel;
use vrpn::sim::PtyDevice;
use vrpn::Now;

use super::{fastrak_model, flock_model, SimThread};

/// A device that can be made silent.
trait Quiet: DeviceModel {
    fn quiet(&mut self, on: bool);
}

impl Quiet for MagellanSim {
    fn quiet(&mut self, on: bool) {
        self.set_silent(on);
    }
}

impl Quiet for CerealSim {
    fn quiet(&mut self, on: bool) {
        self.set_silent(on);
    }
}

impl Quiet for DynaSim {
    fn quiet(&mut self, on: bool) {
        self.mute = on;
    }
}

impl Quiet for JoystickSim {
    fn quiet(&mut self, on: bool) {
        self.mute = on;
    }
}

/// `model`, silent from the start (it speaks once [`unmute`] has seen its time pass).
fn muted<M: Quiet>(mut model: M) -> M {
    model.quiet(true);
    model
}

/// Lets the device speak from `until` on.
fn unmute<M: Quiet>(dev: &mut PtyDevice<M>, now: Now, until: Instant) {
    if now.mono >= until {
        dev.model.quiet(false);
    }
}

/// Axes and buttons of the simulated joystick.
const JOY_AXES: u8 = 6;
const JOY_BUTTONS: u8 = 10;

/// Runs simulator `kind` on a pseudo-terminal at `path` for `duration`, then writes the
/// expected reports to `expect` if given.
pub fn simulate(
    kind: &str,
    path: &Path,
    duration: Duration,
    expect: Option<&Path>,
    mute: Duration,
    rest: Duration,
) {
    let lines: Arc<Mutex<Vec<String>>> = Arc::default();
    let out = lines.clone();
    let emit = move |new: Vec<String>| out.lock().expect("expectation lines").extend(new);
    let until = Instant::now() + mute;
    let rest_until = Instant::now() + rest;
    let _sim = match kind {
        "fastrak" => SimThread::start(path, fastrak_model, |_, _| {}),
        "flock" => SimThread::start(path, flock_model, |_, _| {}),
        "magellan" => {
            let mut state = MagellanExpect::default();
            SimThread::start(
                path,
                || muted(MagellanSim::new(magellan_sim::SimConfig::default())),
                move |dev, now| {
                    unmute(dev, now, until);
                    dev.model.set_moving(now.mono >= rest_until, now);
                    emit(state.feed(dev))
                },
            )
        }
        "cerealbox" => {
            let mut state = CerealExpect::default();
            SimThread::start(
                path,
                || muted(CerealSim::new(cereal_sim::SimConfig::default())),
                move |dev, now| {
                    unmute(dev, now, until);
                    emit(state.feed(dev))
                },
            )
        }
        "dyna" => {
            let mut seen = 0;
            let model = || {
                let mut cfg = dyna_sim::SimConfig::new(19_200);
                cfg.keep_log = true;
                muted(DynaSim::new(cfg))
            };
            SimThread::start(path, model, move |dev, now| {
                unmute(dev, now, until);
                emit(dyna_expect(dev, &mut seen));
            })
        }
        "joylin" => {
            let mut state = JoyExpect::default();
            let model = || {
                let mut cfg = joy_sim::SimConfig::new(JOY_AXES, JOY_BUTTONS);
                cfg.keep_log = true;
                muted(JoystickSim::new(cfg))
            };
            SimThread::start(path, model, move |dev, now| {
                unmute(dev, now, until);
                emit(state.feed(dev))
            })
        }
        "liberty" => {
            let mut seen = 0;
            let model = || {
                let mut cfg = liberty_sim::SimConfig::new(liberty_sim::Kind::Liberty, 115_200);
                cfg.keep_log = true;
                cfg.stations = vec![1, 2];
                LibertySim::new(cfg)
            };
            SimThread::start(path, model, move |dev, _| {
                let sent = dev.model.sent();
                emit(pose_lines(sent[seen..].iter().map(|r| r.sample.expected())));
                seen = sent.len();
            })
        }
        "isotrak" | "3space" => {
            let mut seen = 0;
            let which = if kind == "isotrak" {
                Model::Isotrak
            } else {
                Model::ThreeSpace
            };
            let model = move || {
                let mut cfg = threespace_sim::SimConfig::new(which, 19_200);
                cfg.keep_log = true;
                cfg.stations = vec![1, 2];
                ThreeSpaceSim::new(cfg)
            };
            SimThread::start(path, model, move |dev, _| {
                let sent = dev.model.sent();
                emit(pose_lines(sent[seen..].iter().map(|r| r.sample.expected())));
                seen = sent.len();
            })
        }
        "polaris" => {
            let mut seen = 0;
            let model = || {
                let mut cfg = polaris_sim::SimConfig::new();
                cfg.keep_log = true;
                PolarisSim::new(cfg)
            };
            SimThread::start(path, model, move |dev, _| {
                let sent = dev.model.sent();
                emit(pose_lines(sent[seen..].iter().map(|r| r.values)));
                seen = sent.len();
            })
        }
        "crossbow" => {
            let mut seen = 0;
            let model = || {
                let mut cfg = crossbow_sim::SimConfig::new(38_400);
                cfg.keep_log = true;
                CrossbowSim::new(cfg)
            };
            SimThread::start(path, model, move |dev, _| {
                let sent = dev.model.sent();
                emit(pose_lines(
                    sent[seen..].iter().map(|r| (0, [0.0; 3], r.values.0)),
                ));
                seen = sent.len();
            })
        }
        "gps" => {
            let mut seen = 0;
            let model = || {
                let mut cfg = gps_sim::SimConfig::new(4_800);
                cfg.keep_log = true;
                GpsSim::new(cfg)
            };
            SimThread::start(path, model, move |dev, _| {
                let sent = dev.model.sent();
                emit(pose_lines(
                    sent[seen..]
                        .iter()
                        .map(|f| (0, f.values, [0.0, 0.0, 0.0, 1.0])),
                ));
                seen = sent.len();
            })
        }
        _ => {
            panic!(
                "DEVICE_SIM: fastrak, flock, magellan, cerealbox, dyna, joylin, liberty, \
                 isotrak, 3space, polaris, crossbow or gps, not {kind:?}"
            )
        }
    };
    println!("{kind} simulator on {} for {duration:?}", path.display());
    std::thread::sleep(duration);
    drop(_sim);
    if let Some(file) = expect {
        let lines = lines.lock().expect("expectation lines");
        let mut text = String::new();
        for l in lines.iter() {
            text.push_str(l);
            text.push('\n');
        }
        std::fs::write(file, text).expect("DEVICE_SIM_EXPECT: a writable file");
        println!("{} expected reports in {}", lines.len(), file.display());
    }
}

/// One `pose S X Y Z QX QY QZ QW` line per pose.
fn pose_lines(poses: impl Iterator<Item = (usize, [f64; 3], [f64; 4])>) -> Vec<String> {
    poses
        .map(|(s, p, q)| {
            format!(
                "pose {s} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6}",
                p[0], p[1], p[2], q[0], q[1], q[2], q[3]
            )
        })
        .collect()
}

/// One line `analog V0 V1 …`.
fn analog_line(values: &[f64]) -> String {
    let mut s = String::from("analog");
    for v in values {
        let _ = write!(s, " {v:.6}");
    }
    s
}

/// The changes between button masks `old` and `new` (bits `0..n`), lowest first.
fn button_lines(old: u32, new: u32, n: usize, out: &mut Vec<String>) {
    for i in 0..n {
        if (old ^ new) & (1 << i) != 0 {
            out.push(format!("button {i} {}", u32::from(new & (1 << i) != 0)));
        }
    }
}

/// The Magellan: all six channels when any changed (raw / 7500, zero within the null radius
/// a reset sets), then the changed buttons.
#[derive(Default)]
struct MagellanExpect {
    next_seq: u64,
    chans: [f64; 6],
    mask: u16,
}

impl MagellanExpect {
    fn feed(&mut self, dev: &PtyDevice<MagellanSim>) -> Vec<String> {
        let mut out = Vec::new();
        let from = self.next_seq;
        for r in dev.model.log.iter().filter(|r| r.seq >= from) {
            self.next_seq = r.seq + 1;
            match r.sent {
                Sent::Axes(raw) => {
                    let v = raw.map(|x| axis_value(x, RESET_NULL_RADIUS));
                    if v != self.chans {
                        out.push(analog_line(&v));
                        self.chans = v;
                    }
                }
                Sent::Keys(k) => {
                    button_lines(u32::from(self.mask), u32::from(k), 9, &mut out);
                    self.mask = k;
                }
            }
        }
        out
    }
}

/// The CerealBox, per record: the analogs (twelve bits onto -1…1) if any changed, the
/// changed buttons, then one update per encoder that turned (24-bit signed ticks, 4096 a
/// revolution).
#[derive(Default)]
struct CerealExpect {
    next_seq: u64,
    chans: Vec<f64>,
    mask: u32,
}

impl CerealExpect {
    fn feed(&mut self, dev: &PtyDevice<CerealSim>) -> Vec<String> {
        let mut out = Vec::new();
        let from = self.next_seq;
        for r in dev.model.log.iter().filter(|r| r.seq >= from) {
            self.next_seq = r.seq + 1;
            let l = r.layout;
            let v: Vec<f64> = (0..l.analogs)
                .map(|i| -1.0 + 2.0 * f64::from(cereal_sim::analog(r.seq, i)) / 4095.0)
                .collect();
            if v != self.chans {
                out.push(analog_line(&v));
                self.chans = v;
            }
            let m = cereal_sim::buttons(r.seq);
            button_lines(self.mask, m, l.buttons, &mut out);
            self.mask = m;
            for i in 0..l.encoders {
                let ticks = (cereal_sim::encoder(r.seq, i) << 8) >> 8;
                if ticks != 0 {
                    out.push(format!("dial {i} {:.6}", revolutions(ticks)));
                }
            }
        }
        out
    }
}

/// The DynaSight: one pose of sensor 0 per record, identity orientation.
fn dyna_expect(dev: &PtyDevice<DynaSim>, seen: &mut usize) -> Vec<String> {
    let sent = dev.model.sent();
    let out = sent[*seen..]
        .iter()
        .map(|r| {
            let [x, y, z] = r.sample.expected_position_m();
            format!("pose 0 {x:.6} {y:.6} {z:.6} 0.000000 0.000000 0.000000 1.000000")
        })
        .collect();
    *seen = sent.len();
    out
}

/// The joystick: every channel after each axis event (value / 32767), each button change.
#[derive(Default)]
struct JoyExpect {
    seen: usize,
    chans: Vec<f64>,
    pressed: Vec<i16>,
}

impl JoyExpect {
    fn feed(&mut self, dev: &PtyDevice<JoystickSim>) -> Vec<String> {
        self.chans.resize(usize::from(JOY_AXES), 0.0);
        self.pressed.resize(usize::from(JOY_BUTTONS), 0);
        let sent = dev.model.sent();
        let mut out = Vec::new();
        for e in &sent[self.seen..] {
            let (n, v) = (usize::from(e.event.number), e.event.value);
            match e.event.kind {
                Kind::Axis => {
                    self.chans[n] = f64::from(v) / 32767.0;
                    if !e.event.init {
                        out.push(analog_line(&self.chans));
                    }
                }
                Kind::Button => {
                    if self.pressed[n] != v && !e.event.init {
                        out.push(format!("button {n} {}", u8::from(v != 0)));
                    }
                    self.pressed[n] = v;
                }
            }
        }
        self.seen = sent.len();
        out
    }
}
