//! ForceDevice (DEVICES.md §8), the core subset: the server sends Force, SCP and Force_Error;
//! clients send planes and force fields, which the server hands to callbacks. The trimesh,
//! scene, constraint and custom-effect messages are registered (C++ order) but not yet handled.

use std::rc::Rc;

use super::base::{self, BaseIds, PingCycle};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::name::DeviceName;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::force as codec;

pub use codec::{ForceField, Plane, Plane2};

/// Ids of all 35 ForceDevice types, in C++ registration order (index = row − 1 of §8.1).
#[derive(Clone, Copy, Debug)]
pub struct ForceIds(pub [TypeId; 35]);

impl ForceIds {
    /// Registers every ForceDevice type in C++ order.
    pub fn register(conn: &Connection) -> Result<ForceIds, Error> {
        let mut ids = [TypeId(0); 35];
        for (slot, name) in ids.iter_mut().zip(codec::TYPE_NAMES) {
            *slot = conn.register_type(name)?;
        }
        Ok(ForceIds(ids))
    }
    fn force(&self) -> TypeId {
        self.0[0]
    }
    fn force_field(&self) -> TypeId {
        self.0[1]
    }
    fn plane(&self) -> TypeId {
        self.0[2]
    }
    fn plane2(&self) -> TypeId {
        self.0[3]
    }
    fn scp(&self) -> TypeId {
        self.0[24]
    }
    fn error(&self) -> TypeId {
        self.0[25]
    }
}

/// A force report (C++ `vrpn_FORCECB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceReport {
    /// Time of the report.
    pub time: TimeVal,
    /// Force x, y, z.
    pub force: [f64; 3],
}

/// A surface contact point (C++ `vrpn_FORCESCPCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScpReport {
    /// Time of the report.
    pub time: TimeVal,
    /// Contact point.
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
}

/// A force error (C++ `vrpn_FORCEERRORCB`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ForceErrorReport {
    /// Time of the report.
    pub time: TimeVal,
    /// Error code (`FD_*`).
    pub error_code: i32,
}

#[derive(Default)]
struct RemoteShared {
    force: CallbackList<ForceReport>,
    scp: CallbackList<ScpReport>,
    error: CallbackList<ForceErrorReport>,
}

/// Client half of a force device.
pub struct ForceDeviceRemote {
    conn: Connection,
    ids: ForceIds,
    base: BaseIds,
    ping: PingCycle,
    shared: Rc<RemoteShared>,
    handlers: Vec<HandlerId>,
}

impl ForceDeviceRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<ForceDeviceRemote, Error> {
        let parsed = DeviceName::parse(name)?;
        let conn = Connection::open_location(&parsed)?;
        Self::on_connection(&parsed.device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<ForceDeviceRemote, Error> {
        let sender = base::register_sender(conn, device)?;
        let ids = ForceIds::register(conn)?;
        let base = base::register_base_types(conn, sender)?;
        base::attach_default_printer(conn, &base);
        let ping = PingCycle::new(conn, base);
        let shared = Rc::new(RemoteShared::default());
        let only = SenderFilter::Only(sender);
        let s = shared.clone();
        let h1 = conn.register_handler(ids.force(), only, move |m| {
            if let Ok(f) = codec::Force::decode(m.payload) {
                s.force.call(&ForceReport {
                    time: m.time,
                    force: f.force,
                });
            }
        });
        let s = shared.clone();
        let h2 = conn.register_handler(ids.scp(), only, move |m| {
            if let Ok(f) = codec::Scp::decode(m.payload) {
                s.scp.call(&ScpReport {
                    time: m.time,
                    pos: f.pos,
                    quat: f.quat,
                });
            }
        });
        let s = shared.clone();
        let h3 = conn.register_handler(ids.error(), only, move |m| {
            if let Ok(f) = codec::ForceError::decode(m.payload) {
                s.error.call(&ForceErrorReport {
                    time: m.time,
                    error_code: f.code,
                });
            }
        });
        Ok(ForceDeviceRemote {
            conn: conn.clone(),
            ids,
            base,
            ping,
            shared,
            handlers: vec![h1, h2, h3],
        })
    }

    /// Services the connection and the ping cycle.
    pub fn mainloop(&self) -> Result<(), Error> {
        self.conn.mainloop()?;
        self.ping.poll(&self.conn);
        Ok(())
    }

    /// Calls `f` for every force report.
    pub fn on_force(&self, f: impl FnMut(&ForceReport) + 'static) -> HandlerId {
        self.shared.force.add(f)
    }

    /// Calls `f` for every SCP report.
    pub fn on_scp(&self, f: impl FnMut(&ScpReport) + 'static) -> HandlerId {
        self.shared.scp.add(f)
    }

    /// Calls `f` for every error report.
    pub fn on_error(&self, f: impl FnMut(&ForceErrorReport) + 'static) -> HandlerId {
        self.shared.error.add(f)
    }

    /// Sends a plane RELIABLE (C++ `startSurface`).
    pub fn start_surface(&self, plane: &Plane) -> Result<(), Error> {
        let mut buf = [0u8; Plane::LEN];
        plane.encode(&mut buf);
        self.conn.pack_message(
            TimeVal::now(),
            self.ids.plane(),
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }

    /// Sends a plane then its extra properties, both LOW_LATENCY (C++ `sendSurface`).
    pub fn send_surface(&self, plane: &Plane, extra: &Plane2) -> Result<(), Error> {
        let now = TimeVal::now();
        let mut buf = [0u8; Plane::LEN];
        plane.encode(&mut buf);
        self.conn.pack_message(
            now,
            self.ids.plane(),
            self.base.sender,
            &buf,
            class::LOW_LATENCY,
        )?;
        let mut buf2 = [0u8; Plane2::LEN];
        extra.encode(&mut buf2);
        self.conn.pack_message(
            now,
            self.ids.plane2(),
            self.base.sender,
            &buf2,
            class::LOW_LATENCY,
        )
    }

    /// Sends a force field LOW_LATENCY (C++ `sendForceField`).
    pub fn send_force_field(&self, field: &ForceField) -> Result<(), Error> {
        let mut buf = [0u8; ForceField::LEN];
        field.encode(&mut buf);
        self.conn.pack_message(
            TimeVal::now(),
            self.ids.force_field(),
            self.base.sender,
            &buf,
            class::LOW_LATENCY,
        )
    }
}

impl Drop for ForceDeviceRemote {
    fn drop(&mut self) {
        for h in self.handlers.drain(..) {
            self.conn.remove_handler(h);
        }
    }
}

#[derive(Default)]
struct ServerShared {
    plane: CallbackList<(TimeVal, Plane)>,
    plane2: CallbackList<(TimeVal, Plane2)>,
    field: CallbackList<(TimeVal, ForceField)>,
}

/// Server half of a force device: reports force, SCP and errors; hands client planes and
/// force fields to callbacks.
pub struct ForceDeviceServer {
    conn: Connection,
    ids: ForceIds,
    base: BaseIds,
    shared: Rc<ServerShared>,
}

impl ForceDeviceServer {
    /// Registers `device` on a server (or loopback) connection.
    pub fn new(device: &str, conn: &Connection) -> Result<ForceDeviceServer, Error> {
        let sender = base::register_sender(conn, device)?;
        let ids = ForceIds::register(conn)?;
        let base = base::register_base_types(conn, sender)?;
        base::serve_pings(conn, &base);
        let shared = Rc::new(ServerShared::default());
        let only = SenderFilter::Only(sender);
        let s = shared.clone();
        conn.register_handler(ids.plane(), only, move |m| {
            if let Ok(p) = Plane::decode(m.payload) {
                s.plane.call(&(m.time, p));
            }
        });
        let s = shared.clone();
        conn.register_handler(ids.plane2(), only, move |m| {
            if let Ok(p) = Plane2::decode(m.payload) {
                s.plane2.call(&(m.time, p));
            }
        });
        let s = shared.clone();
        conn.register_handler(ids.force_field(), only, move |m| {
            if let Ok(p) = ForceField::decode(m.payload) {
                s.field.call(&(m.time, p));
            }
        });
        Ok(ForceDeviceServer {
            conn: conn.clone(),
            ids,
            base,
            shared,
        })
    }

    /// Calls `f` for every plane a client sends.
    pub fn on_plane(&self, f: impl FnMut(&(TimeVal, Plane)) + 'static) -> HandlerId {
        self.shared.plane.add(f)
    }

    /// Calls `f` for every Plane2 a client sends.
    pub fn on_plane2(&self, f: impl FnMut(&(TimeVal, Plane2)) + 'static) -> HandlerId {
        self.shared.plane2.add(f)
    }

    /// Calls `f` for every force field a client sends.
    pub fn on_force_field(&self, f: impl FnMut(&(TimeVal, ForceField)) + 'static) -> HandlerId {
        self.shared.field.add(f)
    }

    /// Sends a force (LOW_LATENCY).
    pub fn report_force(&self, time: TimeVal, force: [f64; 3]) -> Result<(), Error> {
        let mut buf = [0u8; codec::Force::LEN];
        codec::Force { force }.encode(&mut buf);
        self.conn.pack_message(
            time,
            self.ids.force(),
            self.base.sender,
            &buf,
            class::LOW_LATENCY,
        )
    }

    /// Sends a surface contact point (LOW_LATENCY).
    pub fn report_scp(&self, time: TimeVal, pos: [f64; 3], quat: [f64; 4]) -> Result<(), Error> {
        let mut buf = [0u8; codec::Scp::LEN];
        codec::Scp { pos, quat }.encode(&mut buf);
        self.conn.pack_message(
            time,
            self.ids.scp(),
            self.base.sender,
            &buf,
            class::LOW_LATENCY,
        )
    }

    /// Sends an error code (RELIABLE, stamped now).
    pub fn send_error(&self, code: i32) -> Result<(), Error> {
        let mut buf = [0u8; codec::ForceError::LEN];
        codec::ForceError { code }.encode(&mut buf);
        self.conn.pack_message(
            TimeVal::now(),
            self.ids.error(),
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }
}
