//! Tracker: poses (position + unit quaternion), velocities and accelerations per sensor
//! (DEVICES.md §2). [`TrackerRemote`] is the client half; [`TrackerServer`] the server half any
//! driver reports through; [`TrackerNull`] the `vrpn_Tracker_NULL` test device.

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;
use std::time::{Duration, Instant};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::base::{self, BaseIds, RemoteCore};
use super::ServerDevice;
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::tracker as codec;

pub use codec::{
    ACCELERATION, POS_QUAT, RESET_ORIGIN, SET_UPDATE_RATE, TO_ROOM, TYPE_NAMES, UNIT_TO_SENSOR,
    VELOCITY, WORKSPACE,
};

/// Ids of the tracker types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct TrackerIds {
    /// Pose report.
    pub pos_quat: TypeId,
    /// Velocity report.
    pub velocity: TypeId,
    /// Acceleration report.
    pub acceleration: TypeId,
    /// Tracker-to-room reply.
    pub to_room: TypeId,
    /// Unit-to-sensor reply.
    pub unit_to_sensor: TypeId,
    /// Request for tracker-to-room.
    pub request_to_room: TypeId,
    /// Request for unit-to-sensor.
    pub request_unit_to_sensor: TypeId,
    /// Workspace reply.
    pub workspace: TypeId,
    /// Request for the workspace.
    pub request_workspace: TypeId,
    /// Update-rate request.
    pub set_update_rate: TypeId,
    /// Reset-origin request.
    pub reset_origin: TypeId,
}

impl TrackerIds {
    /// Registers the eleven tracker types in C++ order.
    pub fn register(conn: &Connection) -> Result<TrackerIds, Error> {
        let mut ids = [TypeId(0); 11];
        for (slot, name) in ids.iter_mut().zip(TYPE_NAMES) {
            *slot = conn.register_type(name)?;
        }
        Ok(TrackerIds {
            pos_quat: ids[0],
            velocity: ids[1],
            acceleration: ids[2],
            to_room: ids[3],
            unit_to_sensor: ids[4],
            request_to_room: ids[5],
            request_unit_to_sensor: ids[6],
            workspace: ids[7],
            request_workspace: ids[8],
            set_update_rate: ids[9],
            reset_origin: ids[10],
        })
    }
}

fn quat_from_xyzw(q: [f64; 4]) -> UnitQuaternion<f64> {
    // Kept exactly as sent: the wire quaternion is unit by contract, and renormalising would
    // change the values an application compares against C++ output.
    UnitQuaternion::new_unchecked(Quaternion::new(q[3], q[0], q[1], q[2]))
}

fn xyzw(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

/// Converts a rotation that happens over `dt` seconds into an angular rate (rad/s, as a
/// rotation vector in the same frame as the quaternion).
fn rotation_rate(q: &UnitQuaternion<f64>, dt: f64) -> Vector3<f64> {
    if dt == 0.0 || !dt.is_finite() {
        return Vector3::zeros();
    }
    // Take the short way round: q and −q are the same rotation.
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let s = v.norm();
    if s < 1e-15 {
        return Vector3::zeros();
    }
    let angle = 2.0 * s.atan2(w);
    v * (angle / s) / dt
}

/// A pose report (C++ `vrpn_TRACKERCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerPose {
    /// Time the server stamped on the report.
    pub time: TimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Position in metres, tracker frame.
    pub pos: Vector3<f64>,
    /// Orientation: rotates tracker axes onto sensor axes.
    pub quat: UnitQuaternion<f64>,
}

/// A velocity report (C++ `vrpn_TRACKERVELCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerVelocity {
    /// Time the server stamped on the report.
    pub time: TimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Linear velocity, m/s.
    pub vel: Vector3<f64>,
    /// Rotation the sensor undergoes during `vel_quat_dt` seconds.
    pub vel_quat: UnitQuaternion<f64>,
    /// Seconds `vel_quat` spans.
    pub vel_quat_dt: f64,
}

impl TrackerVelocity {
    /// Angular velocity in rad/s (rotation vector), from the wire's rotation-over-dt.
    pub fn angular_velocity(&self) -> Vector3<f64> {
        rotation_rate(&self.vel_quat, self.vel_quat_dt)
    }
}

/// An acceleration report (C++ `vrpn_TRACKERACCCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerAcceleration {
    /// Time the server stamped on the report.
    pub time: TimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Linear acceleration, m/s².
    pub acc: Vector3<f64>,
    /// Change of the velocity rotation over `acc_quat_dt` seconds.
    pub acc_quat: UnitQuaternion<f64>,
    /// Seconds `acc_quat` spans.
    pub acc_quat_dt: f64,
}

impl TrackerAcceleration {
    /// Angular acceleration in rad/s²: the rotation vector of `acc_quat` is the change of the
    /// angular rate (rad/s) accumulated over `acc_quat_dt`, so it is divided by dt twice.
    pub fn angular_acceleration(&self) -> Vector3<f64> {
        rotation_rate(&self.acc_quat, self.acc_quat_dt) / self.acc_quat_dt
    }
}

/// Tracker-to-room transform reply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerToRoom {
    /// Time of the reply.
    pub time: TimeVal,
    /// Translation.
    pub pos: Vector3<f64>,
    /// Rotation.
    pub quat: UnitQuaternion<f64>,
}

/// Unit-to-sensor transform reply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerUnitToSensor {
    /// Time of the reply.
    pub time: TimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Translation.
    pub pos: Vector3<f64>,
    /// Rotation.
    pub quat: UnitQuaternion<f64>,
}

/// Workspace reply: an axis-aligned box in tracker coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerWorkspace {
    /// Time of the reply.
    pub time: TimeVal,
    /// Minimum corner.
    pub min: Vector3<f64>,
    /// Maximum corner.
    pub max: Vector3<f64>,
}

#[derive(Default)]
struct RemoteShared {
    pose: CallbackList<TrackerPose>,
    velocity: CallbackList<TrackerVelocity>,
    acceleration: CallbackList<TrackerAcceleration>,
    to_room: CallbackList<TrackerToRoom>,
    unit_to_sensor: CallbackList<TrackerUnitToSensor>,
    workspace: CallbackList<TrackerWorkspace>,
    latest_pose: RefCell<Vec<Option<TrackerPose>>>,
    latest_velocity: RefCell<Vec<Option<TrackerVelocity>>>,
    latest_acceleration: RefCell<Vec<Option<TrackerAcceleration>>>,
    bad_messages: Cell<u64>,
}

fn store<T: Copy>(slots: &RefCell<Vec<Option<T>>>, sensor: i32, value: T) {
    let Ok(i) = usize::try_from(sensor) else {
        return;
    };
    let mut s = slots.borrow_mut();
    if s.len() <= i {
        // Grows once per new sensor index, never per report.
        s.resize(i + 1, None);
    }
    s[i] = Some(value);
}

/// Client half of a tracker: callbacks and the latest state of every sensor.
///
/// ```no_run
/// let tracker = vrpn::TrackerRemote::new("Tracker0@localhost")?;
/// tracker.on_pose(|p| println!("sensor {} at {:?}", p.sensor, p.pos));
/// loop {
///     tracker.mainloop()?;
///     std::thread::sleep(std::time::Duration::from_millis(1));
/// }
/// # Ok::<(), vrpn::Error>(())
/// ```
pub struct TrackerRemote {
    core: RemoteCore,
    ids: TrackerIds,
    shared: Rc<RemoteShared>,
}

impl Deref for TrackerRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl TrackerRemote {
    /// Opens `Device@location` (sharing the connection with other devices at that location).
    pub fn new(name: &str) -> Result<TrackerRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection (in-process servers, shared sockets).
    pub fn on_connection(device: &str, conn: &Connection) -> Result<TrackerRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, TrackerIds::register)?;
        let shared = Rc::new(RemoteShared::default());
        shared.latest_pose.borrow_mut().reserve(16);

        let s = shared.clone();
        core.handle(ids.pos_quat, move |m| {
            match codec::PosQuat::decode(m.payload) {
                Ok(r) if r.sensor >= 0 => {
                    let p = TrackerPose {
                        time: m.time,
                        sensor: r.sensor,
                        pos: Vector3::from(r.pos),
                        quat: quat_from_xyzw(r.quat),
                    };
                    store(&s.latest_pose, p.sensor, p);
                    s.pose.call(&p);
                }
                _ => s.bad_messages.set(s.bad_messages.get() + 1),
            }
        });
        let s = shared.clone();
        core.handle(ids.velocity, move |m| {
            match codec::Velocity::decode(m.payload) {
                Ok(r) if r.sensor >= 0 => {
                    let v = TrackerVelocity {
                        time: m.time,
                        sensor: r.sensor,
                        vel: Vector3::from(r.vel),
                        vel_quat: quat_from_xyzw(r.vel_quat),
                        vel_quat_dt: r.vel_quat_dt,
                    };
                    store(&s.latest_velocity, v.sensor, v);
                    s.velocity.call(&v);
                }
                _ => s.bad_messages.set(s.bad_messages.get() + 1),
            }
        });
        let s = shared.clone();
        core.handle(
            ids.acceleration,
            move |m| match codec::Acceleration::decode(m.payload) {
                Ok(r) if r.sensor >= 0 => {
                    let a = TrackerAcceleration {
                        time: m.time,
                        sensor: r.sensor,
                        acc: Vector3::from(r.acc),
                        acc_quat: quat_from_xyzw(r.acc_quat),
                        acc_quat_dt: r.acc_quat_dt,
                    };
                    store(&s.latest_acceleration, a.sensor, a);
                    s.acceleration.call(&a);
                }
                _ => s.bad_messages.set(s.bad_messages.get() + 1),
            },
        );
        let s = shared.clone();
        core.handle(ids.to_room, move |m| {
            if let Ok(r) = codec::ToRoom::decode(m.payload) {
                s.to_room.call(&TrackerToRoom {
                    time: m.time,
                    pos: Vector3::from(r.pos),
                    quat: quat_from_xyzw(r.quat),
                });
            }
        });
        let s = shared.clone();
        core.handle(ids.unit_to_sensor, move |m| {
            if let Ok(r) = codec::UnitToSensor::decode(m.payload) {
                s.unit_to_sensor.call(&TrackerUnitToSensor {
                    time: m.time,
                    sensor: r.sensor,
                    pos: Vector3::from(r.pos),
                    quat: quat_from_xyzw(r.quat),
                });
            }
        });
        let s = shared.clone();
        core.handle(ids.workspace, move |m| {
            if let Ok(r) = codec::Workspace::decode(m.payload) {
                s.workspace.call(&TrackerWorkspace {
                    time: m.time,
                    min: Vector3::from(r.min),
                    max: Vector3::from(r.max),
                });
            }
        });
        Ok(TrackerRemote { core, ids, shared })
    }

    /// Calls `f` for every pose report of every sensor.
    pub fn on_pose(&self, f: impl FnMut(&TrackerPose) + 'static) -> HandlerId {
        self.shared.pose.add(f)
    }

    /// Calls `f` for pose reports of one sensor.
    pub fn on_sensor_pose(
        &self,
        sensor: i32,
        mut f: impl FnMut(&TrackerPose) + 'static,
    ) -> HandlerId {
        self.shared.pose.add(move |p| {
            if p.sensor == sensor {
                f(p)
            }
        })
    }

    /// Calls `f` for every velocity report.
    pub fn on_velocity(&self, f: impl FnMut(&TrackerVelocity) + 'static) -> HandlerId {
        self.shared.velocity.add(f)
    }

    /// Calls `f` for every acceleration report.
    pub fn on_acceleration(&self, f: impl FnMut(&TrackerAcceleration) + 'static) -> HandlerId {
        self.shared.acceleration.add(f)
    }

    /// Calls `f` for tracker-to-room replies.
    pub fn on_to_room(&self, f: impl FnMut(&TrackerToRoom) + 'static) -> HandlerId {
        self.shared.to_room.add(f)
    }

    /// Calls `f` for unit-to-sensor replies.
    pub fn on_unit_to_sensor(&self, f: impl FnMut(&TrackerUnitToSensor) + 'static) -> HandlerId {
        self.shared.unit_to_sensor.add(f)
    }

    /// Calls `f` for workspace replies.
    pub fn on_workspace(&self, f: impl FnMut(&TrackerWorkspace) + 'static) -> HandlerId {
        self.shared.workspace.add(f)
    }

    /// The latest pose of `sensor`, if one arrived.
    pub fn pose(&self, sensor: usize) -> Option<TrackerPose> {
        self.shared
            .latest_pose
            .borrow()
            .get(sensor)
            .copied()
            .flatten()
    }

    /// The latest velocity of `sensor`.
    pub fn velocity(&self, sensor: usize) -> Option<TrackerVelocity> {
        self.shared
            .latest_velocity
            .borrow()
            .get(sensor)
            .copied()
            .flatten()
    }

    /// The latest acceleration of `sensor`.
    pub fn acceleration(&self, sensor: usize) -> Option<TrackerAcceleration> {
        self.shared
            .latest_acceleration
            .borrow()
            .get(sensor)
            .copied()
            .flatten()
    }

    /// Number of sensor slots seen so far (highest sensor index + 1).
    pub fn sensor_count(&self) -> usize {
        self.shared.latest_pose.borrow().len()
    }

    /// Reports that could not be decoded (wrong length, negative sensor) and were ignored.
    pub fn bad_messages(&self) -> u64 {
        self.shared.bad_messages.get()
    }

    /// Asks the server for its tracker-to-room transform.
    pub fn request_to_room(&self) -> Result<(), Error> {
        self.send(self.ids.request_to_room, &[])
    }

    /// Asks the server for every sensor's unit-to-sensor transform.
    pub fn request_unit_to_sensor(&self) -> Result<(), Error> {
        self.send(self.ids.request_unit_to_sensor, &[])
    }

    /// Asks the server for its workspace.
    pub fn request_workspace(&self) -> Result<(), Error> {
        self.send(self.ids.request_workspace, &[])
    }

    /// Asks for `hz` reports per second (servers that cannot honour it ignore it).
    pub fn set_update_rate(&self, hz: f64) -> Result<(), Error> {
        self.send(self.ids.set_update_rate, &hz.to_be_bytes())
    }

    /// Asks the server to re-zero its origin (servers that cannot honour it ignore it).
    pub fn reset_origin(&self) -> Result<(), Error> {
        self.send(self.ids.reset_origin, &[])
    }
}

/// Transforms a tracker server answers requests with.
#[derive(Clone, Debug)]
pub struct TrackerTransforms {
    /// Tracker-to-room translation.
    pub to_room_pos: [f64; 3],
    /// Tracker-to-room rotation (x, y, z, w).
    pub to_room_quat: [f64; 4],
    /// Per-sensor unit-to-sensor translation and rotation.
    pub unit_to_sensor: Vec<([f64; 3], [f64; 4])>,
    /// Workspace minimum corner.
    pub workspace_min: [f64; 3],
    /// Workspace maximum corner.
    pub workspace_max: [f64; 3],
}

impl TrackerTransforms {
    /// The C++ defaults: identities and a ±0.5 m workspace.
    pub fn identity(sensors: usize) -> TrackerTransforms {
        TrackerTransforms {
            to_room_pos: [0.0; 3],
            to_room_quat: [0.0, 0.0, 0.0, 1.0],
            unit_to_sensor: vec![([0.0; 3], [0.0, 0.0, 0.0, 1.0]); sensors.max(1)],
            workspace_min: [-0.5; 3],
            workspace_max: [0.5; 3],
        }
    }
}

/// Server half of a tracker: what drivers report through (C++ `vrpn_Tracker_Server`).
pub struct TrackerServer {
    conn: Connection,
    ids: TrackerIds,
    base: BaseIds,
    num_sensors: usize,
    /// Time of the last report; request handlers set it to "now", as C++ does.
    timestamp: Rc<Cell<TimeVal>>,
    class: u32,
}

impl TrackerServer {
    /// Registers `device` with `sensors` sensors on a server (or loopback) connection.
    pub fn new(device: &str, conn: &Connection, sensors: usize) -> Result<TrackerServer, Error> {
        Self::with_transforms(device, conn, TrackerTransforms::identity(sensors))
    }

    /// Like [`new`](Self::new) with explicit transforms (from `vrpn_Tracker.cfg`).
    pub fn with_transforms(
        device: &str,
        conn: &Connection,
        transforms: TrackerTransforms,
    ) -> Result<TrackerServer, Error> {
        let (base, ids) = base::register_server(conn, device, TrackerIds::register)?;
        let sender = base.sender;
        let timestamp = Rc::new(Cell::new(TimeVal::ZERO));
        let num_sensors = transforms.unit_to_sensor.len();
        let transforms = Rc::new(transforms);
        let only = SenderFilter::Only(sender);

        let (weak, ts, tf) = (conn.downgrade(), timestamp.clone(), transforms.clone());
        conn.register_handler(ids.request_to_room, only, move |_| {
            let Some(c) = weak.upgrade() else { return };
            let now = TimeVal::now();
            ts.set(now);
            let mut buf = [0u8; codec::ToRoom::LEN];
            codec::ToRoom {
                pos: tf.to_room_pos,
                quat: tf.to_room_quat,
            }
            .encode(&mut buf);
            let _ = c.pack_message(now, ids.to_room, sender, &buf, class::RELIABLE);
        });
        let (weak, ts, tf) = (conn.downgrade(), timestamp.clone(), transforms.clone());
        conn.register_handler(ids.request_unit_to_sensor, only, move |_| {
            let Some(c) = weak.upgrade() else { return };
            let now = TimeVal::now();
            ts.set(now);
            for (i, (pos, quat)) in tf.unit_to_sensor.iter().enumerate() {
                let mut buf = [0u8; codec::UnitToSensor::LEN];
                codec::UnitToSensor {
                    sensor: i as i32,
                    pad: 0,
                    pos: *pos,
                    quat: *quat,
                }
                .encode(&mut buf);
                let _ = c.pack_message(now, ids.unit_to_sensor, sender, &buf, class::RELIABLE);
            }
        });
        let (weak, ts, tf) = (conn.downgrade(), timestamp.clone(), transforms);
        conn.register_handler(ids.request_workspace, only, move |_| {
            let Some(c) = weak.upgrade() else { return };
            let now = TimeVal::now();
            ts.set(now);
            let mut buf = [0u8; codec::Workspace::LEN];
            codec::Workspace {
                min: tf.workspace_min,
                max: tf.workspace_max,
            }
            .encode(&mut buf);
            let _ = c.pack_message(now, ids.workspace, sender, &buf, class::RELIABLE);
        });
        Ok(TrackerServer {
            conn: conn.clone(),
            ids,
            base,
            num_sensors,
            timestamp,
            class: class::LOW_LATENCY,
        })
    }

    /// Class of service for reports (LOW_LATENCY by default, as every C++ tracker).
    pub fn set_class_of_service(&mut self, class_of_service: u32) {
        self.class = class_of_service;
    }

    /// Number of sensors.
    pub fn num_sensors(&self) -> usize {
        self.num_sensors
    }

    /// Time of the last report (or of the last request answered).
    pub fn timestamp(&self) -> TimeVal {
        self.timestamp.get()
    }

    fn check_sensor(&self, sensor: i32) -> Result<(), Error> {
        if sensor < 0 || sensor as usize >= self.num_sensors {
            let _ = self.send_text(
                super::text::TextSeverity::Error,
                0,
                "Sensor number too high",
            );
            return Err(Error::Unsupported(
                "sensor number outside the configured count",
            ));
        }
        Ok(())
    }

    /// Reports a pose.
    pub fn report_pose(
        &self,
        sensor: i32,
        time: TimeVal,
        pos: [f64; 3],
        quat: [f64; 4],
    ) -> Result<(), Error> {
        self.check_sensor(sensor)?;
        self.timestamp.set(time);
        let mut buf = [0u8; codec::PosQuat::LEN];
        codec::PosQuat {
            sensor,
            pad: sensor,
            pos,
            quat,
        }
        .encode(&mut buf);
        self.conn
            .pack_message(time, self.ids.pos_quat, self.base.sender, &buf, self.class)
    }

    /// Reports a pose given as nalgebra types.
    pub fn report(
        &self,
        sensor: i32,
        time: TimeVal,
        pos: &Vector3<f64>,
        quat: &UnitQuaternion<f64>,
    ) -> Result<(), Error> {
        self.report_pose(sensor, time, [pos.x, pos.y, pos.z], xyzw(quat))
    }

    /// Reports a velocity: linear m/s and the rotation over `dt` seconds.
    pub fn report_velocity(
        &self,
        sensor: i32,
        time: TimeVal,
        vel: [f64; 3],
        vel_quat: [f64; 4],
        dt: f64,
    ) -> Result<(), Error> {
        self.check_sensor(sensor)?;
        let mut buf = [0u8; codec::Velocity::LEN];
        codec::Velocity {
            sensor,
            pad: sensor,
            vel,
            vel_quat,
            vel_quat_dt: dt,
        }
        .encode(&mut buf);
        self.conn
            .pack_message(time, self.ids.velocity, self.base.sender, &buf, self.class)
    }

    /// Reports an acceleration: linear m/s² and the change of the rotation rate over `dt`.
    pub fn report_acceleration(
        &self,
        sensor: i32,
        time: TimeVal,
        acc: [f64; 3],
        acc_quat: [f64; 4],
        dt: f64,
    ) -> Result<(), Error> {
        self.check_sensor(sensor)?;
        let mut buf = [0u8; codec::Acceleration::LEN];
        codec::Acceleration {
            sensor,
            pad: sensor,
            acc,
            acc_quat,
            acc_quat_dt: dt,
        }
        .encode(&mut buf);
        self.conn.pack_message(
            time,
            self.ids.acceleration,
            self.base.sender,
            &buf,
            self.class,
        )
    }

    /// Sends a text message from this device.
    pub fn send_text(
        &self,
        severity: super::text::TextSeverity,
        level: u32,
        text: &str,
    ) -> Result<(), Error> {
        base::send_text(&self.conn, self.base.sender, severity, level, text)
    }

    /// The connection this server reports on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// Registers a handler for update-rate requests (drivers that can honour them).
    pub fn on_update_rate(&self, mut f: impl FnMut(f64) + 'static) -> HandlerId {
        self.conn.register_handler(
            self.ids.set_update_rate,
            SenderFilter::Only(self.base.sender),
            move |m| {
                if m.payload.len() == 8 {
                    let mut b = [0u8; 8];
                    b.copy_from_slice(m.payload);
                    f(f64::from_be_bytes(b));
                }
            },
        )
    }

    /// Registers a handler for reset-origin requests.
    pub fn on_reset_origin(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.conn.register_handler(
            self.ids.reset_origin,
            SenderFilter::Only(self.base.sender),
            move |_| f(),
        )
    }
}

/// `vrpn_Tracker_NULL NAME SENSORS RATE`: identity poses, zero velocities, at a fixed rate.
pub struct TrackerNull {
    server: TrackerServer,
    name: String,
    period: Option<Duration>,
    next: Instant,
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
            period: (rate > 0.0 && rate.is_finite()).then(|| Duration::from_secs_f64(1.0 / rate)),
            next: Instant::now(),
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

    fn mainloop(&mut self, now: Instant) {
        let Some(period) = self.period else { return };
        if now < self.next {
            return;
        }
        self.report_all(TimeVal::now());
        // Keep the cadence without drifting; after a stall, restart from now.
        self.next += period;
        if self.next <= now {
            self.next = now + period;
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.period.map(|_| self.next)
    }
}

/// `vrpn_Tracker_Spin NAME SENSORS RATE AX AY AZ SPIN_HZ`: every sensor spins about an axis.
pub struct TrackerSpin {
    server: TrackerServer,
    name: String,
    period: Option<Duration>,
    next: Instant,
    started: Instant,
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
        let now = Instant::now();
        Ok(TrackerSpin {
            server: TrackerServer::new(device, conn, sensors)?,
            name: device.to_string(),
            period: (rate > 0.0 && rate.is_finite()).then(|| Duration::from_secs_f64(1.0 / rate)),
            next: now,
            started: now,
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

    fn mainloop(&mut self, now: Instant) {
        let Some(period) = self.period else { return };
        if now < self.next {
            return;
        }
        let t = TimeVal::now();
        let angle = now.duration_since(self.started).as_secs_f64()
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
        self.next += period;
        if self.next <= now {
            self.next = now + period;
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.period.map(|_| self.next)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angular_velocity_from_rotation_over_dt() {
        // 90° about z during 0.5 s is π rad/s about z.
        let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        let v = TrackerVelocity {
            time: TimeVal::ZERO,
            sensor: 0,
            vel: Vector3::zeros(),
            vel_quat: q,
            vel_quat_dt: 0.5,
        };
        let w = v.angular_velocity();
        assert!((w - Vector3::new(0.0, 0.0, std::f64::consts::PI)).norm() < 1e-12);
        // The same rotation written as −q gives the same rate.
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        assert!((rotation_rate(&neg, 0.5) - w).norm() < 1e-12);
        // Identity and dt = 0 give zero.
        assert_eq!(
            rotation_rate(&UnitQuaternion::identity(), 1.0),
            Vector3::zeros()
        );
        assert_eq!(rotation_rate(&q, 0.0), Vector3::zeros());
    }

    #[test]
    fn angular_acceleration_divides_by_dt_twice() {
        let q = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.2);
        let a = TrackerAcceleration {
            time: TimeVal::ZERO,
            sensor: 0,
            acc: Vector3::zeros(),
            acc_quat: q,
            acc_quat_dt: 0.1,
        };
        assert!((a.angular_acceleration() - Vector3::new(20.0, 0.0, 0.0)).norm() < 1e-9);
    }
}
