//! The example trackers of `vrpn.cfg`: `vrpn_Tracker_NULL` and `vrpn_Tracker_Spin`.

use std::time::Instant;

use super::TrackerServer;
use crate::connection::Connection;
use crate::devices::{Cadence, ServerDevice};
use crate::error::Error;
use crate::time::{Now, TimeVal};

/// `vrpn_Tracker_NULL NAME SENSORS RATE`: identity poses, zero velocities, at a fixed rate.
pub struct TrackerNull {
    server: TrackerServer,
    name: String,
    cadence: Cadence,
}

impl TrackerNull {
    /// A NULL tracker reporting `sensors` sensors `rate` times per second (0: never).
    pub fn new(
        device: &str,
        conn: &Connection,
        sensors: usize,
        rate: f64,
    ) -> Result<TrackerNull, Error> {
        Ok(TrackerNull {
            server: TrackerServer::new(device, conn, sensors)?,
            name: device.to_string(),
            cadence: Cadence::per_second(rate),
        })
    }

    /// The underlying tracker server.
    pub fn server(&self) -> &TrackerServer {
        &self.server
    }

    fn report_all(&self, now: TimeVal) {
        const ID: [f64; 4] = [0.0, 0.0, 0.0, 1.0];
        for s in 0..self.server.num_sensors() as i32 {
            let _ = self.server.report_pose(s, now, [0.0; 3], ID);
            let _ = self.server.report_velocity(s, now, [0.0; 3], ID, 1.0);
            let _ = self.server.report_acceleration(s, now, [0.0; 3], ID, 1.0);
        }
    }
}

impl ServerDevice for TrackerNull {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        if self.cadence.due(now.mono) {
            self.report_all(now.wall);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}

/// `vrpn_Tracker_Spin NAME SENSORS RATE AX AY AZ SPIN_HZ`: every sensor spins about an axis.
pub struct TrackerSpin {
    server: TrackerServer,
    name: String,
    cadence: Cadence,
    started: Option<Instant>,
    axis: [f64; 3],
    spin_hz: f64,
    vel_quat: [f64; 4],
    vel_dt: f64,
}

/// Rotation about `axis` (normalised first; a zero axis gives the identity) by `angle`, (x,y,z,w).
fn axis_angle_xyzw(axis: [f64; 3], angle: f64) -> [f64; 4] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    if n == 0.0 {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let s = (angle / 2.0).sin() / n;
    [axis[0] * s, axis[1] * s, axis[2] * s, (angle / 2.0).cos()]
}

impl TrackerSpin {
    /// A spinning tracker, as the C++ example server computes it.
    pub fn new(
        device: &str,
        conn: &Connection,
        sensors: usize,
        rate: f64,
        axis: [f64; 3],
        spin_hz: f64,
    ) -> Result<TrackerSpin, Error> {
        let (axis, spin_hz) = if spin_hz < 0.0 {
            ([-axis[0], -axis[1], -axis[2]], -spin_hz)
        } else {
            (axis, spin_hz)
        };
        let vel_dt = if spin_hz == 0.0 {
            1.0
        } else {
            0.9 * (0.5 / spin_hz)
        };
        let vel_quat = axis_angle_xyzw(axis, vel_dt * spin_hz * 2.0 * std::f64::consts::PI);
        Ok(TrackerSpin {
            server: TrackerServer::new(device, conn, sensors)?,
            name: device.to_string(),
            cadence: Cadence::per_second(rate),
            started: None,
            axis,
            spin_hz,
            vel_quat,
            vel_dt,
        })
    }
}

impl ServerDevice for TrackerSpin {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        if !self.cadence.due(now.mono) {
            return;
        }
        let t = now.wall;
        let started = *self.started.get_or_insert(now.mono);
        let angle = now.mono.duration_since(started).as_secs_f64()
            * self.spin_hz
            * 2.0
            * std::f64::consts::PI;
        let quat = axis_angle_xyzw(self.axis, angle);
        const ID: [f64; 4] = [0.0, 0.0, 0.0, 1.0];
        for s in 0..self.server.num_sensors() as i32 {
            let _ = self.server.report_pose(s, t, [0.0; 3], quat);
            let _ = self
                .server
                .report_velocity(s, t, [0.0; 3], self.vel_quat, self.vel_dt);
            let _ = self.server.report_acceleration(s, t, [0.0; 3], ID, 1.0);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}
