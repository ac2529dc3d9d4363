//! ForceDevice messages: forces and contact points from the server; surfaces,
//! force fields, constraints, effects and trimesh scene edits from the client.
//!
//! Every C++ decode helper checks its length exactly, so every fixed layout here decodes with
//! an exact length. The exception is `Custom Effect`, which needs at least 8 + 4·n bytes.
//! The scene-edit and constraint messages carry `f32` values; Force and SCP carry `f64`.

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};

/// Force at the end effector, server->client, 24 bytes ([`Force`]).
pub const FORCE: &str = "vrpn_ForceDevice Force";
/// Linear force field, client->server, 64 bytes ([`ForceField`]).
pub const FORCE_FIELD: &str = "vrpn_ForceDevice Force_Field";
/// Surface plane, client->server, 40 bytes ([`Plane`]).
pub const PLANE: &str = "vrpn_ForceDevice Plane";
/// Extra surface properties, client->server, 24 bytes ([`Plane2`]).
pub const PLANE2: &str = "vrpn_ForceDevice Plane2";
/// Add a scene object, 8 bytes ([`AddObject`]).
pub const ADD_OBJECT: &str = "vrpn_ForceDevice addObject";
/// Add an object outside the scene, 4 bytes ([`ObjectId`]).
pub const ADD_OBJECT_EX_SCENE: &str = "vrpn_ForceDevice addObjectExScene";
/// Re-parent an object, 8 bytes ([`AddObject`] layout).
pub const MOVE_TO_PARENT: &str = "vrpn_ForceDevice moveToParent";
/// Object position, 16 bytes ([`ObjectVec3`]).
pub const SET_OBJECT_POSITION: &str = "vrpn_ForceDevice setObjectPosition";
/// Object orientation as axis and angle, 20 bytes ([`ObjectOrientation`]).
pub const SET_OBJECT_ORIENTATION: &str = "vrpn_ForceDevice setObjectOrientation";
/// Object scale, 16 bytes ([`ObjectVec3`]).
pub const SET_OBJECT_SCALE: &str = "vrpn_ForceDevice setObjectScale";
/// Remove an object, 4 bytes ([`ObjectId`]).
pub const REMOVE_OBJECT: &str = "vrpn_ForceDevice removeObject";
/// Trimesh vertex, 20 bytes ([`IndexedVec3`]).
pub const SET_VERTEX: &str = "vrpn_ForceDevice setVertex";
/// Trimesh normal, 20 bytes ([`IndexedVec3`]).
pub const SET_NORMAL: &str = "vrpn_ForceDevice setNormal";
/// Trimesh triangle, 32 bytes ([`SetTriangle`]).
pub const SET_TRIANGLE: &str = "vrpn_ForceDevice setTriangle";
/// Remove a triangle, 8 bytes ([`RemoveTriangle`]).
pub const REMOVE_TRIANGLE: &str = "vrpn_ForceDevice removeTriangle";
/// Trimesh surface parameters, 20 bytes ([`UpdateTrimeshChanges`]).
pub const UPDATE_TRIMESH_CHANGES: &str = "vrpn_ForceDevice updateTrimeshChanges";
/// Trimesh transform matrix, 68 bytes ([`TransformTrimesh`]).
pub const TRANSFORM_TRIMESH: &str = "vrpn_ForceDevice transformTrimesh";
/// Trimesh collision type, 8 bytes ([`SetTrimeshType`]).
pub const SET_TRIMESH_TYPE: &str = "vrpn_ForceDevice setTrimeshType";
/// Clear a trimesh, 4 bytes ([`ObjectId`]).
pub const CLEAR_TRIMESH: &str = "vrpn_ForceDevice clearTrimesh";
/// Haptic origin, 28 bytes ([`Origin`]).
pub const SET_HAPTIC_ORIGIN: &str = "vrpn_ForceDevice setHapticOrigin";
/// Haptic scale, 4 bytes ([`HapticScale`]).
pub const SET_HAPTIC_SCALE: &str = "vrpn_ForceDevice setHapticScale";
/// Scene origin, 28 bytes ([`Origin`]).
pub const SET_SCENE_ORIGIN: &str = "vrpn_ForceDevice setSceneOrigin";
/// Registered by C++ but never sent (ids are allocated client-side).
pub const GET_NEW_OBJECT_ID: &str = "vrpn_ForceDevice getNewObjectID";
/// Object touchability, 6 bytes ([`SetObjectIsTouchable`]).
pub const SET_OBJECT_IS_TOUCHABLE: &str = "vrpn_ForceDevice setObjectIsTouchable";
/// Surface contact point, server->client, 56 bytes ([`Scp`]).
pub const SCP: &str = "vrpn_ForceDevice SCP";
/// Device error, server->client, 4 bytes ([`ForceError`]).
pub const FORCE_ERROR: &str = "vrpn_ForceDevice Force_Error";
/// Constraint on/off, 4 bytes ([`ConstraintInt`]); not sent by the 07.x remote.
pub const CONSTRAINT_ENABLE: &str = "vrpn_ForceDevice constraint_enable";
/// Constraint mode, 4 bytes ([`ConstraintInt`]).
pub const CONSTRAINT_MODE: &str = "vrpn_ForceDevice constraint_mode";
/// Constraint point, 12 bytes ([`ConstraintVec3`]).
pub const CONSTRAINT_POINT: &str = "vrpn_ForceDevice constraint_point";
/// Constraint line point, 12 bytes ([`ConstraintVec3`]).
pub const CONSTRAINT_LINEPT: &str = "vrpn_ForceDevice constraint_linept";
/// Constraint line direction, 12 bytes ([`ConstraintVec3`]).
pub const CONSTRAINT_LINEDIR: &str = "vrpn_ForceDevice constraint_linedir";
/// Constraint plane point, 12 bytes ([`ConstraintVec3`]).
pub const CONSTRAINT_PLPT: &str = "vrpn_ForceDevice constraint_plpt";
/// Constraint plane normal, 12 bytes ([`ConstraintVec3`]).
pub const CONSTRAINT_PLNORM: &str = "vrpn_ForceDevice constraint_plnorm";
/// Constraint spring constant, 4 bytes ([`ConstraintKSpring`]).
pub const CONSTRAINT_KSPRING: &str = "vrpn_ForceDevice constraint_KSpring";
/// Custom effect, 8 + 4·n bytes ([`CustomEffect`]).
pub const CUSTOM_EFFECT: &str = "vrpn_ForceDevice Custom Effect";

/// All 35 ForceDevice type names in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[
    FORCE,
    FORCE_FIELD,
    PLANE,
    PLANE2,
    ADD_OBJECT,
    ADD_OBJECT_EX_SCENE,
    MOVE_TO_PARENT,
    SET_OBJECT_POSITION,
    SET_OBJECT_ORIENTATION,
    SET_OBJECT_SCALE,
    REMOVE_OBJECT,
    SET_VERTEX,
    SET_NORMAL,
    SET_TRIANGLE,
    REMOVE_TRIANGLE,
    UPDATE_TRIMESH_CHANGES,
    TRANSFORM_TRIMESH,
    SET_TRIMESH_TYPE,
    CLEAR_TRIMESH,
    SET_HAPTIC_ORIGIN,
    SET_HAPTIC_SCALE,
    SET_SCENE_ORIGIN,
    GET_NEW_OBJECT_ID,
    SET_OBJECT_IS_TOUCHABLE,
    SCP,
    FORCE_ERROR,
    CONSTRAINT_ENABLE,
    CONSTRAINT_MODE,
    CONSTRAINT_POINT,
    CONSTRAINT_LINEPT,
    CONSTRAINT_LINEDIR,
    CONSTRAINT_PLPT,
    CONSTRAINT_PLNORM,
    CONSTRAINT_KSPRING,
    CUSTOM_EFFECT,
];

/// Force_Error code: a surface parameter was out of range.
pub const FD_VALUE_OUT_OF_RANGE: i32 = 0;
/// Force_Error code: the servo loop overran.
pub const FD_DUTY_CYCLE_ERROR: i32 = 1;
/// Force_Error code: maximum force exceeded, overheating or amplifiers off.
pub const FD_FORCE_ERROR: i32 = 2;
/// Force_Error code: anything else.
pub const FD_MISC_ERROR: i32 = 3;
/// Force_Error code: no error.
pub const FD_OK: i32 = 4;

/// Number of surface planes a server keeps (`MAXPLANE`).
pub const MAX_PLANES: i32 = 4;

/// setTrimeshType: GHOST collision.
pub const TRIMESH_GHOST: i32 = 0;
/// setTrimeshType: HCOLLIDE collision.
pub const TRIMESH_HCOLLIDE: i32 = 1;

/// Constraint mode: none.
pub const CONSTRAINT_MODE_NONE: i32 = 0;
/// Constraint mode: point.
pub const CONSTRAINT_MODE_POINT: i32 = 1;
/// Constraint mode: line.
pub const CONSTRAINT_MODE_LINE: i32 = 2;
/// Constraint mode: plane.
pub const CONSTRAINT_MODE_PLANE: i32 = 3;

/// Custom effect id that stops the running effect (sent with no parameters).
pub const STOP_EFFECT_ID: u32 = 0xFFFF_FFFF;

fixed_payload! {
    /// `vrpn_ForceDevice Force`: the force the device applies. Exact length 24.
    pub struct Force: exact {
        /// Force `[x, y, z]` in device units.
        pub force: [f64; 3],
    }
}

fixed_payload! {
    /// `vrpn_ForceDevice SCP`: surface contact point. Exact length 56.
    pub struct Scp: exact {
        /// Contact point `[x, y, z]`.
        pub pos: [f64; 3],
        /// Orientation `[x, y, z, w]` (identity from the Phantom).
        pub quat: [f64; 4],
    }
}

fixed_payload! {
    /// `vrpn_ForceDevice Force_Error`: an `FD_*` code. Exact length 4.
    pub struct ForceError: exact {
        /// One of [`FD_VALUE_OUT_OF_RANGE`] ... [`FD_OK`].
        pub code: i32,
    }
}

fixed_payload! {
    /// `vrpn_ForceDevice Plane`: a surface plane and its material. Exact length 40.
    ///
    /// Note the wire order: dynamic friction before static friction.
    pub struct Plane: exact {
        /// Plane equation `[a, b, c, d]` with a·x + b·y + c·z + d = 0.
        pub plane: [f32; 4],
        /// Surface spring constant.
        pub kspring: f32,
        /// Damping.
        pub kdamp: f32,
        /// Dynamic friction.
        pub fdyn: f32,
        /// Static friction.
        pub fstat: f32,
        /// Plane index, `0..MAX_PLANES`.
        pub plane_index: i32,
        /// Number of recovery cycles.
        pub recovery_cycles: i32,
    }
}

fixed_payload! {
    /// `vrpn_ForceDevice Plane2`: extra surface properties. Exact length 24.
    pub struct Plane2: exact {
        /// Normal adhesion.
        pub normal_adhesion: f32,
        /// Lateral adhesion.
        pub lateral_adhesion: f32,
        /// Texture amplitude.
        pub texture_amplitude: f32,
        /// Texture wavelength.
        pub texture_wavelength: f32,
        /// Buzz amplitude.
        pub buzz_amplitude: f32,
        /// Buzz frequency.
        pub buzz_frequency: f32,
    }
}

fixed_payload! {
    /// `vrpn_ForceDevice Force_Field`: a force linear in position. Exact length 64.
    /// All zeros stops the field.
    pub struct ForceField: exact {
        /// Field origin `[x, y, z]` in metres.
        pub origin: [f32; 3],
        /// Force at the origin.
        pub force: [f32; 3],
        /// Jacobian, row-major: `jacobian[i][j]` = dF_i/dx_j.
        pub jacobian: [[f32; 3]; 3],
        /// Radius beyond which the field is off, in metres.
        pub radius: f32,
    }
}

fixed_payload! {
    /// `addObject` and `moveToParent`: an object and its parent. Exact length 8.
    pub struct AddObject: exact {
        /// Object number.
        pub obj: i32,
        /// Parent object number, -1 for the root.
        pub parent: i32,
    }
}

fixed_payload! {
    /// `addObjectExScene`, `removeObject` and `clearTrimesh`: one object number. Exact length 4.
    pub struct ObjectId: exact {
        /// Object number.
        pub obj: i32,
    }
}

fixed_payload! {
    /// `setObjectPosition` and `setObjectScale`: object number and a vector. Exact length 16.
    pub struct ObjectVec3: exact {
        /// Object number.
        pub obj: i32,
        /// Position or scale `[x, y, z]`.
        pub v: [f32; 3],
    }
}

fixed_payload! {
    /// `setObjectOrientation`: object number, rotation axis and angle. Exact length 20.
    pub struct ObjectOrientation: exact {
        /// Object number.
        pub obj: i32,
        /// Rotation axis `[x, y, z]`.
        pub axis: [f32; 3],
        /// Rotation angle.
        pub angle: f32,
    }
}

fixed_payload! {
    /// `setVertex` and `setNormal`: object, element index and a vector. Exact length 20.
    pub struct IndexedVec3: exact {
        /// Object number (0 for the single-object calls).
        pub obj: i32,
        /// Vertex or normal index.
        pub index: i32,
        /// Vertex position or normal `[x, y, z]`.
        pub v: [f32; 3],
    }
}

fixed_payload! {
    /// `setTriangle`: a triangle's vertices and normals. Exact length 32.
    pub struct SetTriangle: exact {
        /// Object number.
        pub obj: i32,
        /// Triangle index.
        pub index: i32,
        /// Vertex indices.
        pub vertices: [i32; 3],
        /// Normal indices (-1 when not given).
        pub normals: [i32; 3],
    }
}

fixed_payload! {
    /// `removeTriangle`: object and triangle index. Exact length 8.
    pub struct RemoveTriangle: exact {
        /// Object number.
        pub obj: i32,
        /// Triangle index.
        pub index: i32,
    }
}

fixed_payload! {
    /// `updateTrimeshChanges`: trimesh material. Exact length 20.
    ///
    /// Static friction comes before dynamic friction here (the opposite of [`Plane`]).
    pub struct UpdateTrimeshChanges: exact {
        /// Object number.
        pub obj: i32,
        /// Spring constant.
        pub kspring: f32,
        /// Damping.
        pub kdamp: f32,
        /// Static friction.
        pub fstat: f32,
        /// Dynamic friction.
        pub fdyn: f32,
    }
}

fixed_payload! {
    /// `transformTrimesh`: a homogeneous matrix, row-major. Exact length 68.
    pub struct TransformTrimesh: exact {
        /// Object number.
        pub obj: i32,
        /// 4×4 matrix, row-major.
        pub matrix: [f32; 16],
    }
}

fixed_payload! {
    /// `setTrimeshType`: collision type. Exact length 8.
    pub struct SetTrimeshType: exact {
        /// Object number (-1 from the remote's useGhost/useHcollide).
        pub obj: i32,
        /// [`TRIMESH_GHOST`] or [`TRIMESH_HCOLLIDE`].
        pub kind: i32,
    }
}

fixed_payload! {
    /// `setHapticOrigin` and `setSceneOrigin`: position plus axis-angle. Exact length 28.
    pub struct Origin: exact {
        /// Position `[x, y, z]`.
        pub pos: [f32; 3],
        /// Rotation axis `[x, y, z]`.
        pub axis: [f32; 3],
        /// Rotation angle.
        pub angle: f32,
    }
}

fixed_payload! {
    /// `setHapticScale`: one scale factor. Exact length 4.
    pub struct HapticScale: exact {
        /// Scale factor.
        pub scale: f32,
    }
}

fixed_payload! {
    /// `setObjectIsTouchable`: object number and an i16 flag. Exact length 6.
    pub struct SetObjectIsTouchable: exact {
        /// Object number.
        pub obj: i32,
        /// Non-zero when touchable (`vrpn_bool`, 2 bytes).
        pub touchable: i16,
    }
}

fixed_payload! {
    /// `constraint_enable` and `constraint_mode`: one i32. Exact length 4.
    pub struct ConstraintInt: exact {
        /// Enable flag (0 disables) or a `CONSTRAINT_MODE_*` value.
        pub value: i32,
    }
}

fixed_payload! {
    /// `constraint_point`, `_linept`, `_linedir`, `_plpt`, `_plnorm`: a vector. Exact length 12.
    pub struct ConstraintVec3: exact {
        /// The point or direction `[x, y, z]`.
        pub v: [f32; 3],
    }
}

fixed_payload! {
    /// `constraint_KSpring`: the spring constant. Exact length 4.
    pub struct ConstraintKSpring: exact {
        /// Spring constant.
        pub k: f32,
    }
}

/// `vrpn_ForceDevice Custom Effect`: u32 effect id, u32 n, n × f32 parameters.
///
/// Borrows the parameter bytes from the payload (n is only bounded by the message size).
/// Decoding needs at least 8 + 4·n bytes, as the C++ receiver does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CustomEffect<'a> {
    /// Effect id; [`STOP_EFFECT_ID`] stops the effect.
    pub effect_id: u32,
    params: &'a [u8],
}

impl<'a> CustomEffect<'a> {
    /// Payload length for `n` parameters.
    pub const fn len_for(n: usize) -> usize {
        8 + 4 * n
    }

    /// Decodes a payload.
    pub fn decode(buf: &'a [u8]) -> Result<CustomEffect<'a>> {
        need(buf, 8)?;
        let n = BigEndian::read_u32(&buf[4..8]) as usize;
        let len = n
            .checked_mul(4)
            .and_then(|b| b.checked_add(8))
            .ok_or(WireError::BadValue("custom effect parameter count"))?;
        need(buf, len)?;
        Ok(CustomEffect {
            effect_id: BigEndian::read_u32(&buf[0..4]),
            params: &buf[8..len],
        })
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len() / 4
    }

    /// True when the effect has no parameters.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// Parameter `i`, if present.
    pub fn param(&self, i: usize) -> Option<f32> {
        self.params.get(i * 4..i * 4 + 4).map(BigEndian::read_f32)
    }

    /// The parameters in order.
    pub fn params(&self) -> impl Iterator<Item = f32> + 'a {
        self.params.chunks_exact(4).map(BigEndian::read_f32)
    }

    /// Payload length of this effect.
    pub fn encoded_len(&self) -> usize {
        Self::len_for(self.len())
    }

    /// Re-encodes the decoded effect into `out` (at least [`Self::encoded_len`] bytes).
    pub fn encode(&self, out: &mut [u8]) -> usize {
        let len = self.encoded_len();
        BigEndian::write_u32(&mut out[0..4], self.effect_id);
        BigEndian::write_u32(&mut out[4..8], self.len() as u32);
        out[8..len].copy_from_slice(&self.params[..len - 8]);
        len
    }
}

/// Writes a Custom Effect payload from values; `out` must hold
/// [`CustomEffect::len_for`]`(params.len())` bytes. Returns the length.
pub fn encode_custom_effect(effect_id: u32, params: &[f32], out: &mut [u8]) -> usize {
    let len = CustomEffect::len_for(params.len());
    BigEndian::write_u32(&mut out[0..4], effect_id);
    BigEndian::write_u32(&mut out[4..8], params.len() as u32);
    BigEndian::write_f32_into(params, &mut out[8..len]);
    len
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    #[test]
    fn lengths_match_devices_md() {
        let table: &[(&str, usize)] = &[
            (FORCE, Force::LEN),
            (FORCE_FIELD, ForceField::LEN),
            (PLANE, Plane::LEN),
            (PLANE2, Plane2::LEN),
            (ADD_OBJECT, AddObject::LEN),
            (ADD_OBJECT_EX_SCENE, ObjectId::LEN),
            (MOVE_TO_PARENT, AddObject::LEN),
            (SET_OBJECT_POSITION, ObjectVec3::LEN),
            (SET_OBJECT_ORIENTATION, ObjectOrientation::LEN),
            (SET_OBJECT_SCALE, ObjectVec3::LEN),
            (REMOVE_OBJECT, ObjectId::LEN),
            (SET_VERTEX, IndexedVec3::LEN),
            (SET_NORMAL, IndexedVec3::LEN),
            (SET_TRIANGLE, SetTriangle::LEN),
            (REMOVE_TRIANGLE, RemoveTriangle::LEN),
            (UPDATE_TRIMESH_CHANGES, UpdateTrimeshChanges::LEN),
            (TRANSFORM_TRIMESH, TransformTrimesh::LEN),
            (SET_TRIMESH_TYPE, SetTrimeshType::LEN),
            (CLEAR_TRIMESH, ObjectId::LEN),
            (SET_HAPTIC_ORIGIN, Origin::LEN),
            (SET_HAPTIC_SCALE, HapticScale::LEN),
            (SET_SCENE_ORIGIN, Origin::LEN),
            (SET_OBJECT_IS_TOUCHABLE, SetObjectIsTouchable::LEN),
            (SCP, Scp::LEN),
            (FORCE_ERROR, ForceError::LEN),
            (CONSTRAINT_ENABLE, ConstraintInt::LEN),
            (CONSTRAINT_MODE, ConstraintInt::LEN),
            (CONSTRAINT_POINT, ConstraintVec3::LEN),
            (CONSTRAINT_LINEPT, ConstraintVec3::LEN),
            (CONSTRAINT_LINEDIR, ConstraintVec3::LEN),
            (CONSTRAINT_PLPT, ConstraintVec3::LEN),
            (CONSTRAINT_PLNORM, ConstraintVec3::LEN),
            (CONSTRAINT_KSPRING, ConstraintKSpring::LEN),
        ];
        let expected = [
            24, 64, 40, 24, 8, 4, 8, 16, 20, 16, 4, 20, 20, 32, 8, 20, 68, 8, 4, 28, 4, 28, 6, 56,
            4, 4, 4, 12, 12, 12, 12, 12, 4,
        ];
        assert_eq!(table.len(), expected.len());
        for ((name, len), want) in table.iter().zip(expected) {
            assert_eq!(*len, want, "{name}");
        }
        assert_eq!(TYPE_NAMES.len(), 35);
        assert_eq!(TYPE_NAMES[22], GET_NEW_OBJECT_ID);
        assert_eq!(TYPE_NAMES[34], CUSTOM_EFFECT);
    }

    #[test]
    fn round_trips() {
        round_trip!(
            Force,
            Force {
                force: [1.0, -2.0, 0.5]
            }
        );
        round_trip!(
            Scp,
            Scp {
                pos: [0.1, 0.2, 0.3],
                quat: [0.0, 0.0, 0.0, 1.0]
            }
        );
        let b = round_trip!(
            ForceError,
            ForceError {
                code: FD_FORCE_ERROR
            }
        );
        assert_eq!(b, hex("00000002"));
        // Plane with the remote's defaults: wire order fdyn then fstat.
        let b = round_trip!(
            Plane,
            Plane {
                plane: [0.0, 1.0, 0.0, -0.5],
                kspring: 0.8,
                kdamp: 0.001,
                fdyn: 0.3,
                fstat: 0.7,
                plane_index: 0,
                recovery_cycles: 1
            }
        );
        assert_eq!(&b[24..28], &0.3f32.to_be_bytes());
        assert_eq!(&b[28..32], &0.7f32.to_be_bytes());
        assert_eq!(&b[36..40], &[0, 0, 0, 1]);
        round_trip!(
            Plane2,
            Plane2 {
                normal_adhesion: 0.0001,
                lateral_adhesion: 0.0002,
                texture_amplitude: 0.0005,
                texture_wavelength: 0.01,
                buzz_amplitude: 0.0004,
                buzz_frequency: 0.0003
            }
        );
        let b = round_trip!(
            ForceField,
            ForceField {
                origin: [1.0, 2.0, 3.0],
                force: [0.0; 3],
                jacobian: [[-1.0, 0.1, 0.2], [0.3, -1.0, 0.4], [0.5, 0.6, -1.0]],
                radius: 100.0
            }
        );
        // Row-major: J[0][1] right after J[0][0].
        assert_eq!(&b[28..32], &0.1f32.to_be_bytes());
        assert_eq!(&b[60..64], &100.0f32.to_be_bytes());
        round_trip!(AddObject, AddObject { obj: 2, parent: -1 });
        round_trip!(ObjectId, ObjectId { obj: 9 });
        round_trip!(
            ObjectVec3,
            ObjectVec3 {
                obj: 1,
                v: [1.0, 1.0, 2.0]
            }
        );
        round_trip!(
            ObjectOrientation,
            ObjectOrientation {
                obj: 1,
                axis: [0.0, 1.0, 0.0],
                angle: 1.5
            }
        );
        round_trip!(
            IndexedVec3,
            IndexedVec3 {
                obj: 0,
                index: 4,
                v: [0.5, 0.25, 0.125]
            }
        );
        round_trip!(
            SetTriangle,
            SetTriangle {
                obj: 0,
                index: 1,
                vertices: [0, 1, 2],
                normals: [-1, -1, -1]
            }
        );
        round_trip!(RemoveTriangle, RemoveTriangle { obj: 0, index: 1 });
        let b = round_trip!(
            UpdateTrimeshChanges,
            UpdateTrimeshChanges {
                obj: 0,
                kspring: 0.8,
                kdamp: 0.001,
                fstat: 0.7,
                fdyn: 0.3
            }
        );
        assert_eq!(&b[12..16], &0.7f32.to_be_bytes());
        let mut m = [0.0f32; 16];
        for (i, v) in m.iter_mut().enumerate() {
            *v = i as f32;
        }
        round_trip!(TransformTrimesh, TransformTrimesh { obj: 3, matrix: m });
        round_trip!(
            SetTrimeshType,
            SetTrimeshType {
                obj: -1,
                kind: TRIMESH_HCOLLIDE
            }
        );
        round_trip!(
            Origin,
            Origin {
                pos: [0.0, 0.1, 0.2],
                axis: [0.0, 0.0, 1.0],
                angle: 0.25
            }
        );
        round_trip!(HapticScale, HapticScale { scale: 2.0 });
        let b = round_trip!(
            SetObjectIsTouchable,
            SetObjectIsTouchable {
                obj: 5,
                touchable: 1
            }
        );
        assert_eq!(b, hex("00000005 0001"));
        round_trip!(
            ConstraintInt,
            ConstraintInt {
                value: CONSTRAINT_MODE_PLANE
            }
        );
        round_trip!(
            ConstraintVec3,
            ConstraintVec3 {
                v: [1.0, 0.0, -1.0]
            }
        );
        round_trip!(ConstraintKSpring, ConstraintKSpring { k: 50.0 });
        assert!(Force::decode(&[0u8; 25]).is_err());
        assert!(SetObjectIsTouchable::decode(&[0u8; 8]).is_err());
    }

    #[test]
    fn custom_effect() {
        let mut buf = [0u8; 64];
        let n = encode_custom_effect(7, &[1.0, -0.5, 3.0], &mut buf);
        assert_eq!(n, 20);
        assert_eq!(
            buf[..n].to_vec(),
            hex("00000007 00000003 3f800000 bf000000 40400000")
        );
        let e = CustomEffect::decode(&buf[..n]).unwrap();
        assert_eq!(e.effect_id, 7);
        assert_eq!(e.len(), 3);
        assert_eq!(e.params().collect::<Vec<_>>(), vec![1.0, -0.5, 3.0]);
        assert_eq!(e.param(2), Some(3.0));
        assert_eq!(e.param(3), None);
        let mut again = [0u8; 64];
        assert_eq!(e.encode(&mut again), n);
        assert_eq!(again[..n], buf[..n]);
        // Longer payloads are accepted, shorter ones refused.
        assert_eq!(CustomEffect::decode(&buf[..n + 4]).unwrap().len(), 3);
        for cut in 0..n {
            assert!(CustomEffect::decode(&buf[..cut]).is_err());
        }
        // stopEffect: id -1, no parameters.
        let n = encode_custom_effect(STOP_EFFECT_ID, &[], &mut buf);
        assert_eq!(buf[..n].to_vec(), hex("ffffffff 00000000"));
        assert!(CustomEffect::decode(&buf[..n]).unwrap().is_empty());
        // A huge count never panics.
        assert!(CustomEffect::decode(&hex("00000000 ffffffff")).is_err());
    }
}
