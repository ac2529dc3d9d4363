//! The combiner's orientation estimate, a pure state machine stepped once per server pass
//! with the seconds since the previous pass, computed operation for operation as C++ VRPN
//! 07.38 does (its quaternion library included) so that the poses agree bit for bit.

use crate::layered::{quat_from_euler, quat_invert, quat_mult, quat_normalize, quat_slerp};

/// Standard gravity, m/s²: the length an accelerometer at rest reads.
pub const GRAVITY: f64 = 9.80665;
/// Fraction of the way back to "gravity points down" corrected over one second.
pub const GRAVITY_RESTORE_RATE: f64 = 0.9;
/// Fraction of the way back to "north points along -Z" corrected over one second.
pub const NORTH_RESTORE_RATE: f64 = 0.9;
/// The span of the reported rotational velocity, seconds.
pub const VELOCITY_DT: f64 = 1e-2;

const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];
/// quatlib's `Q_EPSILON`.
const EPSILON: f64 = 1e-10;

/// The estimate and its latest inputs. Quaternions are (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Combiner {
    /// The orientation (starts at the identity).
    pub quat: [f64; 4],
    /// The rotation over [`VELOCITY_DT`] seconds at the latest rotational velocity.
    pub vel_quat: [f64; 4],
    /// Latest accelerometer vector, m/s² (0 before its first report).
    pub accel: [f64; 3],
    /// Latest rotational velocity about x, y and z, rad/s (0 before its first report).
    pub rotation: [f64; 3],
    /// Latest magnetometer vector, when the combiner has one.
    pub north: Option<[f64; 3]>,
}

impl Combiner {
    /// At the identity, all inputs 0; `magnetometer`: whether north corrections are made.
    pub fn new(magnetometer: bool) -> Combiner {
        Combiner {
            quat: IDENTITY,
            vel_quat: IDENTITY,
            accel: [0.0; 3],
            rotation: [0.0; 3],
            north: magnetometer.then_some([0.0; 3]),
        }
    }

    /// One pass, `dt` seconds after the previous one: turn by the rotational velocity (given
    /// in the sensor's frame) for `dt`; then, the closer the acceleration is to gravity's
    /// length, the more of the way turn it towards -Y and the magnetometer's horizontal part
    /// towards -Z (each at its restore rate, scaled by `dt`); then the velocity quaternion.
    pub fn step(&mut self, dt: f64) {
        let mut forward = self.quat;
        let inverse = quat_invert(&forward);
        let r = self.rotation;
        // quatlib's Euler angles put the rotation about Z first.
        let delta = quat_from_euler(dt * r[2], dt * r[1], dt * r[0]);
        let canonical = quat_mult(&forward, &quat_mult(&delta, &inverse));
        self.quat = quat_mult(&canonical, &self.quat);

        let a = self.accel;
        let length = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let scale = 1.0 - (length - GRAVITY).abs();
        if scale > 0.0 {
            forward = self.quat;
            let rate = scale * GRAVITY_RESTORE_RATE * dt;
            let down = xform(&forward, &vec_normalize(a));
            let rot = from_two_vecs(&down, &[0.0, -1.0, 0.0]);
            self.quat = quat_mult(&quat_slerp(&IDENTITY, &rot, rate), &self.quat);

            if let Some(m) = self.north {
                forward = self.quat;
                let mut horizontal = xform(&forward, &m);
                horizontal[1] = 0.0;
                let north = vec_normalize(horizontal);
                let rot = from_two_vecs(&north, &[0.0, 0.0, -1.0]);
                let rate = scale * NORTH_RESTORE_RATE * dt;
                self.quat = quat_mult(&quat_slerp(&IDENTITY, &rot, rate), &self.quat);
            }
        }

        // C++ keeps the inverse of the orientation the pass began with, and the latest
        // `forward`, for this.
        let delta = quat_from_euler(VELOCITY_DT * r[2], VELOCITY_DT * r[1], VELOCITY_DT * r[0]);
        self.vel_quat = quat_mult(&forward, &quat_mult(&delta, &inverse));
    }
}

/// quatlib `q_vec_normalize`; a vector shorter than its epsilon comes back unchanged (quatlib
/// leaves the destination as it was, which for a fresh one is undefined).
pub fn vec_normalize(v: [f64; 3]) -> [f64; 3] {
    let magnitude = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if magnitude < EPSILON {
        return v;
    }
    let f = 1.0 / magnitude;
    [v[0] * f, v[1] * f, v[2] * f]
}

/// quatlib `q_xform`: `q · v · q⁻¹`.
pub fn xform(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    let vq = [v[0], v[1], v[2], 0.0];
    let r = quat_mult(&quat_mult(q, &vq), &quat_invert(q));
    [r[0], r[1], r[2]]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// quatlib `q_make`: the rotation by `angle` about an axis (identity for a null axis).
pub fn quat_make(axis: [f64; 3], angle: f64) -> [f64; 4] {
    let length = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    if length < EPSILON {
        return IDENTITY;
    }
    let (x, y, z) = (axis[0] / length, axis[1] / length, axis[2] / length);
    let (c, s) = ((angle / 2.0).cos(), (angle / 2.0).sin());
    [s * x, s * y, s * z, c]
}

/// quatlib `q_from_two_vecs`: the rotation taking the direction of `v1` onto that of `v2`
/// about an axis perpendicular to both.
pub fn from_two_vecs(v1: &[f64; 3], v2: &[f64; 3]) -> [f64; 4] {
    let u1 = vec_normalize(*v1);
    let u2 = vec_normalize(*v2);
    let mut axis = [
        u1[1] * u2[2] - u1[2] * u2[1],
        u1[2] * u2[0] - u1[0] * u2[2],
        u1[0] * u2[1] - u1[1] * u2[0],
    ];
    let mut magnitude = dot(&axis, &axis).sqrt();
    if magnitude > 1.0 {
        magnitude = 1.0;
    }
    let mut theta = magnitude.asin();
    let mut complement = std::f64::consts::PI - theta;
    if dot(&u1, &u2) < 0.0 {
        theta = complement;
        complement = std::f64::consts::PI - theta;
    }
    if theta < EPSILON {
        return IDENTITY;
    }
    if complement < EPSILON {
        // Opposite directions: any axis perpendicular to them.
        axis = if u1[1] * u1[1] + u1[2] * u1[2] >= EPSILON {
            [0.0, u1[2], -u1[1]]
        } else {
            [0.0, 0.0, 1.0]
        };
    }
    quat_normalize(&quat_make(vec_normalize(axis), theta))
}

/// One report of a combiner as a client hears it: its time, the orientation and the velocity
/// quaternion.
pub type Heard = (crate::time::TimeVal, [f64; 4], [f64; 4]);

/// Checks that `heard`, the reports of a combiner reporting at every pass, are exactly what
/// this model computes when it is stepped by the time between two reports and fed `inputs`
/// (accelerometer, gyroscope, magnetometer vectors, in the order they were sent) as they
/// arrive: each report is explained by the inputs up to the previous report's, or by one to
/// three more (the server took them in since). The first report must be the state before any
/// input. Returns how many reports took in new inputs, or which report nothing explains.
#[cfg(any(test, feature = "sim"))]
pub fn replay(
    magnetometer: bool,
    inputs: &[[[f64; 3]; 3]],
    heard: &[Heard],
) -> Result<usize, String> {
    let mut model = Combiner::new(magnetometer);
    let Some(((mut prev, q0, v0), rest)) = heard.split_first().map(|(h, r)| (*h, r)) else {
        return Err("no report".into());
    };
    if q0 != model.quat || v0 != model.vel_quat {
        return Err(format!("the first report {q0:?} {v0:?} is not the start"));
    }
    let (mut taken, mut advanced) = (0, 0);
    for (n, &(time, quat, vel_quat)) in rest.iter().enumerate() {
        let dt = crate::layered::interval(time, prev);
        let found = (taken..=(taken + 3).min(inputs.len())).find_map(|k| {
            let mut trial = model;
            if k > 0 {
                let [a, r, m] = inputs[k - 1];
                trial.accel = a;
                trial.rotation = r;
                trial.north = trial.north.map(|_| m);
            }
            trial.step(dt);
            (trial.quat == quat && trial.vel_quat == vel_quat).then_some((k, trial))
        });
        let Some((k, next)) = found else {
            return Err(format!(
                "report {} at {time:?} ({quat:?} {vel_quat:?}) follows from none of inputs \
                 {taken}..={} over {dt} s",
                n + 1,
                (taken + 3).min(inputs.len())
            ));
        };
        advanced += usize::from(k > taken);
        taken = k;
        model = next;
        prev = time;
    }
    Ok(advanced)
}
