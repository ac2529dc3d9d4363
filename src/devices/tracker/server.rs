//! The server half of a tracker: what drivers report through (C++ `vrpn_Tracker_Server`).

use std::cell::Cell;
use std::rc::Rc;

use nalgebra::{UnitQuaternion, Vector3};

use super::{codec, xyzw, TrackerIds};
use crate::connection::{Connection, ServiceClass};
use crate::devices::base::{self, BaseIds};
use crate::devices::latest::Index;
use crate::dispatch::{HandlerId, SenderFilter, SenderId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;

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
    class: ServiceClass,
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

        let (ts, tf) = (timestamp.clone(), transforms.clone());
        conn.register_handler(ids.request_to_room, only, move |m| {
            let c = m.connection();
            let now = c.now().wall;
            ts.set(now);
            let mut buf = [0u8; codec::ToRoom::LEN];
            codec::ToRoom {
                pos: tf.to_room_pos,
                quat: tf.to_room_quat,
            }
            .encode(&mut buf);
            let _ = m.reply(now, ids.to_room, sender, &buf, class::RELIABLE);
        });
        let (ts, tf) = (timestamp.clone(), transforms.clone());
        conn.register_handler(ids.request_unit_to_sensor, only, move |m| {
            let c = m.connection();
            let now = c.now().wall;
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
                let _ = m.reply(now, ids.unit_to_sensor, sender, &buf, class::RELIABLE);
            }
        });
        let (ts, tf) = (timestamp.clone(), transforms);
        conn.register_handler(ids.request_workspace, only, move |m| {
            let c = m.connection();
            let now = c.now().wall;
            ts.set(now);
            let mut buf = [0u8; codec::Workspace::LEN];
            codec::Workspace {
                min: tf.workspace_min,
                max: tf.workspace_max,
            }
            .encode(&mut buf);
            let _ = m.reply(now, ids.workspace, sender, &buf, class::RELIABLE);
        });
        Ok(TrackerServer {
            conn: conn.clone(),
            ids,
            base,
            num_sensors,
            timestamp,
            class: ServiceClass::LOW_LATENCY,
        })
    }

    /// Class of service for reports (LOW_LATENCY by default, as every C++ tracker).
    pub fn set_class_of_service(&mut self, class_of_service: impl Into<ServiceClass>) {
        self.class = class_of_service.into();
    }

    /// This device's sender id on its connection.
    pub fn sender(&self) -> SenderId {
        self.base.sender
    }

    /// Number of sensors.
    pub fn num_sensors(&self) -> usize {
        self.num_sensors
    }

    /// Time of the last report (or of the last request answered).
    pub fn timestamp(&self) -> TimeVal {
        self.timestamp.get()
    }

    /// The wire's sensor number of `sensor`, or an error (and a text, as C++) when it is
    /// outside the configured count.
    fn check_sensor(&self, sensor: impl Index) -> Result<i32, Error> {
        let i = sensor.to_index().filter(|&i| i < self.num_sensors);
        let Some(i) = i else {
            let _ = self.send_text(
                crate::devices::text::TextSeverity::Error,
                0,
                "Sensor number too high",
            );
            return Err(Error::Unsupported(
                "sensor number outside the configured count",
            ));
        };
        Ok(i as i32)
    }

    /// Reports a pose: position in metres, orientation as a unit quaternion in VRPN's
    /// **(x, y, z, w)** order. `sensor` is a `usize` (or any integer; outside the configured
    /// count is an error).
    pub fn report_pose(
        &self,
        sensor: impl Index,
        time: TimeVal,
        pos: [f64; 3],
        quat: [f64; 4],
    ) -> Result<(), Error> {
        let sensor = self.check_sensor(sensor)?;
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
        sensor: impl Index,
        time: TimeVal,
        pos: &Vector3<f64>,
        quat: &UnitQuaternion<f64>,
    ) -> Result<(), Error> {
        self.report_pose(sensor, time, [pos.x, pos.y, pos.z], xyzw(quat))
    }

    /// Reports a velocity: linear m/s and the rotation over `dt` seconds (quaternion
    /// x, y, z, w).
    pub fn report_velocity(
        &self,
        sensor: impl Index,
        time: TimeVal,
        vel: [f64; 3],
        vel_quat: [f64; 4],
        dt: f64,
    ) -> Result<(), Error> {
        let sensor = self.check_sensor(sensor)?;
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

    /// Reports an acceleration: linear m/s² and the change of the rotation rate over `dt`
    /// (quaternion x, y, z, w).
    pub fn report_acceleration(
        &self,
        sensor: impl Index,
        time: TimeVal,
        acc: [f64; 3],
        acc_quat: [f64; 4],
        dt: f64,
    ) -> Result<(), Error> {
        let sensor = self.check_sensor(sensor)?;
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
        severity: crate::devices::text::TextSeverity,
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
