//! Poser messages: a client asks a server to move to a pose or velocity.
//!
//! All four types are client->server. The C++ server checks the lengths exactly (56 for poses,
//! 64 for velocities) and fails the handler otherwise, so decoding is exact-length. The
//! relative requests share the absolute layouts.

/// Absolute pose request, 56 bytes ([`PoseRequest`]).
pub const REQUEST_POS_QUAT: &str = "vrpn_Poser Request Pos_Quat";
/// Relative pose request, 56 bytes ([`PoseRequest`]); C++ remotes send the accumulated pose.
pub const REQUEST_RELATIVE_POS_QUAT: &str = "vrpn_Poser Request Relative Pos_Quat";
/// Absolute velocity request, 64 bytes ([`VelocityRequest`]).
pub const REQUEST_VELOCITY: &str = "vrpn_Poser Request Velocity";
/// Relative velocity request, 64 bytes ([`VelocityRequest`]).
pub const REQUEST_RELATIVE_VELOCITY: &str = "vrpn_Poser Request Relative Velocity";

/// Every poser type name in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[
    REQUEST_POS_QUAT,
    REQUEST_RELATIVE_POS_QUAT,
    REQUEST_VELOCITY,
    REQUEST_RELATIVE_VELOCITY,
];

fixed_payload! {
    /// Payload of both pose requests. Exact length 56.
    pub struct PoseRequest: exact {
        /// Position `[x, y, z]` (or its change, for the relative request).
        pub pos: [f64; 3],
        /// Orientation `[x, y, z, w]` (or the rotation to apply).
        pub quat: [f64; 4],
    }
}

fixed_payload! {
    /// Payload of both velocity requests. Exact length 64.
    pub struct VelocityRequest: exact {
        /// Linear velocity `[x, y, z]` (or its change).
        pub vel: [f64; 3],
        /// Rotation during `vel_quat_dt`, `[x, y, z, w]`.
        pub vel_quat: [f64; 4],
        /// Interval of `vel_quat` in seconds (or its change).
        pub vel_quat_dt: f64,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::round_trip;
    use super::*;

    #[test]
    fn round_trips() {
        assert_eq!(PoseRequest::LEN, 56);
        assert_eq!(VelocityRequest::LEN, 64);
        let b = round_trip!(
            PoseRequest,
            PoseRequest {
                pos: [0.5, -0.5, 1.0],
                quat: [0.0, 0.0, 0.0, 1.0]
            }
        );
        assert_eq!(&b[..8], &0.5f64.to_be_bytes());
        assert_eq!(&b[48..56], &1.0f64.to_be_bytes());
        round_trip!(
            VelocityRequest,
            VelocityRequest {
                vel: [0.1, 0.2, 0.3],
                vel_quat: [0.0, 1.0, 0.0, 0.0],
                vel_quat_dt: 0.01
            }
        );
        assert!(PoseRequest::decode(&[0u8; 57]).is_err());
        assert!(VelocityRequest::decode(&[0u8; 72]).is_err());
    }
}
