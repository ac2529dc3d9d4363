//! The prediction of `vrpn_Tracker_DeadReckoning_Rotation`, free of I/O: per sensor, the last
//! pose and a rotation per interval (reported by the source's velocity messages, or estimated
//! from its two latest poses), from which the orientation `prediction` seconds after the last
//! pose is computed with quatlib's operations in C++ VRPN 07.38's order, so that the numbers
//! agree with C++'s to the last bit.

use crate::layered::{interval, quat_invert, quat_mult, quat_slerp};
use crate::time::TimeVal;

/// No rotation, (x, y, z, w).
const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// Most whole rotation steps one prediction applies. C++ applies `prediction / interval`
/// steps with no bound (and never ends when the interval is 0); a source reporting a
/// microscopic interval must not stall the server, so steps beyond this bound are skipped.
pub const MAX_STEPS: u32 = 100_000;

/// The state of one sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor {
    /// The rotation over `rotation_interval` seconds.
    pub rotation: [f64; 4],
    /// Seconds the rotation takes.
    pub rotation_interval: f64,
    /// Whether the source has reported a velocity (then poses no longer estimate it).
    pub got_velocity: bool,
    /// Time of the last pose; `sec == 0` until the first.
    pub last_time: TimeVal,
    /// Position of the last pose.
    pub last_pos: [f64; 3],
    /// Orientation of the last pose.
    pub last_quat: [f64; 4],
}

impl Default for Sensor {
    fn default() -> Self {
        Sensor {
            rotation: IDENTITY,
            rotation_interval: 1.0,
            got_velocity: false,
            last_time: TimeVal::ZERO,
            last_pos: [0.0; 3],
            last_quat: IDENTITY,
        }
    }
}

/// A predicted pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// The time predicted for: the last pose's time plus the prediction time.
    pub time: TimeVal,
    /// The last pose's position, unchanged.
    pub pos: [f64; 3],
    /// The predicted orientation.
    pub quat: [f64; 4],
}

impl Sensor {
    /// A pose of the source: estimates the rotation from the previous pose unless the source
    /// reports velocities, and keeps the pose.
    pub fn pose(&mut self, time: TimeVal, pos: [f64; 3], quat: [f64; 4]) {
        if !self.got_velocity && self.last_time.sec != 0 {
            self.rotation = quat_mult(&quat, &quat_invert(&self.last_quat));
            self.rotation_interval = interval(time, self.last_time);
            if self.rotation_interval < 0.0 {
                self.rotation_interval = 1.0;
                self.rotation = IDENTITY;
            }
        }
        self.last_pos = pos;
        self.last_quat = quat;
        self.last_time = time;
    }

    /// A velocity of the source: its rotation over `dt` seconds is used from now on.
    pub fn velocity(&mut self, vel_quat: [f64; 4], dt: f64) {
        self.got_velocity = true;
        self.rotation = vel_quat;
        self.rotation_interval = dt;
    }

    /// The pose predicted `prediction` seconds ahead, `None` before the first pose.
    pub fn predict(&self, prediction: f64) -> Option<Prediction> {
        if self.last_time.sec == 0 {
            return None;
        }
        let mut q = self.last_quat;
        let step = self.rotation_interval;
        // C++ never returns from a rotation interval of 0 or less (two poses with the same
        // time stamp, a velocity with a non-positive dt): the orientation is not advanced.
        if step > 0.0 {
            let mut remaining = prediction;
            let mut steps = 0;
            while remaining > step && steps < MAX_STEPS {
                q = quat_mult(&self.rotation, &q);
                remaining -= step;
                steps += 1;
            }
            let fraction = quat_slerp(&IDENTITY, &self.rotation, remaining / step);
            q = quat_mult(&fraction, &q);
        }
        Some(Prediction {
            time: ahead(self.last_time, prediction),
            pos: self.last_pos,
            quat: q,
        })
    }
}

/// `time` plus `seconds` (0 or more) as C++ adds them: whole seconds and truncated
/// microseconds, carried.
pub fn ahead(time: TimeVal, seconds: f64) -> TimeVal {
    let whole = seconds as i64;
    let usec = ((seconds - whole as f64) * 1e6) as i64;
    let mut t = TimeVal {
        sec: time.sec + whole,
        usec: time.usec + usec,
    };
    if t.sec > 0 && t.usec >= 1_000_000 {
        t.sec += 1;
        t.usec -= 1_000_000;
    }
    t
}
