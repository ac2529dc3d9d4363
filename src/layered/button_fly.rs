//! `vrpn_Tracker_ButtonFly`: buttons jump to fixed poses (absolute axes) or fly
//! at a constant velocity while held (differential axes), optionally scaled by analogs.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use super::config::{ButtonFly, FlyMode, ScaleAnalog};
use super::{
    euler_col_matrix, interval, mat_mult, quat_from_row_matrix, update_interval, AnalogSource,
    ButtonSource, Mat4, IDENTITY, TWO_PI,
};
use crate::connection::{Connection, ConnectionEvent};
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::dispatch::HandlerId;
use crate::error::Error;
use crate::time::{checked_duration, Now, TimeVal};

struct AxisState {
    absolute: bool,
    vec: [f32; 3],
    rot: [f32; 3],
    active: bool,
}

struct State {
    axes: Vec<AxisState>,
    current: Mat4,
    prevtime: TimeVal,
    timestamp: TimeVal,
    vel_scale: f32,
    rot_scale: f32,
    pos: [f64; 3],
    quat: [f64; 4],
    clock: Option<TimeVal>,
    /// The wall-clock time of the current server loop pass.
    pass: TimeVal,
}

impl State {
    fn now(&self) -> TimeVal {
        self.clock.unwrap_or(self.pass)
    }

    fn reset(&mut self) {
        self.current = IDENTITY;
        self.prevtime = self.now();
        self.pos = [0.0; 3];
        self.quat = [0.0, 0.0, 0.0, 1.0];
    }

    fn set_pose_from_current(&mut self) {
        self.pos = [self.current[3][0], self.current[3][1], self.current[3][2]];
        self.quat = quat_from_row_matrix(&self.current);
    }

    /// One update step: each active axis moves (velocity) or turns (rotation) by its vector
    /// times the scale factors and `dt`, in C++'s order of operations.
    fn update(&mut self, dt: f64) {
        let (mut tx, mut ty, mut tz) = (0.0, 0.0, 0.0);
        let (mut rx, mut ry, mut rz) = (0.0, 0.0, 0.0);
        let vel = self.vel_scale as f64;
        let rs = self.rot_scale as f64;
        for a in self.axes.iter().filter(|a| a.active && !a.absolute) {
            tx += a.vec[0] as f64 * dt * vel;
            ty += a.vec[1] as f64 * dt * vel;
            tz += a.vec[2] as f64 * dt * vel;
            rx = a.rot[0] as f64 * dt * TWO_PI * rs;
            ry = a.rot[1] as f64 * dt * TWO_PI * rs;
            rz = a.rot[2] as f64 * dt * TWO_PI * rs;
        }
        let mut d = euler_col_matrix(rz, ry, rx);
        d[3][0] = tx;
        d[3][1] = ty;
        d[3][2] = tz;
        self.current = mat_mult(&d, &self.current);
        self.set_pose_from_current();
    }
}

/// `vrpn_Tracker_ButtonFly`: a one-sensor tracker driven by buttons.
pub struct TrackerButtonFly {
    name: String,
    tracker: TrackerServer,
    conn: Connection,
    state: Rc<RefCell<State>>,
    buttons: Vec<ButtonSource>,
    vel_source: Option<AnalogSource>,
    rot_source: Option<AnalogSource>,
    update_interval: f64,
    report_changes: bool,
    prev_instant: Option<Instant>,
    /// The monotonic time of the current pass.
    pass_instant: Option<Instant>,
    first_connection: HandlerId,
}

fn scale_source(
    cfg: &Option<ScaleAnalog>,
    conn: &Connection,
    state: &Rc<RefCell<State>>,
    rotation: bool,
) -> Result<Option<AnalogSource>, Error> {
    let Some(c) = cfg else { return Ok(None) };
    let source = AnalogSource::open(&c.source, conn)?;
    let s = state.clone();
    let (channel, offset, scale, power) = (
        c.channel as usize,
        c.offset as f64,
        c.scale as f64,
        c.power as f64,
    );
    source.remote.on_report(move |r| {
        let v = r.channel.get(channel).copied().unwrap_or(0.0);
        let o = v - offset;
        let f = (o * scale).abs().powf(power);
        let value = if o >= 0.0 { f } else { -f } as f32;
        let mut st = s.borrow_mut();
        if rotation {
            st.rot_scale = value;
        } else {
            st.vel_scale = value;
        }
    });
    Ok(Some(source))
}

impl TrackerButtonFly {
    /// Builds the device `cfg` describes, reporting on `conn` (the server connection).
    pub fn new(cfg: &ButtonFly, conn: &Connection) -> Result<TrackerButtonFly, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 1)?;
        let now = conn.now().wall;
        let state = Rc::new(RefCell::new(State {
            axes: cfg
                .axes
                .iter()
                .map(|a| AxisState {
                    absolute: a.mode == FlyMode::Absolute,
                    vec: a.vec,
                    rot: a.rot,
                    active: false,
                })
                .collect(),
            current: IDENTITY,
            prevtime: now,
            timestamp: now,
            vel_scale: 1.0,
            rot_scale: 1.0,
            pos: [0.0; 3],
            quat: [0.0, 0.0, 0.0, 1.0],
            clock: None,
            pass: now,
        }));
        let mut buttons = Vec::with_capacity(cfg.axes.len());
        for (i, a) in cfg.axes.iter().enumerate() {
            let source = ButtonSource::open(&a.button.device, conn)?;
            let (s, index) = (state.clone(), a.button.button as usize);
            source.remote.on_change(move |c| {
                if c.button != index {
                    return;
                }
                let mut st = s.borrow_mut();
                if st.axes[i].absolute {
                    if c.state.is_pressed() {
                        let (v, r) = (st.axes[i].vec, st.axes[i].rot);
                        let mut m = euler_col_matrix(
                            r[2] as f64 * TWO_PI,
                            r[1] as f64 * TWO_PI,
                            r[0] as f64 * TWO_PI,
                        );
                        m[3][0] = v[0] as f64;
                        m[3][1] = v[1] as f64;
                        m[3][2] = v[2] as f64;
                        st.current = m;
                        st.set_pose_from_current();
                        st.axes[i].active = true;
                    }
                } else {
                    st.axes[i].active = c.state.is_pressed();
                }
            });
            buttons.push(source);
        }
        let vel_source = scale_source(&cfg.vel_scale, conn, &state, false)?;
        let rot_source = scale_source(&cfg.rot_scale, conn, &state, true)?;
        let s = state.clone();
        let first_connection = conn.on_event(ConnectionEvent::GotFirstConnection, move || {
            s.borrow_mut().reset();
        });
        state.borrow_mut().reset();
        Ok(TrackerButtonFly {
            name: cfg.name.clone(),
            tracker,
            conn: conn.clone(),
            state,
            buttons,
            vel_source,
            rot_source,
            update_interval: update_interval(cfg.update_rate),
            report_changes: false,
            prev_instant: None,
            pass_instant: None,
            first_connection,
        })
    }

    /// Report only while a differential axis is active (C++ `reportChanges`; vrpn_server: off).
    pub fn set_report_changes(&mut self, on: bool) {
        self.report_changes = on;
    }

    /// Pins the clock the device reads to `t` (`None`: wall clock). For deterministic tests.
    pub fn set_clock(&mut self, t: Option<TimeVal>) {
        self.state.borrow_mut().clock = t;
    }

    /// Resets the pose to identity and restarts the interval.
    pub fn reset(&mut self) {
        self.state.borrow_mut().reset();
    }

    /// The current pose: position and (x, y, z, w) quaternion.
    pub fn pose(&self) -> ([f64; 3], [f64; 4]) {
        let st = self.state.borrow();
        (st.pos, st.quat)
    }

    /// The current velocity and rotation scale factors (f32, as C++ stores them).
    pub fn scales(&self) -> (f32, f32) {
        let st = self.state.borrow();
        (st.vel_scale, st.rot_scale)
    }

    /// The tracker this device reports through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// Deadlines of the sources read from other servers (their connections' own schedules).
    fn source_deadlines(&self) -> impl Iterator<Item = Instant> + '_ {
        self.buttons
            .iter()
            .filter_map(ButtonSource::next_deadline)
            .chain(
                self.vel_source
                    .iter()
                    .filter_map(AnalogSource::next_deadline),
            )
            .chain(
                self.rot_source
                    .iter()
                    .filter_map(AnalogSource::next_deadline),
            )
    }

    /// One mainloop pass at the device's clock.
    pub fn poll(&mut self) {
        for b in &self.buttons {
            b.poll();
        }
        if let Some(a) = &self.vel_source {
            a.poll();
        }
        if let Some(a) = &self.rot_source {
            a.poll();
        }
        let report = {
            let mut st = self.state.borrow_mut();
            let now = st.now();
            let dt = interval(now, st.prevtime);
            let mut jumped = false;
            for a in st.axes.iter_mut().filter(|a| a.absolute && a.active) {
                a.active = false;
                jumped = true;
            }
            let due = dt >= self.update_interval;
            let report = jumped
                || (due
                    && (!self.report_changes || st.axes.iter().any(|a| a.active && !a.absolute)));
            if report || due {
                st.update(dt);
                st.prevtime = now;
                self.prev_instant = self.pass_instant;
            }
            if report {
                st.timestamp = now;
            }
            report.then_some((st.timestamp, st.pos, st.quat))
        };
        if let Some((time, pos, quat)) = report {
            let _ = self.tracker.report_pose(0, time, pos, quat);
        }
    }
}

impl Drop for TrackerButtonFly {
    fn drop(&mut self) {
        self.conn.remove_handler(self.first_connection);
    }
}

impl ServerDevice for TrackerButtonFly {
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
        // An absolute press is reported on the very next pass.
        if self
            .state
            .borrow()
            .axes
            .iter()
            .any(|a| a.absolute && a.active)
        {
            return self.pass_instant;
        }
        // An interval too long for a deadline (a rate below one per `MAX_PERIOD`) is never.
        let own = self
            .prev_instant
            .zip(checked_duration(self.update_interval))
            .map(|(p, d)| p + d);
        own.into_iter().chain(self.source_deadlines()).min()
    }
}
