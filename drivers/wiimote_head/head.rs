//! The head pose from two IR blobs, C++ VRPN 07.38's arithmetic operation for operation (its
//! quaternion library included), free of I/O and of the clock.

use crate::layered::{quat_from_euler, quat_invert, quat_mult, quat_normalize};
use crate::time::TimeVal;

/// The IR camera's resolution in pixels.
const X_RES: f64 = 1024.0;
/// See [`X_RES`].
const Y_RES: f64 = 768.0;
/// quatlib's π (`3.14159265358979323846`, the nearest `f64` to π).
const Q_PI: f64 = std::f64::consts::PI;
/// quatlib's `Q_EPSILON`.
const Q_EPSILON: f64 = 1e-10;

/// The camera's horizontal field of view (43°, measured at Iowa State University).
fn fov_x() -> f64 {
    (43.0 * Q_PI) / 180.0
}

/// The camera's vertical field of view (32°).
fn fov_y() -> f64 {
    (32.0 * Q_PI) / 180.0
}

/// A position and an orientation (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position in metres.
    pub xyz: [f64; 3],
    /// Orientation quaternion (x, y, z, w).
    pub quat: [f64; 4],
}

impl Pose {
    /// No translation, no rotation.
    pub const IDENTITY: Pose = Pose {
        xyz: [0.0; 3],
        quat: [0.0, 0.0, 0.0, 1.0],
    };
}

/// Whether the two blobs were seen the right way up when the lock began.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flip {
    /// No lock yet: decided at the first pose of the next lock.
    Unknown,
    /// Blob 0 then blob 1.
    Normal,
    /// The first pose came out upside down: the blobs are taken in the other order.
    Turned,
}

/// The tracker's state between reports.
#[derive(Clone, Debug)]
pub struct HeadTracker {
    /// Distance between the two LEDs, metres.
    blob_distance: f64,
    blob_x: [f64; 4],
    blob_y: [f64; 4],
    blob_size: [f64; 4],
    /// Blobs of the report before the first missing one (kept when blob 0 is missing, as C++).
    points: usize,
    gravity: [f64; 3],
    gravity_previous: [f64; 3],
    gravity_before_previous: [f64; 3],
    /// A new gravity vector not yet folded into `gravity_xform`.
    gravity_dirty: bool,
    gravity_xform: Pose,
    current: Pose,
    flip: Flip,
    lock: bool,
    /// The position and orientation reported.
    pub reported: Pose,
    /// The time of the latest Wiimote report; `None` before the first.
    pub time: Option<TimeVal>,
    /// A Wiimote report (or a new client) asks for a report at the next pass.
    pub updated: bool,
}

impl HeadTracker {
    /// The state at start-up: identity orientation 1 m in front of the camera, a report due.
    pub fn new(led_spacing: f64) -> HeadTracker {
        let mut t = HeadTracker {
            blob_distance: led_spacing,
            blob_x: [-1.0; 4],
            blob_y: [-1.0; 4],
            blob_size: [-1.0; 4],
            points: 0,
            gravity: [0.0, 0.0, 1.0],
            gravity_previous: [0.0, 0.0, 1.0],
            gravity_before_previous: [0.0, 0.0, 1.0],
            gravity_dirty: true,
            gravity_xform: Pose::IDENTITY,
            current: Pose::IDENTITY,
            flip: Flip::Unknown,
            lock: false,
            reported: Pose::IDENTITY,
            time: None,
            updated: true,
        };
        t.current.xyz[2] = 1.0;
        t.reported = t.current;
        t
    }

    /// One report of the Wiimote's Analog: channels 1-3 gravity, then up to four blobs of
    /// three channels (x, y, size) from channel 4; the first blob with a value not above 0
    /// ends the list. Channels the report lacks read as 0.
    pub fn wiimote_report(&mut self, time: TimeVal, channels: &[f64]) {
        let ch = |i: usize| channels.get(i).copied().unwrap_or(0.0);
        for i in 0..4 {
            let first = i * 3 + 4;
            let (x, y, size) = (ch(first), ch(first + 1), ch(first + 2));
            if x > 0.0 && y > 0.0 && size > 0.0 {
                self.blob_x[i] = x;
                self.blob_y[i] = y;
                self.blob_size[i] = size;
                self.points = i + 1;
            } else {
                break;
            }
        }
        self.updated = true;
        let new_gravity = (0..3).any(|i| ch(1 + i) != self.gravity[i]);
        if new_gravity {
            if !self.gravity_dirty {
                // Slide the history only once the previous vector has been used.
                self.gravity_before_previous = self.gravity_previous;
                self.gravity_previous = self.gravity;
            }
            self.gravity = [ch(1), ch(2), ch(3)];
            self.gravity_dirty = true;
        }
        self.time = Some(time);
    }

    /// The LED blobs in the latest report (x, y, size each), up to the first missing one.
    pub fn blobs(&self) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        (0..self.points).map(|i| (self.blob_x[i], self.blob_y[i], self.blob_size[i]))
    }

    /// Whether the last pose computation saw exactly two blobs.
    pub fn locked(&self) -> bool {
        self.lock
    }

    fn have_gravity(&self) -> bool {
        self.gravity[0] != 0.0 || self.gravity[1] != 1.0 || self.gravity[2] != 0.0
    }

    /// Computes the pose to report (C++ `update_pose`): from exactly two blobs, corrected
    /// for gravity; otherwise the reported pose stays and the lock is lost.
    pub fn update_pose(&mut self) {
        if self.gravity_dirty && self.have_gravity() {
            self.update_gravity();
        }
        self.update_two_led_pose();
        if self.lock {
            if self.have_gravity() {
                self.current = compose(&self.current, &self.gravity_xform);
            }
            if self.flip == Flip::Unknown {
                self.update_flip();
                if self.flip == Flip::Turned {
                    // The pose recomputed with the blobs swapped has been taken already.
                    return;
                }
            }
            self.reported = self.current;
        }
    }

    /// The rotation taking the mean of the last three gravity vectors to +z.
    fn update_gravity(&mut self) {
        let mut mean = self.gravity;
        mean = vec_add(&mean, &self.gravity_previous);
        mean = vec_add(&mean, &self.gravity_before_previous);
        mean = vec_scale(&mean, 0.33333);
        self.gravity_xform = Pose {
            xyz: [0.0; 3],
            quat: quat_from_two_vecs(&mean, &[0.0, 0.0, 1.0]),
        };
        self.gravity_dirty = false;
    }

    fn update_two_led_pose(&mut self) {
        if self.points != 2 {
            self.lock = false;
            self.flip = Flip::Unknown;
            return;
        }
        self.lock = true;
        let (mut x0, mut x1) = (self.blob_x[0], self.blob_x[1]);
        let (mut y0, mut y1) = (self.blob_y[0], self.blob_y[1]);
        if self.flip == Flip::Turned {
            std::mem::swap(&mut x0, &mut x1);
            std::mem::swap(&mut y0, &mut y1);
        }
        let dx = x0 - x1;
        let dy = y0 - y1;
        let dist = (dx * dx + dy * dy).sqrt();
        let angle = dist * ((fov_x() / X_RES) / 2.0);
        let head_dist = (self.blob_distance / 2.0) / angle.tan();
        let rz = dy.atan2(dx);
        let avg_x = (x0 + x1) / 2.0;
        let avg_y = (y0 + y1) / 2.0;
        if avg_x.is_nan() || avg_y.is_nan() {
            return;
        }
        let b_horiz = X_RES / 2.0 / (fov_x() / 2.0).tan();
        let b_vert = Y_RES / 2.0 / (fov_y() / 2.0).tan();
        self.current = Pose {
            xyz: [
                head_dist * (avg_x - X_RES / 2.0) / b_horiz,
                head_dist * (avg_y - Y_RES / 2.0) / b_vert,
                head_dist,
            ],
            quat: quat_from_euler(rz, 0.0, 0.0),
        };
    }

    /// At the first pose of a lock: upside down (the rotated y axis points down) means the
    /// blobs are in the other order, and the pose is computed again with them swapped.
    fn update_flip(&mut self) {
        if self.flip != Flip::Unknown {
            return;
        }
        let up = quat_xform(&self.current.quat, &[0.0, 1.0, 0.0]);
        if up[1] < 0.0 {
            self.flip = Flip::Turned;
            self.update_pose();
        } else {
            self.flip = Flip::Normal;
        }
    }
}

fn vec_add(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn vec_scale(v: &[f64; 3], s: f64) -> [f64; 3] {
    [v[0] * s, v[1] * s, v[2] * s]
}

fn vec_dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (a[0] * b[0]) + (a[1] * b[1]) + (a[2] * b[2])
}

fn vec_cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// quatlib `q_vec_normalize`; a vector shorter than `Q_EPSILON` stays `fallback` (quatlib
/// leaves the destination unwritten).
fn vec_normalize(v: &[f64; 3], fallback: [f64; 3]) -> [f64; 3] {
    let magnitude = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if magnitude < Q_EPSILON {
        return fallback;
    }
    vec_scale(v, 1.0 / magnitude)
}

/// quatlib `q_xform`: `v` rotated by `q` (q v q⁻¹).
pub fn quat_xform(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    let inverse = quat_invert(q);
    let t = quat_mult(q, &[v[0], v[1], v[2], 0.0]);
    let r = quat_mult(&t, &inverse);
    [r[0], r[1], r[2]]
}

/// quatlib `q_make`: the rotation by `angle` about the axis (x, y, z).
fn quat_make(axis: &[f64; 3], angle: f64) -> [f64; 4] {
    let length = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    if length < Q_EPSILON {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let (x, y, z) = (axis[0] / length, axis[1] / length, axis[2] / length);
    let (cos_a, sin_a) = ((angle / 2.0).cos(), (angle / 2.0).sin());
    [sin_a * x, sin_a * y, sin_a * z, cos_a]
}

/// quatlib `q_from_two_vecs`: the rotation taking `v1` to `v2` about their common normal.
pub fn quat_from_two_vecs(v1: &[f64; 3], v2: &[f64; 3]) -> [f64; 4] {
    let u1 = vec_normalize(v1, [0.0; 3]);
    let u2 = vec_normalize(v2, [0.0; 3]);
    let mut axis = vec_cross(&u1, &u2);
    let mut cross_magnitude = vec_dot(&axis, &axis).sqrt();
    if cross_magnitude > 1.0 {
        cross_magnitude = 1.0;
    }
    let mut theta = cross_magnitude.asin();
    let mut theta_complement = Q_PI - theta;
    if vec_dot(&u1, &u2) < 0.0 {
        theta = theta_complement;
        theta_complement = Q_PI - theta;
    }
    if theta < Q_EPSILON {
        return [0.0, 0.0, 0.0, 1.0];
    }
    if theta_complement < Q_EPSILON {
        // Opposed vectors: any axis normal to u1.
        axis = if u1[1] * u1[1] + u1[2] * u1[2] >= Q_EPSILON {
            [0.0, u1[2], -u1[1]]
        } else {
            [0.0, 0.0, 1.0]
        };
    }
    let axis = vec_normalize(&axis, axis);
    quat_normalize(&quat_make(&axis, theta))
}

/// quatlib `q_xyz_quat_compose`: `b` followed by `a` (a ∘ b).
fn compose(a: &Pose, b: &Pose) -> Pose {
    let rotated = quat_xform(&a.quat, &b.xyz);
    Pose {
        xyz: vec_add(&a.xyz, &rotated),
        quat: quat_normalize(&quat_mult(&a.quat, &b.quat)),
    }
}
