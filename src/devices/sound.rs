//! Sound (`vrpn_Sound`): a client loads, plays and places sounds, moves the listener and
//! describes the acoustic scene (polygons and materials); a sound server plays them.
//! [`SoundClient`] is the client half. [`SoundServer`] decodes every request and hands it
//! to the program's callbacks as a [`SoundRequest`]: this crate has no audio back end, a
//! program plugs in its own (C++ subclasses `vrpn_Sound_Server` for each engine).
//!
//! Text messages from the server (C++ servers report errors that way) reach the client
//! through the default text printer, or a [`TextReceiver`](super::text_device::TextReceiver)
//! on the same name.

use std::cell::Cell;
use std::ops::Deref;
use std::rc::Rc;

use super::base::{self, BaseIds, RemoteCore};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::payload::sound::{self as codec, LoadModel, LoadSound};

pub use codec::{
    ConeInfo, DistanceInfo, ListenerPose, ListenerVelocity, Material, MaterialName, Play,
    PolyMaterial, PolyQuad, PolyTri, QuadVertices, SoundDef, SoundId, SoundPose, SoundValue,
    SoundVelocity, Status, TriVertices, MATERIAL_NAME_LEN,
};

/// Ids of the 25 sound types, in C++ registration order ([`codec::TYPE_NAMES`]).
#[derive(Clone, Copy, Debug)]
pub struct SoundIds(pub [TypeId; 25]);

impl SoundIds {
    /// Registers every sound type in C++ order.
    pub fn register(conn: &Connection) -> Result<SoundIds, Error> {
        let mut ids = [TypeId(0); 25];
        for (slot, name) in ids.iter_mut().zip(codec::TYPE_NAMES) {
            *slot = conn.register_type(name)?;
        }
        Ok(SoundIds(ids))
    }
}

// Indices into SoundIds, in TYPE_NAMES order.
const LOAD_LOCAL: usize = 0;
const LOAD_REMOTE: usize = 1;
const UNLOAD: usize = 2;
const PLAY: usize = 3;
const STOP: usize = 4;
const STATUS: usize = 5;
const LISTENER_POSE: usize = 6;
const LISTENER_VELOCITY: usize = 7;
const POSE: usize = 8;
const VELOCITY: usize = 9;
const DIST_INFO: usize = 10;
const CONE_INFO: usize = 11;
const DOPPLER: usize = 12;
const EQ: usize = 13;
const PITCH: usize = 14;
const VOLUME: usize = 15;
const LOAD_MODEL_LOCAL: usize = 16;
const LOAD_MODEL_REMOTE: usize = 17;
const POLY_QUAD: usize = 18;
const POLY_TRI: usize = 19;
const MATERIAL: usize = 20;
const QUAD_VERTICES: usize = 21;
const TRI_VERTICES: usize = 22;
const POLY_OF: usize = 23;
const POLY_MATERIAL: usize = 24;

/// A request as the server received it.
#[derive(Clone, Debug, PartialEq)]
pub enum SoundRequest {
    /// Load the sound file `file` (on the server's side) as `id`, with its parameters.
    LoadLocal {
        /// The id the client chose.
        id: i32,
        /// Initial parameters.
        def: SoundDef,
        /// The file.
        file: String,
    },
    /// `Load_Remote` (C++ defines no payload and ignores it).
    LoadRemote,
    /// Unload a sound.
    Unload(i32),
    /// Play a sound `repeat` times (0: loop).
    Play {
        /// The sound.
        id: i32,
        /// Times to play; 0 loops.
        repeat: i32,
    },
    /// Stop a sound.
    Stop(i32),
    /// Change all of a sound's parameters.
    Status(Status),
    /// Place the listener.
    ListenerPose(ListenerPose),
    /// The listener's velocity.
    ListenerVelocity(ListenerVelocity),
    /// Place a sound.
    Pose(SoundPose),
    /// A sound's velocity.
    Velocity(SoundVelocity),
    /// A sound's distance limits.
    Distances(DistanceInfo),
    /// A sound's cone.
    Cone(ConeInfo),
    /// A sound's Doppler factor.
    DopplerFactor(SoundValue),
    /// A sound's equalisation value.
    EqValue(SoundValue),
    /// A sound's pitch.
    Pitch(SoundValue),
    /// A sound's volume (gain).
    Volume(SoundValue),
    /// Load the model file `file` (on the server's side).
    LoadModelLocal(String),
    /// `Load_Model_Remote` (C++ defines no payload and ignores it).
    LoadModelRemote,
    /// Add a quadrilateral.
    PolyQuad(PolyQuad),
    /// Add a triangle.
    PolyTri(PolyTri),
    /// Define a material.
    Material(Material),
    /// Move a quadrilateral's vertices.
    QuadVertices(QuadVertices),
    /// Move a triangle's vertices.
    TriVertices(TriVertices),
    /// A polygon's opening factor (`id` is the polygon's tag).
    PolyOpeningFactor(SoundValue),
    /// A polygon's material.
    PolyMaterial(PolyMaterial),
}

impl SoundRequest {
    fn decode(index: usize, p: &[u8]) -> Option<SoundRequest> {
        use SoundRequest as R;
        let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        Some(match index {
            LOAD_LOCAL => {
                let l = LoadSound::decode(p).ok()?;
                R::LoadLocal {
                    id: l.id,
                    def: l.def,
                    file: text(l.file),
                }
            }
            LOAD_REMOTE => R::LoadRemote,
            UNLOAD => R::Unload(SoundId::decode(p).ok()?.id),
            PLAY => {
                let q = Play::decode(p).ok()?;
                R::Play {
                    id: q.id,
                    repeat: q.repeat,
                }
            }
            STOP => R::Stop(SoundId::decode(p).ok()?.id),
            STATUS => R::Status(Status::decode(p).ok()?),
            LISTENER_POSE => R::ListenerPose(ListenerPose::decode(p).ok()?),
            LISTENER_VELOCITY => R::ListenerVelocity(ListenerVelocity::decode(p).ok()?),
            POSE => R::Pose(SoundPose::decode(p).ok()?),
            VELOCITY => R::Velocity(SoundVelocity::decode(p).ok()?),
            DIST_INFO => R::Distances(DistanceInfo::decode(p).ok()?),
            CONE_INFO => R::Cone(ConeInfo::decode(p).ok()?),
            DOPPLER => R::DopplerFactor(SoundValue::decode(p).ok()?),
            EQ => R::EqValue(SoundValue::decode(p).ok()?),
            PITCH => R::Pitch(SoundValue::decode(p).ok()?),
            VOLUME => R::Volume(SoundValue::decode(p).ok()?),
            LOAD_MODEL_LOCAL => R::LoadModelLocal(text(LoadModel::decode(p).ok()?.file)),
            LOAD_MODEL_REMOTE => R::LoadModelRemote,
            POLY_QUAD => R::PolyQuad(PolyQuad::decode(p).ok()?),
            POLY_TRI => R::PolyTri(PolyTri::decode(p).ok()?),
            MATERIAL => R::Material(Material::decode(p).ok()?),
            QUAD_VERTICES => R::QuadVertices(QuadVertices::decode(p).ok()?),
            TRI_VERTICES => R::TriVertices(TriVertices::decode(p).ok()?),
            POLY_OF => R::PolyOpeningFactor(SoundValue::decode(p).ok()?),
            POLY_MATERIAL => R::PolyMaterial(PolyMaterial::decode(p).ok()?),
            _ => return None,
        })
    }
}

/// A request with the time the client stamped on it.
#[derive(Clone, Debug, PartialEq)]
pub struct SoundRequestMsg {
    /// The client's time stamp.
    pub time: TimeVal,
    /// The request.
    pub request: SoundRequest,
}

/// The server half (C++ `vrpn_Sound_Server` without an engine): every request decoded and
/// handed to [`on_request`](Self::on_request) callbacks. It also answers pings and can send
/// text messages ([`send_text`](Self::send_text)), as C++'s does.
pub struct SoundServer {
    conn: Connection,
    base: BaseIds,
    requests: Rc<CallbackList<SoundRequestMsg>>,
    bad: Rc<Cell<u64>>,
}

impl SoundServer {
    /// Registers `device` on `conn`.
    pub fn new(device: &str, conn: &Connection) -> Result<SoundServer, Error> {
        let (base, ids) = base::register_server(conn, device, SoundIds::register)?;
        let requests: Rc<CallbackList<SoundRequestMsg>> = Rc::new(CallbackList::default());
        let bad = Rc::new(Cell::new(0));
        for (index, type_id) in ids.0.iter().enumerate() {
            let (r, b) = (requests.clone(), bad.clone());
            conn.register_handler(*type_id, SenderFilter::Only(base.sender), move |m| {
                match SoundRequest::decode(index, m.payload) {
                    Some(request) => r.call(&SoundRequestMsg {
                        time: m.time,
                        request,
                    }),
                    None => b.set(b.get() + 1),
                }
            });
        }
        Ok(SoundServer {
            conn: conn.clone(),
            base,
            requests,
            bad,
        })
    }

    /// Calls `f` with every request a client sends.
    pub fn on_request(&self, f: impl FnMut(&SoundRequestMsg) + 'static) -> HandlerId {
        self.requests.add(f)
    }

    /// Removes a callback [`on_request`](Self::on_request) returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.requests.remove(id)
    }

    /// Sends a text message (C++ sound servers report failures this way).
    pub fn send_text(&self, severity: crate::TextSeverity, text: &str) -> Result<(), Error> {
        base::send_text(&self.conn, self.base.sender, severity, 0, text)
    }

    /// Requests too short to decode, ignored.
    pub fn bad_messages(&self) -> u64 {
        self.bad.get()
    }
}

/// The client half (C++ `vrpn_Sound_Client`): every request of the protocol, RELIABLE.
pub struct SoundClient {
    core: RemoteCore,
    ids: SoundIds,
}

impl Deref for SoundClient {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

macro_rules! fixed_request {
    ($(#[$doc:meta])* $fn:ident($($arg:ident: $t:ty),*) => $idx:expr, $payload:ident { $($init:tt)* }) => {
        $(#[$doc])*
        pub fn $fn(&self, $($arg: $t),*) -> Result<(), Error> {
            let p = $payload { $($init)* };
            let mut buf = [0u8; $payload::LEN];
            p.encode(&mut buf);
            self.core.send(self.ids.0[$idx], &buf)
        }
    };
}

impl SoundClient {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<SoundClient, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A client for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<SoundClient, Error> {
        let (core, ids) = RemoteCore::new(device, conn, SoundIds::register)?;
        Ok(SoundClient { core, ids })
    }

    /// Asks the server to load its file `file` as sound `id` with the parameters `def`;
    /// returns `id` (C++ `loadSound`). The name is at most 2047 bytes, without NUL.
    pub fn load_sound(&self, file: &str, id: i32, def: &SoundDef) -> Result<i32, Error> {
        check_file(file)?;
        let l = LoadSound {
            id,
            def: *def,
            file: file.as_bytes(),
        };
        let mut buf = vec![0u8; l.encoded_len()];
        l.encode(&mut buf);
        self.core.send(self.ids.0[LOAD_LOCAL], &buf)?;
        Ok(id)
    }

    fixed_request! {
        /// Unloads sound `id`.
        unload_sound(id: i32) => UNLOAD, SoundId { id }
    }

    fixed_request! {
        /// Plays sound `id` `repeat` times (0 loops).
        play_sound(id: i32, repeat: i32) => PLAY, Play { repeat, id }
    }

    fixed_request! {
        /// Stops sound `id`.
        stop_sound(id: i32) => STOP, SoundId { id }
    }

    fixed_request! {
        /// Changes every parameter of sound `id` (a message C++ servers handle but the C++
        /// client never sends).
        set_sound_status(id: i32, repeat: i32, def: &SoundDef) => STATUS, Status { repeat, id, def: *def, pad: [0; 4] }
    }

    fixed_request! {
        /// Sound `id`'s volume (gain).
        set_sound_volume(id: i32, volume: f64) => VOLUME, SoundValue { id, value: volume }
    }

    fixed_request! {
        /// Places sound `id` (orientation x y z w).
        set_sound_pose(id: i32, position: [f64; 3], orientation: [f64; 4]) => POSE, SoundPose { id, orientation, position }
    }

    fixed_request! {
        /// Sound `id`'s velocity (x, y, z and speed).
        set_sound_velocity(id: i32, velocity: [f64; 4]) => VELOCITY, SoundVelocity { id, velocity }
    }

    fixed_request! {
        /// Sound `id`'s distance limits.
        set_sound_distances(id: i32, max_front: f64, min_front: f64, max_back: f64, min_back: f64)
            => DIST_INFO, DistanceInfo { id, max_front, min_front, max_back, min_back }
    }

    fixed_request! {
        /// Sound `id`'s cone.
        set_sound_cone_info(id: i32, inner_angle: f64, outer_angle: f64, gain: f64)
            => CONE_INFO, ConeInfo { id, inner_angle, outer_angle, gain }
    }

    fixed_request! {
        /// Sound `id`'s Doppler factor.
        set_sound_doppler_scale(id: i32, factor: f64) => DOPPLER, SoundValue { id, value: factor }
    }

    fixed_request! {
        /// Sound `id`'s equalisation value.
        set_sound_eq_value(id: i32, value: f64) => EQ, SoundValue { id, value }
    }

    fixed_request! {
        /// Sound `id`'s pitch.
        set_sound_pitch(id: i32, pitch: f64) => PITCH, SoundValue { id, value: pitch }
    }

    fixed_request! {
        /// Places the listener (orientation x y z w).
        set_listener_pose(position: [f64; 3], orientation: [f64; 4]) => LISTENER_POSE, ListenerPose { position, orientation, pad: [0; 32] }
    }

    fixed_request! {
        /// The listener's velocity (x, y, z and speed).
        set_listener_velocity(velocity: [f64; 4]) => LISTENER_VELOCITY, ListenerVelocity { velocity }
    }

    /// Asks the server to load its model file `file`.
    pub fn load_model_local(&self, file: &str) -> Result<(), Error> {
        check_file(file)?;
        let l = LoadModel {
            file: file.as_bytes(),
        };
        let mut buf = vec![0u8; l.encoded_len()];
        l.encode(&mut buf);
        self.core.send(self.ids.0[LOAD_MODEL_LOCAL], &buf)
    }

    fixed_request! {
        /// Adds a quadrilateral to the scene.
        load_poly_quad(quad: &PolyQuad) => POLY_QUAD, PolyQuad { ..*quad }
    }

    fixed_request! {
        /// Adds a triangle to the scene.
        load_poly_tri(tri: &PolyTri) => POLY_TRI, PolyTri { ..*tri }
    }

    fixed_request! {
        /// Defines a material.
        load_material(material: &Material) => MATERIAL, Material { ..*material }
    }

    fixed_request! {
        /// A polygon's opening factor.
        set_poly_opening_factor(tag: i32, factor: f64) => POLY_OF, SoundValue { id: tag, value: factor }
    }

    fixed_request! {
        /// Moves a quadrilateral's vertices.
        set_quad_vertices(tag: i32, vertices: [[f64; 3]; 4]) => QUAD_VERTICES, QuadVertices { tag, vertices }
    }

    fixed_request! {
        /// Moves a triangle's vertices.
        set_tri_vertices(tag: i32, vertices: [[f64; 3]; 3]) => TRI_VERTICES, TriVertices { tag, vertices }
    }

    /// A polygon's material, by name (fewer than 128 bytes).
    pub fn set_poly_material(&self, tag: i32, material: &str) -> Result<(), Error> {
        let material = MaterialName::new(material)
            .map_err(|_| Error::InvalidArgument(format!("material name {material:?} must be shorter than {MATERIAL_NAME_LEN} bytes, without NUL")))?;
        let p = PolyMaterial { tag, material };
        let mut buf = [0u8; PolyMaterial::LEN];
        p.encode(&mut buf);
        self.core.send(self.ids.0[POLY_MATERIAL], &buf)
    }
}

fn check_file(file: &str) -> Result<(), Error> {
    if file.len() > codec::MAX_FILENAME_LEN || file.contains('\0') {
        return Err(Error::InvalidArgument(format!(
            "file name {file:?}: at most {} bytes, without NUL",
            codec::MAX_FILENAME_LEN
        )));
    }
    Ok(())
}
