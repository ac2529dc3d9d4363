//! Tracker: poses (position + unit quaternion), velocities and accelerations per sensor.
//! [`TrackerRemote`] is the client half; [`TrackerServer`] the server half any
//! driver reports through; [`TrackerNull`] the `vrpn_Tracker_NULL` test device.
//!
//! Quaternions: the reports carry nalgebra's [`UnitQuaternion`]; wherever a quaternion is a
//! plain `[f64; 4]` (the server's `report_pose`, the transforms, the wire), its order is
//! **x, y, z, w** (vector part first, scalar last), as in C++ VRPN.

use std::cell::Cell;
use std::ops::Deref;
use std::rc::Rc;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::base::RemoteCore;
use super::latest::{Latest, Stamp};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::payload::tracker as codec;

mod examples;
mod server;

pub use examples::{TrackerNull, TrackerSpin};
pub use server::{TrackerServer, TrackerTransforms};

pub use super::latest::MAX_LATEST_INDEX;
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

pub(crate) fn xyzw(q: &UnitQuaternion<f64>) -> [f64; 4] {
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
    /// Time the server stamped on the report, translated to the local clock when clock
    /// synchronisation with the server is in effect (otherwise as stamped).
    pub time: TimeVal,
    /// The time exactly as the server stamped it (its own clock).
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock of the `mainloop()` pass that read it).
    pub arrival: TimeVal,
    /// Which pose of this sensor it is: 1 for the first this remote received, then 2, ...
    /// (0 for a sensor index at or beyond [`MAX_LATEST_INDEX`], whose state is not kept).
    /// A frame loop that sees the same `seq` twice saw no new report.
    pub seq: u64,
    /// Sensor index.
    pub sensor: usize,
    /// Position in metres, tracker frame.
    pub pos: Vector3<f64>,
    /// Orientation: rotates tracker axes onto sensor axes. As an array:
    /// `[quat.i, quat.j, quat.k, quat.w]` is VRPN's (x, y, z, w) order.
    pub quat: UnitQuaternion<f64>,
}

/// A velocity report (C++ `vrpn_TRACKERVELCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerVelocity {
    /// Time the server stamped on the report (translated as [`TrackerPose::time`]).
    pub time: TimeVal,
    /// The time exactly as the server stamped it.
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock).
    pub arrival: TimeVal,
    /// Which velocity report of this sensor it is (1, 2, ...; see [`TrackerPose::seq`]).
    pub seq: u64,
    /// Sensor index.
    pub sensor: usize,
    /// Linear velocity, m/s, tracker frame.
    pub vel: Vector3<f64>,
    /// Rotation the sensor undergoes during `vel_quat_dt` seconds, expressed in the tracker's
    /// frame: the orientation `vel_quat_dt` later is `vel_quat * quat` (as C++ VRPN's
    /// dead-reckoning filter applies it).
    pub vel_quat: UnitQuaternion<f64>,
    /// Seconds `vel_quat` spans.
    pub vel_quat_dt: f64,
}

impl TrackerVelocity {
    /// Angular velocity in rad/s, tracker frame: the rotation vector of `vel_quat` divided by
    /// `vel_quat_dt`.
    pub fn angular_velocity(&self) -> Vector3<f64> {
        rotation_rate(&self.vel_quat, self.vel_quat_dt)
    }
}

/// An acceleration report (C++ `vrpn_TRACKERACCCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerAcceleration {
    /// Time the server stamped on the report (translated as [`TrackerPose::time`]).
    pub time: TimeVal,
    /// The time exactly as the server stamped it.
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock).
    pub arrival: TimeVal,
    /// Which acceleration report of this sensor it is (1, 2, ...; see [`TrackerPose::seq`]).
    pub seq: u64,
    /// Sensor index.
    pub sensor: usize,
    /// Linear acceleration, m/s², tracker frame.
    pub acc: Vector3<f64>,
    /// Change of the velocity rotation over `acc_quat_dt` seconds.
    pub acc_quat: UnitQuaternion<f64>,
    /// Seconds `acc_quat` spans.
    pub acc_quat_dt: f64,
}

impl TrackerAcceleration {
    /// Angular acceleration in rad/s², tracker frame: the rotation vector of `acc_quat` is the change of the
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
    pub sensor: usize,
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

struct RemoteShared {
    pose: CallbackList<TrackerPose>,
    velocity: CallbackList<TrackerVelocity>,
    acceleration: CallbackList<TrackerAcceleration>,
    to_room: CallbackList<TrackerToRoom>,
    unit_to_sensor: CallbackList<TrackerUnitToSensor>,
    workspace: CallbackList<TrackerWorkspace>,
    latest_pose: Latest<TrackerPose>,
    latest_velocity: Latest<TrackerVelocity>,
    latest_acceleration: Latest<TrackerAcceleration>,
    bad_messages: Cell<u64>,
}

impl Default for RemoteShared {
    fn default() -> Self {
        RemoteShared {
            pose: CallbackList::default(),
            velocity: CallbackList::default(),
            acceleration: CallbackList::default(),
            to_room: CallbackList::default(),
            unit_to_sensor: CallbackList::default(),
            workspace: CallbackList::default(),
            latest_pose: Latest::with_capacity(16),
            latest_velocity: Latest::with_capacity(0),
            latest_acceleration: Latest::with_capacity(0),
            bad_messages: Cell::new(0),
        }
    }
}

/// Client half of a tracker: callbacks and the latest state of every sensor.
///
/// Two ways to read it, which may be mixed: callbacks ([`on_pose`](Self::on_pose), ...) run
/// for every report inside `mainloop()`; the latest state ([`pose`](Self::pose),
/// [`take_pose`](Self::take_pose), ...) is what a frame loop reads once per frame, with
/// `seq` and `take_*` saying whether a report is new since the last frame.
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

        let s = shared.clone();
        core.handle(ids.pos_quat, move |m| {
            match codec::PosQuat::decode(m.payload) {
                Ok(r) if r.sensor >= 0 => {
                    let (st, sensor) = (Stamp::of(m), r.sensor as usize);
                    let p = s.latest_pose.store(sensor, |seq| TrackerPose {
                        time: m.time,
                        sender_time: st.sender_time,
                        arrival: st.arrival,
                        seq,
                        sensor,
                        pos: Vector3::from(r.pos),
                        quat: quat_from_xyzw(r.quat),
                    });
                    s.pose.call(&p);
                }
                _ => s.bad_messages.set(s.bad_messages.get() + 1),
            }
        });
        let s = shared.clone();
        core.handle(ids.velocity, move |m| {
            match codec::Velocity::decode(m.payload) {
                Ok(r) if r.sensor >= 0 => {
                    let (st, sensor) = (Stamp::of(m), r.sensor as usize);
                    let v = s.latest_velocity.store(sensor, |seq| TrackerVelocity {
                        time: m.time,
                        sender_time: st.sender_time,
                        arrival: st.arrival,
                        seq,
                        sensor,
                        vel: Vector3::from(r.vel),
                        vel_quat: quat_from_xyzw(r.vel_quat),
                        vel_quat_dt: r.vel_quat_dt,
                    });
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
                    let (st, sensor) = (Stamp::of(m), r.sensor as usize);
                    let a = s
                        .latest_acceleration
                        .store(sensor, |seq| TrackerAcceleration {
                            time: m.time,
                            sender_time: st.sender_time,
                            arrival: st.arrival,
                            seq,
                            sensor,
                            acc: Vector3::from(r.acc),
                            acc_quat: quat_from_xyzw(r.acc_quat),
                            acc_quat_dt: r.acc_quat_dt,
                        });
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
        core.handle(
            ids.unit_to_sensor,
            move |m| match codec::UnitToSensor::decode(m.payload) {
                Ok(r) if r.sensor >= 0 => s.unit_to_sensor.call(&TrackerUnitToSensor {
                    time: m.time,
                    sensor: r.sensor as usize,
                    pos: Vector3::from(r.pos),
                    quat: quat_from_xyzw(r.quat),
                }),
                _ => s.bad_messages.set(s.bad_messages.get() + 1),
            },
        );
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
        sensor: usize,
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

    /// Removes a callback any `on_*` method of this remote returned; false when it is not
    /// one of them (ids are unique in the process, so another list's id never matches).
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        let s = &self.shared;
        s.pose.remove(id)
            || s.velocity.remove(id)
            || s.acceleration.remove(id)
            || s.to_room.remove(id)
            || s.unit_to_sensor.remove(id)
            || s.workspace.remove(id)
    }

    /// The latest pose of `sensor`, if one arrived (whether or not it was read before).
    pub fn pose(&self, sensor: usize) -> Option<TrackerPose> {
        self.shared.latest_pose.get(sensor)
    }

    /// The latest pose of `sensor` if it arrived since the last `take_pose(sensor)`: a frame
    /// loop that calls it once per frame gets each new pose once and `None` in frames
    /// where none came (then [`pose`](Self::pose) still has the last one).
    pub fn take_pose(&self, sensor: usize) -> Option<TrackerPose> {
        self.shared.latest_pose.take(sensor)
    }

    /// The latest velocity of `sensor`.
    pub fn velocity(&self, sensor: usize) -> Option<TrackerVelocity> {
        self.shared.latest_velocity.get(sensor)
    }

    /// The latest velocity of `sensor` if new since the last `take_velocity(sensor)`.
    pub fn take_velocity(&self, sensor: usize) -> Option<TrackerVelocity> {
        self.shared.latest_velocity.take(sensor)
    }

    /// The latest acceleration of `sensor`.
    pub fn acceleration(&self, sensor: usize) -> Option<TrackerAcceleration> {
        self.shared.latest_acceleration.get(sensor)
    }

    /// The latest acceleration of `sensor` if new since the last `take_acceleration(sensor)`.
    pub fn take_acceleration(&self, sensor: usize) -> Option<TrackerAcceleration> {
        self.shared.latest_acceleration.take(sensor)
    }

    /// Pose reports received for `sensor` so far (the `seq` of the latest one).
    pub fn pose_count(&self, sensor: usize) -> u64 {
        self.shared.latest_pose.seq(sensor)
    }

    /// Number of sensor slots seen so far (highest sensor index + 1).
    pub fn sensor_count(&self) -> usize {
        self.shared.latest_pose.len()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angular_velocity_from_rotation_over_dt() {
        // 90° about z during 0.5 s is π rad/s about z.
        let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        let v = TrackerVelocity {
            time: TimeVal::ZERO,
            sender_time: TimeVal::ZERO,
            arrival: TimeVal::ZERO,
            seq: 1,
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
            sender_time: TimeVal::ZERO,
            arrival: TimeVal::ZERO,
            seq: 1,
            sensor: 0,
            acc: Vector3::zeros(),
            acc_quat: q,
            acc_quat_dt: 0.1,
        };
        assert!((a.angular_acceleration() - Vector3::new(20.0, 0.0, 0.0)).norm() < 1e-9);
    }
}
