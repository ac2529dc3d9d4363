//! `vrpn_Tracker_AnalogFly`: up to six analog axes become a tracker pose,
//! either directly (absolute) or by integrating rates (differential), with optional reset and
//! clutch buttons.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use super::config::{AnalogFly, FlyMode};
use super::{
    col_matrix_from_quat, euler_col_matrix, interval, mat_mult, quat_from_euler,
    quat_from_row_matrix, update_interval, xyz_quat_invert, AnalogSource, ButtonSource, Mat4,
    IDENTITY, TWO_PI,
};
use crate::connection::{Connection, ConnectionEvent};
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::dispatch::HandlerId;
use crate::error::Error;
use crate::time::{checked_duration, Now, TimeVal};

/// Everything the callbacks and the mainloop share.
struct State {
    absolute: bool,
    world_frame: bool,
    value: [f64; 6],
    current: Mat4,
    clutch: Mat4,
    prevtime: TimeVal,
    clutch_engaged: bool,
    clutch_was_off: bool,
    timestamp: TimeVal,
    pos: [f64; 3],
    quat: [f64; 4],
    /// A fixed "now" for tests; `None` uses the time of the current pass.
    clock: Option<TimeVal>,
    /// The wall-clock time of the current server loop pass.
    pass: TimeVal,
}

impl State {
    fn now(&self) -> TimeVal {
        self.clock.unwrap_or(self.pass)
    }

    fn reset(&mut self) {
        self.clutch = IDENTITY;
        self.current = IDENTITY;
        self.prevtime = self.now();
        self.pos = [0.0; 3];
        self.quat = [0.0, 0.0, 0.0, 1.0];
    }

    /// One update step: the axis values (scaled by `dt` unless absolute) become a
    /// translation and Euler rotation that is applied to the current pose (or replaces it when
    /// absolute), with the clutch taken into account, in C++'s order of operations.
    fn update(&mut self, dt: f64) {
        let dt = if self.absolute { 1.0 } else { dt };
        let v = self.value;
        let (tx, ty, tz) = (v[0] * dt, v[1] * dt, v[2] * dt);
        let rx = v[3] * dt * TWO_PI;
        let ry = v[4] * dt * TWO_PI;
        let rz = v[5] * dt * TWO_PI;
        let mut d = euler_col_matrix(rz, ry, rx);
        d[3][0] = tx;
        d[3][1] = ty;
        d[3][2] = tz;
        if !self.clutch_engaged {
            self.clutch_was_off = true;
            return;
        }
        if self.clutch_was_off {
            self.clutch_was_off = false;
            let q = quat_from_euler(rz, ry, rx);
            let (it, iq) = xyz_quat_invert([tx, ty, tz], q);
            let mut dinv = col_matrix_from_quat(iq);
            dinv[3][0] = it[0];
            dinv[3][1] = it[1];
            dinv[3][2] = it[2];
            self.clutch = mat_mult(&dinv, &self.current);
        }
        if self.absolute {
            self.current = mat_mult(&d, &self.clutch);
        } else if self.world_frame {
            let n = [
                tx + self.current[3][0],
                ty + self.current[3][1],
                tz + self.current[3][2],
            ];
            d[3][..3].fill(0.0);
            self.current[3][..3].fill(0.0);
            self.current = mat_mult(&self.current, &d);
            self.current[3][..3].copy_from_slice(&n);
        } else {
            self.current = mat_mult(&d, &self.current);
        }
        self.pos = [self.current[3][0], self.current[3][1], self.current[3][2]];
        self.quat = quat_from_row_matrix(&self.current);
    }
}

/// `vrpn_Tracker_AnalogFly`: a one-sensor tracker driven by analog axes.
pub struct TrackerAnalogFly {
    name: String,
    tracker: TrackerServer,
    conn: Connection,
    state: Rc<RefCell<State>>,
    /// Enabled axes in X, Y, Z, RX, RY, RZ order, each with its own remote.
    axes: Vec<AnalogSource>,
    reset_button: Option<ButtonSource>,
    clutch_button: Option<ButtonSource>,
    update_interval: f64,
    report_changes: bool,
    /// When the wall clock last crossed an interval boundary (for the deadline).
    prev_instant: Option<Instant>,
    /// The monotonic time of the current pass.
    pass_instant: Option<Instant>,
    first_connection: HandlerId,
}

impl TrackerAnalogFly {
    /// Builds the device `cfg` describes, reporting on `conn` (the server connection).
    pub fn new(cfg: &AnalogFly, conn: &Connection) -> Result<TrackerAnalogFly, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 1)?;
        let now = conn.now().wall;
        let absolute = cfg.mode == FlyMode::Absolute;
        let state = Rc::new(RefCell::new(State {
            absolute,
            world_frame: cfg.world_frame,
            value: [0.0; 6],
            current: IDENTITY,
            clutch: IDENTITY,
            prevtime: now,
            clutch_engaged: cfg.clutch.is_none(),
            clutch_was_off: false,
            timestamp: now,
            pos: [0.0; 3],
            quat: [0.0, 0.0, 0.0, 1.0],
            clock: None,
            pass: now,
        }));

        let mut axes = Vec::new();
        for (i, axis) in cfg.axes.iter().enumerate() {
            let Some(src) = &axis.source else { continue };
            let source = AnalogSource::open(src, conn)?;
            let s = state.clone();
            let channel = axis.channel as usize;
            let offset = axis.offset as f64;
            let thresh = axis.threshold as f64;
            let scale = axis.scale as f64;
            let power = axis.power as f64;
            source.remote.on_report(move |r| {
                let mut st = s.borrow_mut();
                let v = r.channel.get(channel).copied().unwrap_or(0.0);
                let o = v - offset;
                if st.absolute {
                    st.timestamp = r.time;
                }
                st.value[i] = if o.abs() <= thresh {
                    0.0
                } else if o >= 0.0 {
                    (o * scale).powf(power)
                } else {
                    -(o.abs() * scale).powf(power)
                };
            });
            axes.push(source);
        }

        let reset_button = match &cfg.reset {
            Some(b) => {
                let source = ButtonSource::open(&b.device, conn)?;
                let (s, index) = (state.clone(), b.button as usize);
                source.remote.on_change(move |c| {
                    if c.button == index && c.state.is_pressed() {
                        s.borrow_mut().reset();
                    }
                });
                Some(source)
            }
            None => None,
        };
        let clutch_button = match &cfg.clutch {
            Some(b) => {
                let source = ButtonSource::open(&b.device, conn)?;
                let (s, index) = (state.clone(), b.button as usize);
                source.remote.on_change(move |c| {
                    if c.button == index {
                        s.borrow_mut().clutch_engaged = c.state.is_pressed();
                    }
                });
                Some(source)
            }
            None => None,
        };

        let s = state.clone();
        let first_connection = conn.on_event(ConnectionEvent::GotFirstConnection, move || {
            s.borrow_mut().reset();
        });
        state.borrow_mut().reset();
        if absolute {
            let mut st = state.borrow_mut();
            st.prevtime = now;
            st.timestamp = now;
        }
        Ok(TrackerAnalogFly {
            name: cfg.name.clone(),
            tracker,
            conn: conn.clone(),
            state,
            axes,
            reset_button,
            clutch_button,
            update_interval: update_interval(cfg.update_rate),
            report_changes: false,
            prev_instant: None,
            pass_instant: None,
            first_connection,
        })
    }

    /// Report only while some axis is non-zero (C++ `reportChanges`; vrpn_server: off).
    pub fn set_report_changes(&mut self, on: bool) {
        self.report_changes = on;
    }

    /// Pins the clock the device reads ("now" for intervals, resets and report times) to `t`;
    /// `None` returns to the wall clock. For deterministic tests.
    pub fn set_clock(&mut self, t: Option<TimeVal>) {
        self.state.borrow_mut().clock = t;
    }

    /// Resets the pose to identity and restarts the interval (what the reset button does).
    pub fn reset(&mut self) {
        self.state.borrow_mut().reset();
    }

    /// The current pose: position and (x, y, z, w) quaternion.
    pub fn pose(&self) -> ([f64; 3], [f64; 4]) {
        let st = self.state.borrow();
        (st.pos, st.quat)
    }

    /// The processed value of each axis (X, Y, Z, RX, RY, RZ).
    pub fn values(&self) -> [f64; 6] {
        self.state.borrow().value
    }

    /// The tracker this device reports through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// Deadlines of the sources read from other servers (their connections' own schedules).
    fn source_deadlines(&self) -> impl Iterator<Item = Instant> + '_ {
        self.axes
            .iter()
            .filter_map(AnalogSource::next_deadline)
            .chain(
                self.reset_button
                    .iter()
                    .filter_map(ButtonSource::next_deadline),
            )
            .chain(
                self.clutch_button
                    .iter()
                    .filter_map(ButtonSource::next_deadline),
            )
    }

    /// One mainloop pass at the device's clock.
    pub fn poll(&mut self) {
        for a in &self.axes {
            a.poll();
        }
        if let Some(b) = &self.reset_button {
            b.poll();
        }
        if let Some(b) = &self.clutch_button {
            b.poll();
        }
        let report = {
            let mut st = self.state.borrow_mut();
            let now = st.now();
            let dt = interval(now, st.prevtime);
            let due = dt >= self.update_interval;
            let report = due && (!self.report_changes || st.value.iter().any(|&v| v != 0.0));
            if report {
                if !st.absolute {
                    st.timestamp = now;
                }
                st.update(dt);
                st.prevtime = now;
            }
            if due {
                st.prevtime = now;
                self.prev_instant = self.pass_instant;
            }
            report.then_some((st.timestamp, st.pos, st.quat))
        };
        if let Some((time, pos, quat)) = report {
            let _ = self.tracker.report_pose(0, time, pos, quat);
        }
    }
}

impl Drop for TrackerAnalogFly {
    fn drop(&mut self) {
        self.conn.remove_handler(self.first_connection);
    }
}

impl ServerDevice for TrackerAnalogFly {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        self.state.borrow_mut().pass = now.wall;
        self.pass_instant = Some(now.mono);
        if self.prev_instant.is_none() {
            self.prev_instant = Some(now.mono);
        }
        self.poll();
    }

    fn next_deadline(&self) -> Option<Instant> {
        // An interval too long for a deadline (a rate below one per `MAX_PERIOD`) is never.
        let own = self
            .prev_instant
            .zip(checked_duration(self.update_interval))
            .map(|(p, d)| p + d);
        own.into_iter().chain(self.source_deadlines()).min()
    }
}
