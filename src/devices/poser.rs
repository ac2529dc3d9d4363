//! Poser: the client requests poses and velocities; the server clamps, stores
//! and calls back. Quirks of the C++ remote and server are kept for wire compatibility.
//! Every quaternion here is `[f64; 4]` in VRPN's (x, y, z, w) order.

use std::cell::RefCell;
use std::ops::Deref;
use std::rc::Rc;

use super::base::{self, RemoteCore};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::poser as codec;

/// Ids of the poser types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct PoserIds {
    /// Absolute pose request.
    pub pose: TypeId,
    /// Relative pose request.
    pub pose_relative: TypeId,
    /// Absolute velocity request.
    pub velocity: TypeId,
    /// Relative velocity request.
    pub velocity_relative: TypeId,
}

impl PoserIds {
    /// Registers the four poser types in C++ order.
    pub fn register(conn: &Connection) -> Result<PoserIds, Error> {
        Ok(PoserIds {
            pose: conn.register_type(codec::REQUEST_POS_QUAT)?,
            pose_relative: conn.register_type(codec::REQUEST_RELATIVE_POS_QUAT)?,
            velocity: conn.register_type(codec::REQUEST_VELOCITY)?,
            velocity_relative: conn.register_type(codec::REQUEST_RELATIVE_VELOCITY)?,
        })
    }
}

/// quatlib `q_mult(a, b)` = a·b, quaternions as (x, y, z, w).
pub fn q_mult(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by + ay * bw + az * bx - ax * bz,
        aw * bz + az * bw + ax * by - ay * bx,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// A pose (C++ `vrpn_POSERCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoserPose {
    /// Time of the request.
    pub time: TimeVal,
    /// Position.
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
}

/// Client half: sends pose and velocity requests.
pub struct PoserRemote {
    core: RemoteCore,
    ids: PoserIds,
    /// The pose last requested (relative requests accumulate into it, as in C++).
    pos: std::cell::Cell<[f64; 3]>,
    quat: std::cell::Cell<[f64; 4]>,
}

impl Deref for PoserRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl PoserRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<PoserRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<PoserRemote, Error> {
        let (core, ids) = RemoteCore::new(device, conn, PoserIds::register)?;
        Ok(PoserRemote {
            core,
            ids,
            pos: std::cell::Cell::new([0.0; 3]),
            quat: std::cell::Cell::new([0.0, 0.0, 0.0, 1.0]),
        })
    }

    fn send_pose(&self, t: TypeId, time: TimeVal) -> Result<(), Error> {
        let mut buf = [0u8; codec::PoseRequest::LEN];
        codec::PoseRequest {
            pos: self.pos.get(),
            quat: self.quat.get(),
        }
        .encode(&mut buf);
        self.send_at(time, t, &buf, class::LOW_LATENCY)
    }

    /// Requests an absolute pose.
    pub fn request_pose(&self, time: TimeVal, pos: [f64; 3], quat: [f64; 4]) -> Result<(), Error> {
        self.pos.set(pos);
        self.quat.set(quat);
        self.send_pose(self.ids.pose, time)
    }

    /// Requests a relative pose: accumulates into the remote's pose (pos += dp, quat = dq·quat)
    /// and sends the accumulated pose, as C++ does.
    pub fn request_pose_relative(
        &self,
        time: TimeVal,
        dpos: [f64; 3],
        dquat: [f64; 4],
    ) -> Result<(), Error> {
        let mut pos = self.pos.get();
        for (p, d) in pos.iter_mut().zip(dpos) {
            *p += d;
        }
        self.pos.set(pos);
        self.quat.set(q_mult(dquat, self.quat.get()));
        self.send_pose(self.ids.pose_relative, time)
    }

    fn send_velocity(
        &self,
        t: TypeId,
        time: TimeVal,
        vel: [f64; 3],
        quat: [f64; 4],
        dt: f64,
    ) -> Result<(), Error> {
        let mut buf = [0u8; codec::VelocityRequest::LEN];
        codec::VelocityRequest {
            vel,
            vel_quat: quat,
            vel_quat_dt: dt,
        }
        .encode(&mut buf);
        self.send_at(time, t, &buf, class::LOW_LATENCY)
    }

    /// Requests a velocity.
    pub fn request_pose_velocity(
        &self,
        time: TimeVal,
        vel: [f64; 3],
        quat: [f64; 4],
        dt: f64,
    ) -> Result<(), Error> {
        self.send_velocity(self.ids.velocity, time, vel, quat, dt)
    }

    /// Requests a relative velocity (sent as given; not accumulated).
    pub fn request_pose_velocity_relative(
        &self,
        time: TimeVal,
        dvel: [f64; 3],
        dquat: [f64; 4],
        ddt: f64,
    ) -> Result<(), Error> {
        self.send_velocity(self.ids.velocity_relative, time, dvel, dquat, ddt)
    }
}

/// Server-side poser state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoserState {
    /// Time of the last request.
    pub time: TimeVal,
    /// Position (clamped to the workspace).
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
    /// Velocity (clamped to [-1, 1]).
    pub vel: [f64; 3],
    /// Velocity rotation (x, y, z, w).
    pub vel_quat: [f64; 4],
    /// Velocity rotation interval.
    pub vel_quat_dt: f64,
}

struct ServerShared {
    state: RefCell<PoserState>,
    pose: CallbackList<PoserPose>,
    relative: CallbackList<PoserPose>,
}

fn clamp3(v: &mut [f64; 3], lo: f64, hi: f64) {
    for x in v {
        *x = x.clamp(lo, hi);
    }
}

/// Server half (C++ `vrpn_Poser_Server`): position clamped to [-1, 1] on every axis.
pub struct PoserServer {
    shared: Rc<ServerShared>,
    sender: crate::dispatch::SenderId,
}

impl PoserServer {
    /// This device's sender id on its connection.
    pub fn sender(&self) -> crate::dispatch::SenderId {
        self.sender
    }

    /// Registers `device` on a server (or loopback) connection.
    pub fn new(device: &str, conn: &Connection) -> Result<PoserServer, Error> {
        let (base, ids) = base::register_server(conn, device, PoserIds::register)?;
        let sender = base.sender;
        let shared = Rc::new(ServerShared {
            state: RefCell::new(PoserState {
                time: TimeVal::ZERO,
                pos: [0.0; 3],
                quat: [0.0, 0.0, 0.0, 1.0],
                vel: [0.0; 3],
                vel_quat: [0.0, 0.0, 0.0, 1.0],
                vel_quat_dt: 1.0,
            }),
            pose: CallbackList::default(),
            relative: CallbackList::default(),
        });
        let only = SenderFilter::Only(sender);
        let s = shared.clone();
        conn.register_handler(ids.pose, only, move |m| {
            let Ok(r) = codec::PoseRequest::decode(m.payload) else {
                return;
            };
            let p = {
                let mut st = s.state.borrow_mut();
                st.time = m.time;
                st.pos = r.pos;
                st.quat = r.quat;
                clamp3(&mut st.pos, -1.0, 1.0);
                PoserPose {
                    time: m.time,
                    pos: st.pos,
                    quat: st.quat,
                }
            };
            s.pose.call(&p);
        });
        let s = shared.clone();
        conn.register_handler(ids.pose_relative, only, move |m| {
            let Ok(r) = codec::PoseRequest::decode(m.payload) else {
                return;
            };
            {
                let mut st = s.state.borrow_mut();
                st.time = m.time;
                for i in 0..3 {
                    st.pos[i] += r.pos[i];
                }
                st.quat = q_mult(r.quat, st.quat);
                clamp3(&mut st.pos, -1.0, 1.0);
            }
            s.relative.call(&PoserPose {
                time: m.time,
                pos: r.pos,
                quat: r.quat,
            });
        });
        let s = shared.clone();
        conn.register_handler(ids.velocity, only, move |m| {
            let Ok(r) = codec::VelocityRequest::decode(m.payload) else {
                return;
            };
            let mut st = s.state.borrow_mut();
            st.time = m.time;
            st.vel = r.vel;
            st.vel_quat = r.vel_quat;
            st.vel_quat_dt = r.vel_quat_dt;
            clamp3(&mut st.vel, -1.0, 1.0);
        });
        let s = shared.clone();
        conn.register_handler(ids.velocity_relative, only, move |m| {
            let Ok(r) = codec::VelocityRequest::decode(m.payload) else {
                return;
            };
            let mut st = s.state.borrow_mut();
            st.time = m.time;
            // C++ quirks: z ignored, dq multiplied into the pose quaternion.
            st.vel[0] += r.vel[0];
            st.vel[1] += r.vel[1];
            st.quat = q_mult(r.vel_quat, st.quat);
            st.vel_quat_dt += r.vel_quat_dt;
            clamp3(&mut st.vel, -1.0, 1.0);
        });
        Ok(PoserServer { shared, sender })
    }

    /// Calls `f` with the clamped pose after each absolute pose request.
    pub fn on_pose(&self, f: impl FnMut(&PoserPose) + 'static) -> HandlerId {
        self.shared.pose.add(f)
    }

    /// Calls `f` with the raw (dp, dq) of each relative pose request.
    pub fn on_relative_pose(&self, f: impl FnMut(&PoserPose) + 'static) -> HandlerId {
        self.shared.relative.add(f)
    }

    /// Removes a callback `on_pose` or `on_relative_pose` returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.pose.remove(id) || self.shared.relative.remove(id)
    }

    /// The server's current state.
    pub fn state(&self) -> PoserState {
        *self.shared.state.borrow()
    }
}
