//! `vrpn_Poser_Analog`: a Poser whose requested positions drive channels of Analog_Output
//! devices (an actuated stage behind a D/A card), optionally reporting back as a Tracker.
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Poser_Analog NAME SEND_TRACKER_REPORTS
//! X  DEVICE CHANNEL OFFSET SCALE MIN MAX
//! Y  DEVICE CHANNEL OFFSET SCALE MIN MAX
//! Z  DEVICE CHANNEL OFFSET SCALE MIN MAX
//! RX DEVICE CHANNEL OFFSET SCALE MIN MAX
//! RY DEVICE CHANNEL OFFSET SCALE MIN MAX
//! RZ DEVICE CHANNEL OFFSET SCALE MIN MAX
//! ```
//!
//! The six axis lines follow in this order. `DEVICE` is an Analog_Output `*NAME` (this
//! server), `NAME@host`, or `NULL` (the axis drives nothing). See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! For each `vrpn_Poser Request Pos_Quat`: the position clamped to each axis's `[MIN, MAX]`;
//! for X, Y and Z in turn, a `vrpn_Analog_Output Change_Request` of `(p − OFFSET) × SCALE`
//! to `CHANNEL` of `DEVICE`; then, with `SEND_TRACKER_REPORTS` non-zero, a `vrpn_Tracker
//! Pos_Quat` (sensor 0, the clamped position, the requested orientation, the time of the
//! pass). For each `vrpn_Poser Request Velocity`, with tracker reports on: a `vrpn_Tracker
//! Velocity` of the velocity clamped to [-1, 1], the requested rotation and an interval of
//! 1 s (C++ never copies the requested one). All as C++ VRPN 07.38.

mod config;
#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

pub use self::config::{Axis, PoserAnalog};
use crate::config::DeviceRef;
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::RemoteCore;
use crate::devices::poser::PoserIds;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::dispatch::SenderFilter;
use crate::driver::registry::Driver;
use crate::error::Error;
use crate::time::Now;
use crate::wire::payload::poser::{PoseRequest, VelocityRequest};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Poser_Analog"],
    parse: config::parse,
    hints: &[],
};

/// The position a request asks for, clamped to the workspace.
pub fn clamp_position(pos: [f64; 3], min: &[f64; 3], max: &[f64; 3]) -> [f64; 3] {
    let mut p = pos;
    for i in 0..3 {
        if p[i] < min[i] {
            p[i] = min[i];
        } else if p[i] > max[i] {
            p[i] = max[i];
        }
    }
    p
}

/// The analog value an axis sends for a (clamped) position coordinate.
pub fn axis_value(axis: &Axis, p: f64) -> f64 {
    (p - axis.offset) * axis.scale
}

/// An Analog_Output the poser drives.
struct Output {
    target: DeviceRef,
    remote: AnalogOutputRemote,
}

impl Output {
    fn open(target: &DeviceRef, server: &Connection) -> Result<Output, Error> {
        let remote = match target {
            DeviceRef::Local(n) => AnalogOutputRemote::on_connection(n, server)?,
            DeviceRef::Remote(n) => {
                let (device, conn) = RemoteCore::open_in(server.reactor().as_ref(), n)?;
                AnalogOutputRemote::on_connection(&device, &conn)?
            }
        };
        Ok(Output {
            target: target.clone(),
            remote,
        })
    }
}

struct State {
    cfg: PoserAnalog,
    tracker: TrackerServer,
    outputs: Vec<Output>,
    /// For X, Y and Z: the index in `outputs` of the axis's device.
    drives: [Option<usize>; 3],
}

impl State {
    fn pose(&mut self, req: &PoseRequest) {
        let p = clamp_position(req.pos, &self.cfg.min(), &self.cfg.max());
        for (i, d) in self.drives.iter().enumerate() {
            let axis = &self.cfg.axes[i];
            if let (Some(o), Some(channel)) = (d, axis.channel) {
                let value = axis_value(axis, p[i]);
                let _ = self.outputs[*o]
                    .remote
                    .request_change_channel_value(channel as i32, value);
            }
        }
        if self.cfg.tracker_reports {
            let now = self.tracker.connection().now().wall;
            let _ = self.tracker.report_pose(0, now, p, req.quat);
        }
    }

    fn velocity(&mut self, req: &VelocityRequest) {
        if self.cfg.tracker_reports {
            let v = clamp_position(req.vel, &[-1.0; 3], &[1.0; 3]);
            let now = self.tracker.connection().now().wall;
            let _ = self.tracker.report_velocity(0, now, v, req.vel_quat, 1.0);
        }
    }
}

/// The running poser.
pub struct PoserAnalogDevice {
    name: String,
    state: Rc<RefCell<State>>,
}

impl PoserAnalogDevice {
    /// The poser `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &PoserAnalog, conn: &Connection) -> Result<PoserAnalogDevice, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 1)?;
        let ids = PoserIds::register(conn)?;
        let sender = tracker.sender();
        let mut outputs: Vec<Output> = Vec::new();
        let mut drives = [None; 3];
        for (i, d) in drives.iter_mut().enumerate() {
            let Some(target) = &cfg.axes[i].device else {
                continue;
            };
            let index = match outputs.iter().position(|o| &o.target == target) {
                Some(k) => k,
                None => {
                    outputs.push(Output::open(target, conn)?);
                    outputs.len() - 1
                }
            };
            *d = Some(index);
        }
        let state = Rc::new(RefCell::new(State {
            cfg: cfg.clone(),
            tracker,
            outputs,
            drives,
        }));
        let s = state.clone();
        conn.register_handler(ids.pose, SenderFilter::Only(sender), move |m| {
            if let (Ok(req), Ok(mut st)) = (PoseRequest::decode(m.payload), s.try_borrow_mut()) {
                st.pose(&req);
            }
        });
        let s = state.clone();
        conn.register_handler(ids.velocity, SenderFilter::Only(sender), move |m| {
            if let (Ok(req), Ok(mut st)) = (VelocityRequest::decode(m.payload), s.try_borrow_mut())
            {
                st.velocity(&req);
            }
        });
        Ok(PoserAnalogDevice {
            name: cfg.name.clone(),
            state,
        })
    }
}

impl ServerDevice for PoserAnalogDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        let st = self.state.borrow();
        for o in &st.outputs {
            if !o.target.is_local() {
                let _ = o.remote.mainloop();
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let st = self.state.borrow();
        st.outputs
            .iter()
            .filter(|o| !o.target.is_local())
            .filter_map(|o| o.remote.connection().poll_timeout())
            .min()
    }
}
