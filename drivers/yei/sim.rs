//! A simulated YEI 3-Space Sensor: a wired unit on its own port, or a wireless dongle with
//! units paired at logical ids, for tests and for a simulator on a pseudo-terminal.
//!
//! It parses what the host writes as the unit does: binary commands (`F7`, or `F8` and a
//! logical id, each checked against its checksum; a bad one is counted and ignored) and ASCII
//! commands (`:`…`\n`, `>id,`…`\n`, a NUL after either). It answers the LED reads, keeps
//! the timing and slots, counts calibrations and tares, and streams once told to: record `k`
//! of unit `u` holds [`record_of(u, k)`](record_of). A wired unit sends records back to back
//! at its interval; a wireless unit's records wait in the dongle (manual flush mode) until
//! the host releases them one at a time (`F7 B4 id`), each as `00 id 59` and the record. Every
//! wireless command is answered by a header (`00 id len` and data, or `01 id` for an id
//! nothing is paired at); an ASCII one by `0,id,0\r\n`. A wired unit's bytes go out paced
//! at the baud rate; the dongle's answers whole (it is a USB device). With [`SimConfig::keep_log`] it logs what a client must receive ([`YeiSim::sent`]),
//! computed from `record_of` with f32 rounding, with the time each record's first byte left.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::command::{
    checksum, CALIBRATE_GYROS, FLUSH_ONE, GET_LED_COLOR, GET_LED_MODE, SET_AXES, SET_LED_COLOR,
    SET_LED_MODE, SET_SLOTS, SET_TIMING, SET_WIRELESS_MODE, START_STREAMING, START_WIRED,
    START_WIRELESS, STOP_STREAMING, TARE,
};
use super::record::{encode, Record, CHANNELS, GRAVITY, RECORD_LEN, SLOTS};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim yei PATH`: a wired unit.
pub static SIMULATOR: Simulator = Simulator {
    name: "yei",
    about: "YEI 3-Space Sensor (wired): 50 records/s of known orientations, sensors, buttons",
    baud: 115200,
    line: "vrpn_YEI_3Space_Sensor YEI0 {PATH} {BAUD} 0 0 50.0 0 0 1 0",
    make: |baud| Box::new(YeiSim::new(SimConfig::new(baud))),
};

/// `vrpn_device_sim yei_wireless PATH`: a dongle with units at logical ids 0 and 1.
pub static SIMULATOR_WIRELESS: Simulator = Simulator {
    name: "yei_wireless",
    about: "YEI 3-Space wireless dongle: units at logical ids 0 and 1, 50 records/s each",
    baud: 115200,
    line: "vrpn_YEI_3Space_Sensor_Wireless YEI0 0 {PATH} {BAUD} 0 0 50.0 0 0 1 1 /\n\
           vrpn_YEI_3Space_Sensor_Wireless YEI1 1 0 0 50.0 0 1 0 1",
    make: |baud| Box::new(YeiSim::new(SimConfig::wireless(baud, &[0, 1]))),
};

/// Record `k` of unit `u`: orientations turning slowly, values that change every record,
/// a button byte counting up every four records.
pub fn record_of(u: usize, k: u64) -> Record {
    let a = (k as f64) * 0.01 + u as f64;
    let (s, c) = (a / 2.0).sin_cos();
    let (s2, c2) = (a / 3.0).sin_cos();
    let mut channels = [0.0; CHANNELS];
    for (i, ch) in channels.iter_mut().enumerate() {
        *ch = ((a + i as f64) * 1.3).sin() * (1.0 + i as f64 % 3.0);
    }
    channels[9] = 20.0 + (k % 100) as f64 * 0.125 + u as f64;
    channels[10] = (k % 11) as f64 / 10.0;
    Record {
        untared: [0.0, 0.0, s, c],
        tared: [s2, 0.0, 0.0, c2],
        accel_g: [a.sin() * 0.5, a.cos() * 0.25, 0.125],
        channels,
        buttons: ((k / 4) % 256) as u8,
    }
}

/// How the simulated unit behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// `None`: a wired unit. `Some(ids)`: a dongle with units paired at these logical ids.
    pub wireless: Option<Vec<u8>>,
    /// Log what a client must receive.
    pub keep_log: bool,
    /// Time the unit takes to act on a command.
    pub answer_delay: Duration,
    /// Answers nothing to the LED reads (a unit that is not there).
    pub deaf: bool,
    /// Records the dongle keeps per unit before dropping the oldest.
    pub dongle_buffer: usize,
}

impl SimConfig {
    /// A wired unit at `baud`, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            wireless: None,
            keep_log: false,
            answer_delay: Duration::from_micros(300),
            deaf: false,
            dongle_buffer: 16,
        }
    }

    /// A dongle at `baud` with units at `ids`, no log.
    pub fn wireless(baud: u32, ids: &[u8]) -> SimConfig {
        SimConfig {
            wireless: Some(ids.to_vec()),
            ..SimConfig::new(baud)
        }
    }
}

/// What a client must receive, per record, with the time its first byte left.
#[derive(Clone, Debug, PartialEq)]
pub struct Sent {
    /// The unit (index in the configuration's order).
    pub unit: usize,
    /// The record number.
    pub k: u64,
    /// Untared and tared orientations (x, y, z, w), f32-rounded.
    pub quats: [[f64; 4]; 2],
    /// Acceleration in m/s².
    pub acc: [f64; 3],
    /// The Analog channels.
    pub channels: [f64; CHANNELS],
    /// Buttons pressed.
    pub buttons: u8,
    /// When its first byte left.
    pub first_byte: Instant,
}

fn r32(v: f64) -> f64 {
    f64::from(v as f32)
}

/// What a client must receive for `record_of(unit, k)`.
pub fn expected(unit: usize, k: u64, first_byte: Instant) -> Sent {
    let r = record_of(unit, k);
    Sent {
        unit,
        k,
        quats: [r.untared.map(r32), r.tared.map(r32)],
        acc: r.accel_g.map(|g| r32(g) * GRAVITY),
        channels: r.channels.map(r32),
        buttons: r.buttons,
        first_byte,
    }
}

/// One unit's state.
#[derive(Clone, Debug, Default)]
pub struct UnitState {
    /// Logical id (wireless).
    pub id: u8,
    /// Streaming.
    pub streaming: bool,
    /// Streaming interval asked for, µs.
    pub interval_us: u32,
    /// Slots asked for.
    pub slots: [u8; 8],
    /// LED mode.
    pub led_mode: u8,
    /// LED colour.
    pub led_color: [f32; 3],
    /// Axis choice.
    pub axes: Option<u8>,
    /// Gyro calibrations heard.
    pub calibrations: u32,
    /// Tares heard.
    pub tares: u32,
    /// ASCII commands heard, in order.
    pub ascii: Vec<String>,
    /// Start-streaming commands heard.
    pub starts: u32,
    next: Option<Instant>,
    count: u64,
    held: VecDeque<u64>,
}

enum Parse {
    Idle,
    Binary { wireless: bool, buf: Vec<u8> },
    Ascii { buf: Vec<u8> },
}

/// The simulated unit or dongle. See the module documentation.
pub struct YeiSim {
    cfg: SimConfig,
    /// The units (one for a wired unit).
    pub units: Vec<UnitState>,
    /// Commands with a wrong checksum or an unknown command byte.
    pub bad_commands: u32,
    /// Manual flush mode set on the dongle.
    pub manual_flush: bool,
    parse: Parse,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    actions: VecDeque<(Instant, Action)>,
    sent: Vec<Sent>,
}

#[derive(Clone, Debug)]
enum Action {
    Binary(Option<u8>, Vec<u8>),
    Ascii(Option<u8>, String),
}

/// Arguments each binary command takes.
fn arg_len(cmd: u8) -> Option<usize> {
    Some(match cmd {
        STOP_STREAMING | START_STREAMING | GET_LED_MODE | GET_LED_COLOR | CALIBRATE_GYROS
        | TARE => 0,
        SET_LED_MODE | SET_AXES | SET_WIRELESS_MODE | FLUSH_ONE => 1,
        SET_LED_COLOR | SET_TIMING => 12,
        SET_SLOTS => 8,
        _ => return None,
    })
}

impl YeiSim {
    /// A unit (or dongle) behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> YeiSim {
        let ids = cfg.wireless.clone().unwrap_or_else(|| vec![0]);
        YeiSim {
            units: ids
                .iter()
                .map(|&id| UnitState {
                    id,
                    led_mode: 1,
                    ..UnitState::default()
                })
                .collect(),
            cfg,
            bad_commands: 0,
            manual_flush: false,
            parse: Parse::Idle,
            out: VecDeque::new(),
            line_free: None,
            actions: VecDeque::new(),
            sent: Vec::new(),
        }
    }

    /// What a client must have received.
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    /// Answers nothing to the LED reads while true.
    pub fn set_deaf(&mut self, deaf: bool) {
        self.cfg.deaf = deaf;
    }

    fn wireless(&self) -> bool {
        self.cfg.wireless.is_some()
    }

    /// The time a byte takes on the line: a wired unit's UART at its baud rate; none for the
    /// dongle, a USB device whose answers come whole in its packets.
    fn byte_time(&self) -> Duration {
        if self.wireless() {
            return Duration::ZERO;
        }
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let mut t = start;
        for &b in bytes {
            self.out.push_back((t, b));
            t += self.byte_time();
        }
        self.line_free = Some(t);
        start
    }

    fn unit_at(&self, id: Option<u8>) -> Option<usize> {
        match id {
            None => Some(0),
            Some(id) => self.units.iter().position(|u| u.id == id),
        }
    }

    fn take_byte(&mut self, b: u8, now: Instant) {
        let at = now + self.cfg.answer_delay;
        match &mut self.parse {
            Parse::Idle => {
                self.parse = match b {
                    START_WIRED => Parse::Binary {
                        wireless: false,
                        buf: Vec::new(),
                    },
                    START_WIRELESS if self.wireless() => Parse::Binary {
                        wireless: true,
                        buf: Vec::new(),
                    },
                    b':' | b'>' => Parse::Ascii { buf: vec![b] },
                    _ => Parse::Idle, // NULs after ASCII commands, noise
                };
            }
            Parse::Ascii { buf } => {
                if b != b'\n' {
                    buf.push(b);
                    return;
                }
                let text = String::from_utf8_lossy(buf).into_owned();
                self.parse = Parse::Idle;
                let action = match text.strip_prefix('>') {
                    Some(rest) => match rest.split_once(',') {
                        Some((id, cmd)) if self.wireless() => match id.parse::<u8>() {
                            Ok(id) => Action::Ascii(Some(id), cmd.to_owned()),
                            Err(_) => return self.bad(),
                        },
                        _ => return self.bad(),
                    },
                    None if !self.wireless() => Action::Ascii(None, text[1..].to_owned()),
                    None => return self.bad(),
                };
                self.actions.push_back((at, action));
            }
            Parse::Binary { wireless, buf } => {
                buf.push(b);
                let head = usize::from(*wireless);
                if buf.len() <= head {
                    return;
                }
                let Some(n) = arg_len(buf[head]) else {
                    self.parse = Parse::Idle;
                    return self.bad();
                };
                if buf.len() < head + 1 + n + 1 {
                    return;
                }
                let (body, sum) = buf.split_at(buf.len() - 1);
                let ok = checksum(body) == sum[0];
                let id = wireless.then(|| body[0]);
                let cmd = body[head..].to_vec();
                self.parse = Parse::Idle;
                if !ok {
                    return self.bad();
                }
                self.actions.push_back((at, Action::Binary(id, cmd)));
            }
        }
    }

    fn bad(&mut self) {
        self.bad_commands += 1;
    }

    fn act(&mut self, action: Action, at: Instant) {
        match action {
            Action::Ascii(id, cmd) => {
                let Some(u) = self.unit_at(id) else {
                    return;
                };
                self.units[u].ascii.push(cmd);
                if let Some(id) = id {
                    self.queue(format!("0,{id},0\r\n").as_bytes(), at);
                }
            }
            Action::Binary(None, cmd) if self.wireless() => self.dongle(&cmd, at),
            Action::Binary(id, cmd) => {
                let Some(u) = self.unit_at(id) else {
                    self.queue(&[1, id.unwrap_or(0)], at);
                    return;
                };
                let data = self.unit_command(u, &cmd, at);
                if let Some(id) = id {
                    let mut reply = vec![0, id, data.len() as u8];
                    reply.extend_from_slice(&data);
                    self.queue(&reply, at);
                } else if !data.is_empty() {
                    self.queue(&data, at);
                }
            }
        }
    }

    fn dongle(&mut self, cmd: &[u8], at: Instant) {
        match cmd[0] {
            SET_WIRELESS_MODE => self.manual_flush = cmd[1] == 0,
            FLUSH_ONE => {
                let Some(u) = self.unit_at(Some(cmd[1])) else {
                    return;
                };
                if let Some(k) = self.units[u].held.pop_front() {
                    let mut reply = vec![0, cmd[1], RECORD_LEN as u8];
                    reply.extend_from_slice(&encode(&record_of(u, k)));
                    let t = self.queue(&reply, at);
                    self.log(u, k, t);
                }
            }
            _ => self.bad(),
        }
    }

    fn unit_command(&mut self, u: usize, cmd: &[u8], at: Instant) -> Vec<u8> {
        let deaf = self.cfg.deaf;
        let unit = &mut self.units[u];
        let f = |i: usize| f32::from_be_bytes([cmd[i], cmd[i + 1], cmd[i + 2], cmd[i + 3]]);
        match cmd[0] {
            STOP_STREAMING => unit.streaming = false,
            START_STREAMING => {
                unit.streaming = true;
                unit.starts += 1;
                unit.next = Some(at + Duration::from_millis(1));
            }
            GET_LED_MODE if !deaf => return vec![unit.led_mode],
            GET_LED_COLOR if !deaf => {
                return unit
                    .led_color
                    .iter()
                    .flat_map(|v| v.to_be_bytes())
                    .collect()
            }
            GET_LED_MODE | GET_LED_COLOR => {}
            SET_LED_MODE => unit.led_mode = cmd[1],
            SET_LED_COLOR => unit.led_color = [f(1), f(5), f(9)],
            CALIBRATE_GYROS => unit.calibrations += 1,
            TARE => unit.tares += 1,
            SET_AXES => unit.axes = Some(cmd[1]),
            SET_TIMING => unit.interval_us = u32::from_be_bytes([cmd[1], cmd[2], cmd[3], cmd[4]]),
            SET_SLOTS => unit.slots.copy_from_slice(&cmd[1..9]),
            _ => {}
        }
        Vec::new()
    }

    fn log(&mut self, u: usize, k: u64, first_byte: Instant) {
        if self.cfg.keep_log {
            self.sent.push(expected(u, k, first_byte));
        }
    }

    fn stream(&mut self, now: Instant) {
        let record_time = self.byte_time() * RECORD_LEN as u32;
        for u in 0..self.units.len() {
            loop {
                let unit = &self.units[u];
                let Some(next) = unit.next.filter(|&t| unit.streaming && t <= now) else {
                    break;
                };
                // As fast as it can: a record's time on the line, at least 1 ms.
                let interval = Duration::from_micros(u64::from(unit.interval_us))
                    .max(record_time)
                    .max(Duration::from_millis(1));
                let k = unit.count;
                self.units[u].count += 1;
                self.units[u].next = Some(next + interval);
                if self.units[u].slots != SLOTS {
                    continue; // not asked for what the driver reads: nothing useful to send
                }
                if self.wireless() {
                    let held = &mut self.units[u].held;
                    held.push_back(k);
                    if held.len() > self.cfg.dongle_buffer {
                        held.pop_front();
                    }
                } else {
                    let t = self.queue(&encode(&record_of(u, k)), next);
                    self.log(u, k, t);
                }
            }
        }
    }
}

impl DeviceModel for YeiSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            self.take_byte(b, now.mono);
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while let Some((t, _)) = self.actions.front() {
            if *t > now.mono {
                break;
            }
            let (t, a) = self.actions.pop_front().unwrap();
            self.act(a, t);
        }
        self.stream(now.mono);
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let streams = self
            .units
            .iter()
            .filter(|u| u.streaming)
            .filter_map(|u| u.next);
        [
            self.out.front().map(|&(t, _)| t),
            self.actions.front().map(|&(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .chain(streams)
        .min()
    }
}
