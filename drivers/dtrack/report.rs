//! From a parsed frame to what VRPN clients receive, as C++ VRPN computes it: which tracker
//! sensor each body, Flystick and marker becomes, the report time from the frame's time
//! stamp, positions in metres and orientation from the rotation matrix, and the Flystick's
//! buttons and joystick (with the simulated ramp of old Flysticks' hat).

use super::frame::{Header, Targets};
use crate::layered::quat_from_row_matrix;
use crate::time::TimeVal;

/// VRPN buttons per Flystick (C++ fixes 8).
pub const BUTTONS_PER_FLYSTICK: usize = 8;
/// VRPN analog channels per Flystick (C++ fixes 2).
pub const CHANNELS_PER_FLYSTICK: usize = 2;
/// Tracker sensors served (bodies, Flysticks and markers together); a target numbered
/// beyond is not reported.
pub const MAX_SENSORS: usize = 512;
/// Flysticks whose buttons and joystick fit VRPN's 256 buttons and 128 channels.
pub const MAX_FLYSTICK_CONTROLS: usize = 32;

/// Fixed numbers of bodies and Flysticks, with their VRPN ids (the optional config fields).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FixedNumbering {
    /// Bodies visible to VRPN.
    pub bodies: i32,
    /// Flysticks visible to VRPN.
    pub flysticks: i32,
    /// Sensor of body *i* (then of Flystick *j* at `bodies + j`).
    pub sensor: Vec<i32>,
    /// Button/analog block of Flystick *j*.
    pub flystick_block: Vec<i32>,
}

impl FixedNumbering {
    /// C++'s numbering from the counts and the optional renumbering list (one id per body,
    /// then one per Flystick): a Flystick's button block is its id less the number of
    /// bodies renumbered below it.
    pub fn new(bodies: i32, flysticks: i32, ids: Option<&[i32]>) -> FixedNumbering {
        let (nb, nf) = (bodies.max(0) as usize, flysticks.max(0) as usize);
        let (sensor, flystick_block) = match ids {
            Some(ids) => {
                let sensor: Vec<i32> = ids[..nb + nf].to_vec();
                let mut block: Vec<i32> = ids[nb..nb + nf].to_vec();
                for &body in &ids[..nb] {
                    for (j, b) in block.iter_mut().enumerate() {
                        if body < ids[j + nb] && *b > 0 {
                            *b -= 1;
                        }
                    }
                }
                (sensor, block)
            }
            None => ((0..(nb + nf) as i32).collect(), (0..nf as i32).collect()),
        };
        FixedNumbering {
            bodies,
            flysticks,
            sensor,
            flystick_block,
        }
    }
}

/// One tracker report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Sensor number.
    pub sensor: usize,
    /// Position in metres.
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
}

/// What one frame gives the clients; the buttons and channels persist between frames (as
/// C++'s arrays do) and are reported when they change.
#[derive(Clone, Debug)]
pub struct Output {
    /// The frame's report time.
    pub time: TimeVal,
    /// Tracker reports in C++'s order: bodies, Flysticks, markers.
    pub poses: Vec<Pose>,
    /// Buttons served (8 per Flystick).
    pub num_buttons: usize,
    /// Button states.
    pub buttons: [bool; MAX_FLYSTICK_CONTROLS * BUTTONS_PER_FLYSTICK],
    /// Channels served (2 per Flystick).
    pub num_channels: usize,
    /// Channel values.
    pub channels: [f64; MAX_FLYSTICK_CONTROLS * CHANNELS_PER_FLYSTICK],
    /// Targets numbered beyond what VRPN can serve in this frame (not reported).
    pub beyond: usize,
}

/// The frame-to-report state machine. See the module documentation.
#[derive(Clone, Debug)]
pub struct Reporter {
    fixed: Option<FixedNumbering>,
    markers: bool,
    joy_per_sec: f32,
    joy_simulate: [bool; MAX_FLYSTICK_CONTROLS * CHANNELS_PER_FLYSTICK],
    joy_last: [f32; MAX_FLYSTICK_CONTROLS * CHANNELS_PER_FLYSTICK],
    first: Option<TimeVal>,
    last: TimeVal,
    warned_no_bodycal: bool,
    out: Output,
}

/// C++'s report time: the DTRACK3 time (`ts2`) when the clocks agree within 0.1 s, else the
/// arrival less the latency it states; or the `ts` time of day placed in the day of arrival
/// closest to it; or the arrival.
pub fn report_time(h: &Header, arrived: TimeVal) -> TimeVal {
    let mut t = arrived;
    let (sec, usec, latency) = h.ts2;
    if sec > 0 {
        let dt = TimeVal {
            sec: sec as i64,
            usec: usec as i64,
        };
        let apart = (t.usec - dt.usec) as f64 / 1e6 + (t.sec - dt.sec) as f64;
        if apart.abs() > 0.1 {
            if t.usec < latency as i32 as i64 {
                t.usec += 1_000_000u32.wrapping_sub(latency) as i64;
                t.sec -= 1;
            } else {
                t.usec -= latency as i64;
            }
        } else {
            t = dt;
        }
    } else if h.timestamp >= 0.0 {
        let mut tts = h.timestamp as i64;
        let ttu = ((h.timestamp - tts as f64) * 1_000_000.0) as i64;
        tts += t.sec - t.sec % 86400;
        if tts >= t.sec + 43200 - 1800 {
            tts -= 86400;
        } else if tts <= t.sec - 43200 - 1800 {
            tts += 86400;
        }
        t = TimeVal {
            sec: tts,
            usec: ttu,
        };
    }
    t
}

/// C++ body pose: millimetres to metres, the column-wise matrix read as rows.
fn pose(sensor: usize, loc: &[f32; 3], rot: &[f32; 9]) -> Pose {
    let mut m = [[0.0f64; 4]; 4];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = rot[3 * r + c] as f64;
        }
    }
    m[3][3] = 1.0;
    Pose {
        sensor,
        pos: loc.map(|v| v as f64 / 1000.0),
        quat: quat_from_row_matrix(&m),
    }
}

fn sensor_index(id: i32) -> Option<usize> {
    usize::try_from(id).ok().filter(|&s| s < MAX_SENSORS)
}

impl Reporter {
    /// A reporter with C++'s options: fixed numbering, `3d` marker output, and the time the
    /// simulated hat of an old Flystick takes to reach ±1 (0: at once).
    pub fn new(fixed: Option<FixedNumbering>, markers: bool, time_to_reach_joy: f32) -> Self {
        Reporter {
            fixed,
            markers,
            joy_per_sec: if time_to_reach_joy > 1e-20 {
                1.0 / time_to_reach_joy
            } else {
                1e20
            },
            joy_simulate: [false; MAX_FLYSTICK_CONTROLS * CHANNELS_PER_FLYSTICK],
            joy_last: [0.0; MAX_FLYSTICK_CONTROLS * CHANNELS_PER_FLYSTICK],
            first: None,
            last: TimeVal::ZERO,
            warned_no_bodycal: false,
            out: Output {
                time: TimeVal::ZERO,
                poses: Vec::with_capacity(3 * super::frame::MAX_TARGETS),
                num_buttons: 0,
                buttons: [false; MAX_FLYSTICK_CONTROLS * BUTTONS_PER_FLYSTICK],
                num_channels: 0,
                channels: [0.0; MAX_FLYSTICK_CONTROLS * CHANNELS_PER_FLYSTICK],
                beyond: 0,
            },
        }
    }

    /// True the first time a frame came without `6dcal` and without fixed numbering (C++
    /// warns once: targets are then counted as they appear).
    pub fn take_no_bodycal_warning(&mut self, h: &Header) -> bool {
        if self.fixed.is_none() && !h.has_bodycal && !self.warned_no_bodycal {
            self.warned_no_bodycal = true;
            return true;
        }
        false
    }

    /// The reports of one frame that arrived at `arrived`.
    pub fn frame(&mut self, h: &Header, t: &Targets, arrived: TimeVal) -> &Output {
        let time = report_time(h, arrived);
        if self.first.is_none() {
            self.first = Some(time);
            self.last = time;
        }
        let dt =
            ((time.usec - self.last.usec) as f64 / 1e6 + (time.sec - self.last.sec) as f64) as f32;
        self.last = time;

        let (nbody, nflystick) = match &self.fixed {
            Some(f) => (f.bodies, f.flysticks),
            None if h.has_bodycal => (t.num_bodycal, t.flysticks.len() as i32),
            None => (t.bodies.len() as i32, t.flysticks.len() as i32),
        };
        let out = &mut self.out;
        out.time = time;
        out.poses.clear();
        out.beyond = 0;
        let controls = nflystick.clamp(0, MAX_FLYSTICK_CONTROLS as i32) as usize;
        out.num_buttons = controls * BUTTONS_PER_FLYSTICK;
        out.num_channels = controls * CHANNELS_PER_FLYSTICK;

        for b in &t.bodies {
            if b.id >= nbody || b.quality < 0.0 {
                continue;
            }
            let id = match &self.fixed {
                Some(f) => f.sensor.get(b.id as usize).copied().unwrap_or(-1),
                None => b.id,
            };
            match sensor_index(id) {
                Some(s) => out.poses.push(pose(s, &b.loc, &b.rot)),
                None => out.beyond += 1,
            }
        }
        for f in &t.flysticks {
            if f.id >= nflystick {
                continue;
            }
            if f.quality >= 0.0 {
                let id = match &self.fixed {
                    Some(x) => x.sensor.get((f.id + nbody) as usize).copied().unwrap_or(-1),
                    None => f.id + nbody,
                };
                match sensor_index(id) {
                    Some(s) => out.poses.push(pose(s, &f.loc, &f.rot)),
                    None => out.beyond += 1,
                }
            }
            let block = match &self.fixed {
                Some(x) => x.flystick_block.get(f.id as usize).copied().unwrap_or(-1),
                None => f.id,
            };
            match usize::try_from(block)
                .ok()
                .filter(|&b| b < MAX_FLYSTICK_CONTROLS)
            {
                Some(b) => {
                    flystick_buttons(out, b, f, t.old_flystick_format);
                    flystick_channels(
                        out,
                        &mut self.joy_simulate,
                        &mut self.joy_last,
                        self.joy_per_sec,
                        b,
                        f,
                        dt,
                    );
                }
                None => out.beyond += 1,
            }
        }
        if self.markers {
            let offset = (nbody + nflystick) as i64;
            for (i, m) in t.markers.iter().enumerate() {
                match usize::try_from(offset + i as i64)
                    .ok()
                    .filter(|&s| s < MAX_SENSORS)
                {
                    Some(s) => out.poses.push(Pose {
                        sensor: s,
                        pos: m.loc.map(|v| v as f64 / 1000.0),
                        quat: [0.0, 0.0, 0.0, 1.0],
                    }),
                    None => out.beyond += 1,
                }
            }
        }
        &self.out
    }
}

fn flystick_buttons(out: &mut Output, block: usize, f: &super::frame::Flystick, old: bool) {
    let base = block * BUTTONS_PER_FLYSTICK;
    let n = (f.num_button.max(0) as usize).min(BUTTONS_PER_FLYSTICK);
    for i in 0..BUTTONS_PER_FLYSTICK {
        out.buttons[base + i] = i < n && f.button[i] != 0;
    }
    if old {
        // Old format: VRPN's buttons 1 and 3 are the controller's 3 and 1 (kept from older
        // VRPN releases).
        out.buttons[base + 1] = f.button[3] != 0;
        out.buttons[base + 3] = f.button[1] != 0;
    }
}

fn flystick_channels(
    out: &mut Output,
    simulate: &mut [bool],
    last: &mut [f32],
    per_sec: f32,
    block: usize,
    f: &super::frame::Flystick,
    dt: f32,
) {
    let base = block * CHANNELS_PER_FLYSTICK;
    let n = (f.num_joystick.max(0) as usize).min(CHANNELS_PER_FLYSTICK);
    for i in 0..CHANNELS_PER_FLYSTICK {
        let ind = base + i;
        if i >= n {
            out.channels[ind] = 0.0;
            continue;
        }
        let mut v = f.joystick[i];
        if v == 0.0 {
            simulate[ind] = false;
        } else if v.abs() > 0.99 && last[ind] == 0.0 {
            simulate[ind] = true;
        }
        if simulate[ind] {
            if v > 0.0 {
                v = last[ind] + per_sec * dt;
                if v >= 1.0 {
                    v = 1.0;
                    simulate[ind] = false;
                }
            } else {
                v = last[ind] - per_sec * dt;
                if v <= -1.0 {
                    v = -1.0;
                    simulate[ind] = false;
                }
            }
        }
        last[ind] = v;
        out.channels[ind] = v as f64;
    }
}
