//! Sound messages (`vrpn_Sound`): a client loads, plays and places sounds, moves the
//! listener and describes the acoustic scene; the server (a sound engine) acts on them. All
//! messages go client->server.
//!
//! The C++ client sizes several payloads with `sizeof` of its structs, which include padding
//! (x86-64 values): those payloads end in filler bytes the server never reads. The encoders
//! here reproduce the lengths with zero filler, so a C++ server reads them exactly as it
//! reads its own client's; the decoders need only the bytes that carry values.

use super::super::{need, Result};
use super::fixed_text::FixedText;
use super::Field;

/// Load a sound file on the server's side ([`LoadSound`]).
pub const LOAD_LOCAL: &str = "vrpn_Sound Load_Local";
/// Send a sound file's contents (never implemented by C++: no payload).
pub const LOAD_REMOTE: &str = "vrpn_Sound Load_Remote";
/// Unload a sound, 4 bytes ([`SoundId`]).
pub const UNLOAD: &str = "vrpn_Sound Unload";
/// Play a sound, 8 bytes ([`Play`]).
pub const PLAY: &str = "vrpn_Sound Play";
/// Stop a sound, 4 bytes ([`SoundId`]).
pub const STOP: &str = "vrpn_Sound Stop";
/// Change all of a sound's parameters, 184 bytes ([`Status`]).
pub const STATUS: &str = "vrpn_Sound Status";
/// Place the listener, 88 bytes ([`ListenerPose`]).
pub const LISTENER_POSE: &str = "vrpn_Sound Listener_Pose";
/// The listener's velocity, 32 bytes ([`ListenerVelocity`]).
pub const LISTENER_VELOCITY: &str = "vrpn_Sound Listener_Velocity";
/// Place a sound, 60 bytes ([`SoundPose`]).
pub const POSE: &str = "vrpn_Sound Pose";
/// A sound's velocity, 36 bytes ([`SoundVelocity`]).
pub const VELOCITY: &str = "vrpn_Sound Velocity";
/// A sound's distance limits, 36 bytes ([`DistanceInfo`]).
pub const DIST_INFO: &str = "vrpn_Sound DistInfo";
/// A sound's cone, 28 bytes ([`ConeInfo`]).
pub const CONE_INFO: &str = "vrpn_Sound ConeInfo";
/// A sound's Doppler factor, 12 bytes ([`SoundValue`]).
pub const DOPPLER_FACTOR: &str = "vrpn_Sound DopFac";
/// A sound's equalisation value, 12 bytes ([`SoundValue`]).
pub const EQ_VALUE: &str = "vrpn_Sound EqVal";
/// A sound's pitch, 12 bytes ([`SoundValue`]).
pub const PITCH: &str = "vrpn_Sound Pitch";
/// A sound's volume (gain), 12 bytes ([`SoundValue`]).
pub const VOLUME: &str = "vrpn_Sound Volume";
/// Load a model file on the server's side ([`LoadModel`]).
pub const LOAD_MODEL_LOCAL: &str = "vrpn_Sound Load_Model_Local";
/// Send a model (never implemented by C++: no payload).
pub const LOAD_MODEL_REMOTE: &str = "vrpn_Sound Load_Model_Remote";
/// Add a quadrilateral to the scene, 248 bytes ([`PolyQuad`]).
pub const LOAD_POLY_QUAD: &str = "vrpn_Sound Load_Poly_Quad";
/// Add a triangle to the scene, 228 bytes ([`PolyTri`]).
pub const LOAD_POLY_TRI: &str = "vrpn_Sound Load_Poly_Tri";
/// Define a material, 164 bytes ([`Material`]).
pub const LOAD_MATERIAL: &str = "vrpn_Sound Load_Material";
/// Move a quadrilateral's vertices, 100 bytes ([`QuadVertices`]).
pub const QUAD_VERTICES: &str = "vrpn_Sound Quad_Vertices";
/// Move a triangle's vertices, 76 bytes ([`TriVertices`]).
pub const TRI_VERTICES: &str = "vrpn_Sound Tri_Vertices";
/// A polygon's opening factor, 12 bytes ([`SoundValue`], the id being the polygon's tag).
pub const POLY_OPENING_FACTOR: &str = "vrpn_Sound Poly_OF";
/// A polygon's material, 132 bytes ([`PolyMaterial`]).
pub const POLY_MATERIAL: &str = "vrpn_Sound Poly_Material";

/// The sound type names in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[
    LOAD_LOCAL,
    LOAD_REMOTE,
    UNLOAD,
    PLAY,
    STOP,
    STATUS,
    LISTENER_POSE,
    LISTENER_VELOCITY,
    POSE,
    VELOCITY,
    DIST_INFO,
    CONE_INFO,
    DOPPLER_FACTOR,
    EQ_VALUE,
    PITCH,
    VOLUME,
    LOAD_MODEL_LOCAL,
    LOAD_MODEL_REMOTE,
    LOAD_POLY_QUAD,
    LOAD_POLY_TRI,
    LOAD_MATERIAL,
    QUAD_VERTICES,
    TRI_VERTICES,
    POLY_OPENING_FACTOR,
    POLY_MATERIAL,
];

/// Bytes of a material name field (`MAX_MATERIAL_NAME_LENGTH`).
pub const MATERIAL_NAME_LEN: usize = 128;
/// A material name as on the wire.
pub type MaterialName = FixedText<MATERIAL_NAME_LEN>;

/// Longest file name a C++ server accepts (`MAX_FILENAME_LENGTH` less the NUL).
pub const MAX_FILENAME_LEN: usize = 2047;

fixed_payload! {
    /// A sound's parameters (`vrpn_SoundDef`), 172 bytes on the wire: position, orientation
    /// (x, y, z, w), velocity (x, y, z and a fourth value, speed), volume as f32, then
    /// distances, cone, Doppler scale, equalisation and pitch as f64.
    pub struct SoundDef: at_least {
        /// Position.
        pub position: [f64; 3],
        /// Orientation quaternion, x y z w.
        pub orientation: [f64; 4],
        /// Velocity.
        pub velocity: [f64; 4],
        /// Gain (C++ calls it volume).
        pub volume: f32,
        /// Farthest distance behind.
        pub max_back_dist: f64,
        /// Nearest distance behind.
        pub min_back_dist: f64,
        /// Farthest distance in front.
        pub max_front_dist: f64,
        /// Nearest distance in front.
        pub min_front_dist: f64,
        /// Inner cone angle.
        pub cone_inner_angle: f64,
        /// Outer cone angle.
        pub cone_outer_angle: f64,
        /// Gain outside the cone.
        pub cone_gain: f64,
        /// Doppler scale.
        pub doppler_scale: f64,
        /// Equalisation.
        pub equalization: f64,
        /// Pitch.
        pub pitch: f64,
    }
}

impl Field for SoundDef {
    const SIZE: usize = SoundDef::LEN;
    fn read(buf: &[u8]) -> Self {
        SoundDef::decode(buf).unwrap_or_default()
    }
    fn write(&self, buf: &mut [u8]) {
        self.encode(buf);
    }
}

fixed_payload! {
    /// `Unload` and `Stop`: the sound's id. At least 4 bytes.
    pub struct SoundId: at_least {
        /// The id the client gave the sound when loading it.
        pub id: i32,
    }
}

fixed_payload! {
    /// `Play` as the C++ client sends it: repeat count (0: loop forever), then the id. At
    /// least 8 bytes (the C++ server reads a whole [`Status`] there, filled with whatever
    /// follows in its buffer; see [`Status`]).
    pub struct Play: at_least {
        /// Times to play; 0 loops.
        pub repeat: i32,
        /// The sound.
        pub id: i32,
    }
}

fixed_payload! {
    /// `Status`: repeat, id and every parameter, then 4 filler bytes (184 bytes).
    pub struct Status: at_least {
        /// Repeat count.
        pub repeat: i32,
        /// The sound.
        pub id: i32,
        /// Its parameters.
        pub def: SoundDef,
        /// Filler (`sizeof` padding).
        pub pad: [u8; 4],
    }
}

fixed_payload! {
    /// `Listener_Pose`: position, then orientation (x, y, z, w), then 32 filler bytes (C++
    /// sizes it as a pose and a velocity): 88 bytes.
    pub struct ListenerPose: at_least {
        /// Position.
        pub position: [f64; 3],
        /// Orientation, x y z w.
        pub orientation: [f64; 4],
        /// Filler.
        pub pad: [u8; 32],
    }
}

fixed_payload! {
    /// `Listener_Velocity`: four f64. 32 bytes.
    pub struct ListenerVelocity: at_least {
        /// Velocity x, y, z and speed.
        pub velocity: [f64; 4],
    }
}

fixed_payload! {
    /// `Pose`: the id, then the orientation (x, y, z, w) **before** the position. 60 bytes.
    pub struct SoundPose: at_least {
        /// The sound.
        pub id: i32,
        /// Orientation, x y z w.
        pub orientation: [f64; 4],
        /// Position.
        pub position: [f64; 3],
    }
}

fixed_payload! {
    /// `Velocity`: the id and four f64. 36 bytes.
    pub struct SoundVelocity: at_least {
        /// The sound.
        pub id: i32,
        /// Velocity x, y, z and speed.
        pub velocity: [f64; 4],
    }
}

fixed_payload! {
    /// `DistInfo` in the order the C++ client writes it (its `setSoundDistances`): farthest
    /// front, nearest front, farthest back, nearest back. (The C++ server's decoder names
    /// the four slots min back, max back, min front, max front; only the order is on the
    /// wire.) 36 bytes.
    pub struct DistanceInfo: at_least {
        /// The sound.
        pub id: i32,
        /// Farthest distance in front.
        pub max_front: f64,
        /// Nearest distance in front.
        pub min_front: f64,
        /// Farthest distance behind.
        pub max_back: f64,
        /// Nearest distance behind.
        pub min_back: f64,
    }
}

fixed_payload! {
    /// `ConeInfo`: id, inner angle, outer angle, gain outside. 28 bytes.
    pub struct ConeInfo: at_least {
        /// The sound.
        pub id: i32,
        /// Inner angle.
        pub inner_angle: f64,
        /// Outer angle.
        pub outer_angle: f64,
        /// Gain outside the cone.
        pub gain: f64,
    }
}

fixed_payload! {
    /// `DopFac`, `EqVal`, `Pitch`, `Volume` (sound id) and `Poly_OF` (polygon tag): an id
    /// and one f64. 12 bytes.
    pub struct SoundValue: at_least {
        /// The sound (or polygon tag).
        pub id: i32,
        /// The value.
        pub value: f64,
    }
}

fixed_payload! {
    /// `Load_Poly_Quad`: 240 bytes of values and 8 filler bytes (248).
    pub struct PolyQuad: at_least {
        /// Whether it is a sub-quad (a boolean).
        pub sub_quad: i32,
        /// Opening factor.
        pub opening_factor: f64,
        /// The polygon's tag (its id in later messages).
        pub tag: i32,
        /// Four vertices.
        pub vertices: [[f64; 3]; 4],
        /// Its material.
        pub material: MaterialName,
        /// Filler.
        pub pad: [u8; 8],
    }
}

fixed_payload! {
    /// `Load_Poly_Tri`: 216 bytes of values and 12 filler bytes (228).
    pub struct PolyTri: at_least {
        /// Whether it is a sub-triangle (a boolean).
        pub sub_tri: i32,
        /// Opening factor.
        pub opening_factor: f64,
        /// The polygon's tag.
        pub tag: i32,
        /// Three vertices.
        pub vertices: [[f64; 3]; 3],
        /// Its material.
        pub material: MaterialName,
        /// Filler.
        pub pad: [u8; 12],
    }
}

fixed_payload! {
    /// `Load_Material`: id, name, transmittance gain and high-frequency, reflectance gain
    /// and high-frequency. 164 bytes.
    pub struct Material: at_least {
        /// The material's id.
        pub id: i32,
        /// Its name (polygons refer to it by name).
        pub name: MaterialName,
        /// Transmittance gain.
        pub transmittance_gain: f64,
        /// Transmittance high-frequency.
        pub transmittance_highfreq: f64,
        /// Reflectance gain.
        pub reflectance_gain: f64,
        /// Reflectance high-frequency.
        pub reflectance_highfreq: f64,
    }
}

fixed_payload! {
    /// `Quad_Vertices`: the polygon's tag and four vertices. 100 bytes.
    pub struct QuadVertices: at_least {
        /// The polygon's tag.
        pub tag: i32,
        /// Four vertices.
        pub vertices: [[f64; 3]; 4],
    }
}

fixed_payload! {
    /// `Tri_Vertices`: the polygon's tag and three vertices. 76 bytes.
    pub struct TriVertices: at_least {
        /// The polygon's tag.
        pub tag: i32,
        /// Three vertices.
        pub vertices: [[f64; 3]; 3],
    }
}

fixed_payload! {
    /// `Poly_Material`: the polygon's tag and a material name. 132 bytes.
    pub struct PolyMaterial: at_least {
        /// The polygon's tag.
        pub tag: i32,
        /// The material's name.
        pub material: MaterialName,
    }
}

/// `Load_Local`: id, [`SoundDef`], the file name NUL-terminated, then 4 filler bytes (the
/// C++ client counts `sizeof(vrpn_SoundDef)`, 176, for the 172 bytes it writes; its server
/// reads the name from byte 176 up to 4 bytes before the end).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadSound<'a> {
    /// The id the client gives the sound.
    pub id: i32,
    /// Its initial parameters.
    pub def: SoundDef,
    /// The file on the server's side.
    pub file: &'a [u8],
}

/// Offset of the file name in `Load_Local`.
const LOAD_FILE_OFFSET: usize = 4 + SoundDef::LEN;

impl<'a> LoadSound<'a> {
    /// Decodes the payload; the name runs to its NUL or to the end.
    pub fn decode(buf: &'a [u8]) -> Result<LoadSound<'a>> {
        need(buf, LOAD_FILE_OFFSET)?;
        let rest = &buf[LOAD_FILE_OFFSET..];
        let n = rest.iter().position(|&b| b == 0).unwrap_or(rest.len());
        Ok(LoadSound {
            id: i32::read(buf),
            def: SoundDef::read(&buf[4..]),
            file: &rest[..n],
        })
    }

    /// Payload length as the C++ client computes it.
    pub fn encoded_len(&self) -> usize {
        LOAD_FILE_OFFSET + self.file.len() + 1 + 4
    }

    /// Writes the payload (zero filler) at the start of `out`.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let len = self.encoded_len();
        out[..len].fill(0);
        self.id.write(out);
        self.def.encode(&mut out[4..]);
        out[LOAD_FILE_OFFSET..LOAD_FILE_OFFSET + self.file.len()].copy_from_slice(self.file);
        len
    }
}

/// `Load_Model_Local`: the file name NUL-terminated and 4 filler bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadModel<'a> {
    /// The model file on the server's side.
    pub file: &'a [u8],
}

impl<'a> LoadModel<'a> {
    /// Decodes the payload; the name runs to its NUL or to the end.
    pub fn decode(buf: &'a [u8]) -> Result<LoadModel<'a>> {
        let n = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
        Ok(LoadModel { file: &buf[..n] })
    }

    /// Payload length as the C++ client computes it.
    pub fn encoded_len(&self) -> usize {
        self.file.len() + 1 + 4
    }

    /// Writes the payload (zero filler) at the start of `out`.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let len = self.encoded_len();
        out[..len].fill(0);
        out[..self.file.len()].copy_from_slice(self.file);
        len
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn lengths_match_the_cpp_client() {
        assert_eq!(SoundDef::LEN, 172);
        assert_eq!(Status::LEN, 184);
        assert_eq!(ListenerPose::LEN, 88);
        assert_eq!(ListenerVelocity::LEN, 32);
        assert_eq!(SoundPose::LEN, 60);
        assert_eq!(SoundVelocity::LEN, 36);
        assert_eq!(DistanceInfo::LEN, 36);
        assert_eq!(ConeInfo::LEN, 28);
        assert_eq!(SoundValue::LEN, 12);
        assert_eq!(PolyQuad::LEN, 248);
        assert_eq!(PolyTri::LEN, 228);
        assert_eq!(Material::LEN, 164);
        assert_eq!(QuadVertices::LEN, 100);
        assert_eq!(TriVertices::LEN, 76);
        assert_eq!(PolyMaterial::LEN, 132);
        assert_eq!(Play::LEN, 8);
    }

    #[test]
    fn layouts() {
        let b = round_trip!(Play, Play { repeat: 0, id: 3 });
        assert_eq!(b, hex("00000000 00000003"));
        let b = round_trip!(
            SoundPose,
            SoundPose {
                id: 1,
                orientation: [0.0, 0.0, 0.0, 1.0],
                position: [2.0, 0.0, 0.0]
            }
        );
        // Orientation first, then position.
        assert_eq!(&b[..4], &hex("00000001")[..]);
        assert_eq!(&b[28..36], &hex("3ff0000000000000")[..]);
        assert_eq!(&b[36..44], &hex("4000000000000000")[..]);
        let b = round_trip!(
            DistanceInfo,
            DistanceInfo {
                id: 2,
                max_front: 1.0,
                min_front: 2.0,
                max_back: 3.0,
                min_back: 4.0
            }
        );
        assert_eq!(&b[4..12], &hex("3ff0000000000000")[..]);
        assert_eq!(&b[28..36], &hex("4010000000000000")[..]);
        let b = round_trip!(SoundValue, SoundValue { id: 5, value: 0.5 });
        assert_eq!(b, hex("00000005 3fe0000000000000"));
        let def = SoundDef {
            volume: 0.5,
            pitch: 2.0,
            ..SoundDef::default()
        };
        let b = round_trip!(SoundDef, def);
        // volume is an f32 at byte 88, pitch the last f64.
        assert_eq!(&b[88..92], &hex("3f000000")[..]);
        assert_eq!(&b[164..172], &hex("4000000000000000")[..]);
        let m = Material {
            id: 1,
            name: MaterialName::new("wood").unwrap(),
            transmittance_gain: 0.25,
            ..Material::default()
        };
        let b = round_trip!(Material, m);
        assert_eq!(&b[4..9], b"wood\0");
        assert_eq!(&b[132..140], &hex("3fd0000000000000")[..]);
    }

    #[test]
    fn file_name_messages() {
        let l = LoadSound {
            id: 7,
            def: SoundDef::default(),
            file: b"boom.wav",
        };
        let mut buf = [0xAAu8; 300];
        let n = l.encode(&mut buf);
        // C++: sizeof(id) + strlen + sizeof(vrpn_SoundDef) (176 on x86-64) + 1.
        assert_eq!(n, 4 + 8 + 176 + 1);
        assert_eq!(&buf[176..185], b"boom.wav\0");
        assert_eq!(&buf[185..n], &[0, 0, 0, 0]);
        assert_eq!(LoadSound::decode(&buf[..n]).unwrap(), l);
        assert!(LoadSound::decode(&buf[..175]).is_err());
        let m = LoadModel { file: b"room.obj" };
        let n = m.encode(&mut buf);
        assert_eq!(n, 8 + 1 + 4);
        assert_eq!(LoadModel::decode(&buf[..n]).unwrap(), m);
    }
}
