//! ForceDevice: the server sends Force, SCP and Force_Error; clients send
//! planes, force fields, trimesh / scene requests, constraints and custom effects, which the
//! server hands to callbacks ([`ForceDeviceServer::on_plane`], [`ForceDeviceServer::on_request`],
//! [`ForceDeviceServer::on_custom_effect`]).
//!
//! The remote's constraint API behaves as the 07.35 C++ remote (built with
//! `FD_SPRINGS_AS_FIELDS`): a constraint is turned into a force field and sent as one; the
//! `constraint_*` messages themselves can still be sent with [`ForceDeviceRemote::send_request`].

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;

use super::base::{self, BaseIds, RemoteCore};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::force as codec;

pub use codec::{
    AddObject, ConstraintInt, ConstraintKSpring, ConstraintVec3, CustomEffect, ForceField,
    HapticScale, IndexedVec3, ObjectId, ObjectOrientation, ObjectVec3, Origin, Plane, Plane2,
    RemoveTriangle, SetObjectIsTouchable, SetTriangle, SetTrimeshType, TransformTrimesh,
    UpdateTrimeshChanges, CONSTRAINT_MODE_LINE, CONSTRAINT_MODE_NONE, CONSTRAINT_MODE_PLANE,
    CONSTRAINT_MODE_POINT, STOP_EFFECT_ID, TRIMESH_GHOST, TRIMESH_HCOLLIDE,
};

/// Ids of all 35 ForceDevice types, in C++ registration order.
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
    fn custom_effect(&self) -> TypeId {
        self.0[34]
    }
}

/// Longest fixed request payload (`transformTrimesh`).
const REQUEST_MAX: usize = TransformTrimesh::LEN;

macro_rules! force_requests {
    ($($(#[$doc:meta])* $v:ident($t:ty) = $idx:expr,)*) => {
        /// A client-to-server ForceDevice request other than Plane, Plane2, Force_Field and
        /// Custom Effect: trimesh, scene and constraint messages.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum ForceRequest {
            $($(#[$doc])* $v($t),)*
        }

        impl ForceRequest {
            /// Indices into [`ForceIds`] of every request type.
            const INDICES: &'static [usize] = &[$($idx),*];

            /// Index of this request's type in [`ForceIds`] (the order in which the C++ device registers them).
            pub fn type_index(&self) -> usize {
                match self {
                    $(ForceRequest::$v(_) => $idx,)*
                }
            }

            /// The VRPN type name of this request.
            pub fn type_name(&self) -> &'static str {
                codec::TYPE_NAMES[self.type_index()]
            }

            fn encode(&self, out: &mut [u8; REQUEST_MAX]) -> usize {
                match self {
                    $(ForceRequest::$v(p) => p.encode(out),)*
                }
            }

            fn decode(index: usize, buf: &[u8]) -> Option<ForceRequest> {
                $(if index == $idx {
                    return <$t>::decode(buf).ok().map(ForceRequest::$v);
                })*
                None
            }
        }
    };
}

force_requests! {
    /// `addObject`: object and parent (-1 = root).
    AddObject(AddObject) = 4,
    /// `addObjectExScene`.
    AddObjectExScene(ObjectId) = 5,
    /// `moveToParent`: object and new parent.
    MoveToParent(AddObject) = 6,
    /// `setObjectPosition`.
    SetObjectPosition(ObjectVec3) = 7,
    /// `setObjectOrientation`: axis and angle.
    SetObjectOrientation(ObjectOrientation) = 8,
    /// `setObjectScale`.
    SetObjectScale(ObjectVec3) = 9,
    /// `removeObject`.
    RemoveObject(ObjectId) = 10,
    /// `setVertex`.
    SetVertex(IndexedVec3) = 11,
    /// `setNormal`.
    SetNormal(IndexedVec3) = 12,
    /// `setTriangle`.
    SetTriangle(SetTriangle) = 13,
    /// `removeTriangle`.
    RemoveTriangle(RemoveTriangle) = 14,
    /// `updateTrimeshChanges`: material (static friction before dynamic).
    UpdateTrimeshChanges(UpdateTrimeshChanges) = 15,
    /// `transformTrimesh`: a row-major 4×4 matrix.
    TransformTrimesh(TransformTrimesh) = 16,
    /// `setTrimeshType`: ghost or hcollide.
    SetTrimeshType(SetTrimeshType) = 17,
    /// `clearTrimesh`.
    ClearTrimesh(ObjectId) = 18,
    /// `setHapticOrigin`.
    SetHapticOrigin(Origin) = 19,
    /// `setHapticScale`.
    SetHapticScale(HapticScale) = 20,
    /// `setSceneOrigin`.
    SetSceneOrigin(Origin) = 21,
    /// `setObjectIsTouchable`.
    SetObjectIsTouchable(SetObjectIsTouchable) = 23,
    /// `constraint_enable`: 0 disables.
    ConstraintEnable(ConstraintInt) = 26,
    /// `constraint_mode`: one of the `CONSTRAINT_MODE_*` values.
    ConstraintMode(ConstraintInt) = 27,
    /// `constraint_point`.
    ConstraintPoint(ConstraintVec3) = 28,
    /// `constraint_linept`.
    ConstraintLinePoint(ConstraintVec3) = 29,
    /// `constraint_linedir`.
    ConstraintLineDirection(ConstraintVec3) = 30,
    /// `constraint_plpt`.
    ConstraintPlanePoint(ConstraintVec3) = 31,
    /// `constraint_plnorm`.
    ConstraintPlaneNormal(ConstraintVec3) = 32,
    /// `constraint_KSpring`.
    ConstraintKSpring(ConstraintKSpring) = 33,
}

/// A request as the server received it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceRequestMsg {
    /// Time the client stamped on it.
    pub time: TimeVal,
    /// The request.
    pub request: ForceRequest,
}

/// A custom effect as the server received it (parameters borrowed from the message).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CustomEffectMsg<'a> {
    /// Time the client stamped on it.
    pub time: TimeVal,
    /// Effect id ([`STOP_EFFECT_ID`] stops) and parameters.
    pub effect: CustomEffect<'a>,
}

type EffectCallback = Rc<RefCell<dyn for<'a> FnMut(&CustomEffectMsg<'a>)>>;

/// The remote's constraint (C++ `vrpn_ForceDevice_Remote` constraint members).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    /// Whether the constraint's field is being sent.
    pub enabled: bool,
    /// One of the `CONSTRAINT_MODE_*` values.
    pub mode: i32,
    /// Point of a point constraint.
    pub point: [f32; 3],
    /// A point on the line of a line constraint.
    pub line_point: [f32; 3],
    /// Direction of the line.
    pub line_direction: [f32; 3],
    /// A point on the plane of a plane constraint.
    pub plane_point: [f32; 3],
    /// Normal of the plane.
    pub plane_normal: [f32; 3],
    /// Spring constant.
    pub kspring: f32,
}

impl Default for Constraint {
    /// Disabled, point mode, everything else zero.
    fn default() -> Self {
        Constraint {
            enabled: false,
            mode: CONSTRAINT_MODE_POINT,
            point: [0.0; 3],
            line_point: [0.0; 3],
            line_direction: [0.0; 3],
            plane_point: [0.0; 3],
            plane_normal: [0.0; 3],
            kspring: 0.0,
        }
    }
}

fn unit(v: [f32; 3]) -> [f64; 3] {
    let v = v.map(f64::from);
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let n = if n == 0.0 { 1.0 } else { n };
    v.map(|x| x / n)
}

impl Constraint {
    /// The force field that realises this constraint, starting from `prev`
    /// (kept unchanged in mode NONE).
    pub fn field(&self, prev: &ForceField) -> ForceField {
        let k = self.kspring as f64;
        let (origin, j): ([f32; 3], [[f64; 3]; 3]) = match self.mode {
            CONSTRAINT_MODE_POINT => (self.point, [[-k, 0.0, 0.0], [0.0, -k, 0.0], [0.0, 0.0, -k]]),
            CONSTRAINT_MODE_PLANE => {
                let n = unit(self.plane_normal);
                (
                    self.plane_point,
                    [0, 1, 2].map(|r| [0, 1, 2].map(|c| -k * n[r] * n[c])),
                )
            }
            CONSTRAINT_MODE_LINE => {
                let d = self.line_direction;
                // C++ quirk: the X and Y components of the direction are mirrored.
                let e = unit([-d[0], -d[1], d[2]]);
                let id = |r: usize, c: usize| if r == c { 1.0 } else { 0.0 };
                (
                    self.line_point,
                    [0, 1, 2].map(|r| [0, 1, 2].map(|c| -k * (id(r, c) - e[r] * e[c]))),
                )
            }
            _ => return *prev,
        };
        ForceField {
            origin,
            force: [0.0; 3],
            jacobian: j.map(|row| row.map(|x| x as f32)),
            radius: 100.0,
        }
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
    core: RemoteCore,
    ids: ForceIds,
    shared: Rc<RemoteShared>,
    constraint: Cell<Constraint>,
    constraint_field: Cell<ForceField>,
    effect_buf: RefCell<Vec<u8>>,
}

impl Deref for ForceDeviceRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl ForceDeviceRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<ForceDeviceRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<ForceDeviceRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, ForceIds::register)?;
        let shared = Rc::new(RemoteShared::default());
        let s = shared.clone();
        core.handle(ids.force(), move |m| {
            if let Ok(f) = codec::Force::decode(m.payload) {
                s.force.call(&ForceReport {
                    time: m.time,
                    force: f.force,
                });
            }
        });
        let s = shared.clone();
        core.handle(ids.scp(), move |m| {
            if let Ok(f) = codec::Scp::decode(m.payload) {
                s.scp.call(&ScpReport {
                    time: m.time,
                    pos: f.pos,
                    quat: f.quat,
                });
            }
        });
        let s = shared.clone();
        core.handle(ids.error(), move |m| {
            if let Ok(f) = codec::ForceError::decode(m.payload) {
                s.error.call(&ForceErrorReport {
                    time: m.time,
                    error_code: f.code,
                });
            }
        });
        Ok(ForceDeviceRemote {
            core,
            ids,
            shared,
            constraint: Cell::new(Constraint::default()),
            constraint_field: Cell::new(ForceField::default()),
            effect_buf: RefCell::new(Vec::new()),
        })
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

    /// Removes a callback an `on_*` method of this remote returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        let s = &self.shared;
        s.force.remove(id) || s.scp.remove(id) || s.error.remove(id)
    }

    /// Sends a plane RELIABLE (C++ `startSurface`).
    pub fn start_surface(&self, plane: &Plane) -> Result<(), Error> {
        let mut buf = [0u8; Plane::LEN];
        plane.encode(&mut buf);
        self.send(self.ids.plane(), &buf)
    }

    /// Sends a plane then its extra properties, both LOW_LATENCY (C++ `sendSurface`).
    pub fn send_surface(&self, plane: &Plane, extra: &Plane2) -> Result<(), Error> {
        let now = self.connection().now().wall;
        let mut buf = [0u8; Plane::LEN];
        plane.encode(&mut buf);
        self.send_at(now, self.ids.plane(), &buf, class::LOW_LATENCY)?;
        let mut buf2 = [0u8; Plane2::LEN];
        extra.encode(&mut buf2);
        self.send_at(now, self.ids.plane2(), &buf2, class::LOW_LATENCY)
    }

    /// Sends a force field LOW_LATENCY (C++ `sendForceField`).
    pub fn send_force_field(&self, field: &ForceField) -> Result<(), Error> {
        let mut buf = [0u8; ForceField::LEN];
        field.encode(&mut buf);
        self.send_at(
            self.connection().now().wall,
            self.ids.force_field(),
            &buf,
            class::LOW_LATENCY,
        )
    }
}

impl ForceDeviceRemote {
    /// Sends a trimesh, scene or constraint request RELIABLE, as the C++ remote does.
    pub fn send_request(&self, request: &ForceRequest) -> Result<(), Error> {
        let mut buf = [0u8; REQUEST_MAX];
        let len = request.encode(&mut buf);
        self.send(self.ids.0[request.type_index()], &buf[..len])
    }

    /// Sends a custom effect RELIABLE (C++ `setCustomEffect` + `startEffect`).
    pub fn send_custom_effect(&self, effect_id: u32, params: &[f32]) -> Result<(), Error> {
        let mut buf = self.effect_buf.borrow_mut();
        let len = CustomEffect::len_for(params.len());
        if buf.len() < len {
            buf.resize(len, 0); // grows to the largest effect sent, then reused
        }
        codec::encode_custom_effect(effect_id, params, &mut buf[..len]);
        self.send(self.ids.custom_effect(), &buf[..len])
    }

    /// Stops the custom effect: id 0xFFFFFFFF with no parameters (C++ `stopEffect`).
    pub fn stop_effect(&self) -> Result<(), Error> {
        self.send_custom_effect(STOP_EFFECT_ID, &[])
    }

    /// Stops the force field: all 16 floats zero, RELIABLE (C++ `stopForceField`).
    pub fn stop_force_field(&self) -> Result<(), Error> {
        let mut buf = [0u8; ForceField::LEN];
        ForceField::default().encode(&mut buf);
        self.send(self.ids.force_field(), &buf)
    }

    /// The constraint as last set.
    pub fn constraint(&self) -> Constraint {
        self.constraint.get()
    }

    /// Enables (1) or disables (0) the constraint (C++ `enableConstraint`): enabling sends the
    /// constraint's force field, disabling stops the field; setting the current value again
    /// sends nothing; other values are refused.
    pub fn enable_constraint(&self, enable: i32) -> Result<(), Error> {
        let on = match enable {
            0 => false,
            1 => true,
            _ => return Err(Error::Unsupported("constraint enable must be 0 or 1")),
        };
        let mut c = self.constraint.get();
        if c.enabled == on {
            return Ok(());
        }
        c.enabled = on;
        self.constraint.set(c);
        if on {
            self.send_constraint_field()
        } else {
            self.stop_force_field()
        }
    }

    fn send_constraint_field(&self) -> Result<(), Error> {
        let field = self.constraint.get().field(&self.constraint_field.get());
        self.constraint_field.set(field);
        self.send_force_field(&field)
    }

    fn update_constraint(&self, f: impl FnOnce(&mut Constraint)) -> Result<(), Error> {
        let mut c = self.constraint.get();
        f(&mut c);
        self.constraint.set(c);
        // The field is recomputed on every change and sent only while enabled.
        let field = c.field(&self.constraint_field.get());
        self.constraint_field.set(field);
        if c.enabled {
            self.send_force_field(&field)
        } else {
            Ok(())
        }
    }

    /// Sets the constraint mode (`CONSTRAINT_MODE_*`).
    pub fn set_constraint_mode(&self, mode: i32) -> Result<(), Error> {
        self.update_constraint(|c| c.mode = mode)
    }

    /// Sets the point of a point constraint.
    pub fn set_constraint_point(&self, p: [f32; 3]) -> Result<(), Error> {
        self.update_constraint(|c| c.point = p)
    }

    /// Sets a point on the line of a line constraint.
    pub fn set_constraint_line_point(&self, p: [f32; 3]) -> Result<(), Error> {
        self.update_constraint(|c| c.line_point = p)
    }

    /// Sets the direction of the line of a line constraint.
    pub fn set_constraint_line_direction(&self, d: [f32; 3]) -> Result<(), Error> {
        self.update_constraint(|c| c.line_direction = d)
    }

    /// Sets a point on the plane of a plane constraint.
    pub fn set_constraint_plane_point(&self, p: [f32; 3]) -> Result<(), Error> {
        self.update_constraint(|c| c.plane_point = p)
    }

    /// Sets the normal of the plane of a plane constraint.
    pub fn set_constraint_plane_normal(&self, n: [f32; 3]) -> Result<(), Error> {
        self.update_constraint(|c| c.plane_normal = n)
    }

    /// Sets the constraint's spring constant.
    pub fn set_constraint_kspring(&self, k: f32) -> Result<(), Error> {
        self.update_constraint(|c| c.kspring = k)
    }
}

#[derive(Default)]
struct ServerShared {
    plane: CallbackList<(TimeVal, Plane)>,
    plane2: CallbackList<(TimeVal, Plane2)>,
    field: CallbackList<(TimeVal, ForceField)>,
    request: CallbackList<ForceRequestMsg>,
    effects: RefCell<Vec<(HandlerId, EffectCallback)>>,
    bad_messages: Cell<u64>,
}

impl ServerShared {
    fn call_effects(&self, msg: &CustomEffectMsg<'_>) {
        let mut i = 0;
        loop {
            let cb = match self.effects.borrow().get(i) {
                Some((_, cb)) => cb.clone(),
                None => break,
            };
            if let Ok(mut f) = cb.try_borrow_mut() {
                f(msg);
            }
            i += 1;
        }
    }
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
    /// This device's sender id on its connection.
    pub fn sender(&self) -> crate::dispatch::SenderId {
        self.base.sender
    }

    /// Registers `device` on a server (or loopback) connection.
    pub fn new(device: &str, conn: &Connection) -> Result<ForceDeviceServer, Error> {
        let (base, ids) = base::register_server(conn, device, ForceIds::register)?;
        let sender = base.sender;
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
        for &index in ForceRequest::INDICES {
            let s = shared.clone();
            conn.register_handler(ids.0[index], only, move |m| {
                match ForceRequest::decode(index, m.payload) {
                    Some(request) => s.request.call(&ForceRequestMsg {
                        time: m.time,
                        request,
                    }),
                    None => s.bad_messages.set(s.bad_messages.get() + 1),
                }
            });
        }
        let s = shared.clone();
        conn.register_handler(
            ids.custom_effect(),
            only,
            move |m| match CustomEffect::decode(m.payload) {
                Ok(effect) => s.call_effects(&CustomEffectMsg {
                    time: m.time,
                    effect,
                }),
                Err(_) => s.bad_messages.set(s.bad_messages.get() + 1),
            },
        );
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

    /// Calls `f` for every trimesh, scene or constraint request a client sends.
    pub fn on_request(&self, f: impl FnMut(&ForceRequestMsg) + 'static) -> HandlerId {
        self.shared.request.add(f)
    }

    /// Removes a callback `on_plane`, `on_plane2`, `on_force_field`, `on_request` or
    /// `on_custom_effect` returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        let s = &self.shared;
        let effect = || {
            let mut e = s.effects.borrow_mut();
            let before = e.len();
            e.retain(|(i, _)| *i != id);
            e.len() != before
        };
        s.plane.remove(id)
            || s.plane2.remove(id)
            || s.field.remove(id)
            || s.request.remove(id)
            || effect()
    }

    /// Calls `f` for every custom effect a client sends (including stops).
    pub fn on_custom_effect(
        &self,
        f: impl for<'a> FnMut(&CustomEffectMsg<'a>) + 'static,
    ) -> HandlerId {
        let id = HandlerId::fresh();
        self.shared
            .effects
            .borrow_mut()
            .push((id, Rc::new(RefCell::new(f))));
        id
    }

    /// The connection the device reports on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// Requests and effects that could not be decoded and were ignored.
    pub fn bad_messages(&self) -> u64 {
        self.shared.bad_messages.get()
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

    /// Sends a surface contact point (LOW_LATENCY); `quat` in (x, y, z, w) order.
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
            self.conn.now().wall,
            self.ids.error(),
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }
}
