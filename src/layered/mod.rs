//! Layered devices: server objects that are themselves clients of other devices.
//!
//! [`analog_fly::TrackerAnalogFly`] turns analog axes (a joystick, a space mouse) into a tracker
//! pose; [`button_fly::TrackerButtonFly`] does the same from buttons. Each listens to its
//! sources through ordinary remotes: a `*NAME` source is a remote on the server's own connection
//! (every connection delivers what it packs to its local handlers, so the callback runs inside
//! the source's report), a `NAME@host` source a remote on a client connection to that server,
//! serviced from the layered device's mainloop.
//!
//! The pose arithmetic reproduces C++ VRPN's quaternion library (quatlib) operation for operation
//! so that reported poses agree with C++ bit for bit.

use crate::config::DeviceRef;
use crate::connection::Connection;
use crate::devices::analog::AnalogRemote;
use crate::devices::base::RemoteCore;
use crate::devices::button::ButtonRemote;
use crate::devices::tracker::TrackerRemote;
use crate::error::Error;
use crate::time::TimeVal;

pub mod analog_fly;
pub mod button_fly;
pub mod config;
pub mod imu;

pub use analog_fly::TrackerAnalogFly;
pub use button_fly::TrackerButtonFly;

/// 2π as C++ computes it from `PI = 3.14159265358979323846`.
pub(crate) const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// A 4×4 matrix indexed `m[row][col]`.
pub type Mat4 = [[f64; 4]; 4];

/// The identity matrix.
pub const IDENTITY: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// quatlib `q_euler_to_col_matrix`: rotation block only, row/column 3 of the
/// identity.
pub fn euler_col_matrix(yaw: f64, pitch: f64, roll: f64) -> Mat4 {
    let (sy, cy) = (yaw.sin(), yaw.cos());
    let (sp, cp) = (pitch.sin(), pitch.cos());
    let (sr, cr) = (roll.sin(), roll.cos());
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, 0.0],
        [sy * cp, cy * cr + sy * sp * sr, sy * sp * cr - cy * sr, 0.0],
        [-sp, cp * sr, cp * cr, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// quatlib `q_matrix_mult`: `a × b`, sums accumulated from 0 left to right.
pub fn mat_mult(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut c = [[0.0; 4]; 4];
    for (r, row) in c.iter_mut().enumerate() {
        for (col, out) in row.iter_mut().enumerate() {
            let mut s = 0.0;
            for (k, bk) in b.iter().enumerate() {
                s += a[r][k] * bk[col];
            }
            *out = s;
        }
    }
    c
}

/// quatlib `q_from_row_matrix`, returning (x, y, z, w).
pub fn quat_from_row_matrix(m: &Mat4) -> [f64; 4] {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let mut q = [0.0; 4];
    if tr > 0.0 {
        let s = (tr + 1.0).sqrt();
        q[3] = s * 0.5;
        let s = 0.5 / s;
        q[0] = (m[1][2] - m[2][1]) * s;
        q[1] = (m[2][0] - m[0][2]) * s;
        q[2] = (m[0][1] - m[1][0]) * s;
    } else {
        let mut i = 0;
        if m[1][1] > m[0][0] {
            i = 1;
        }
        if m[2][2] > m[i][i] {
            i = 2;
        }
        let j = (i + 1) % 3;
        let k = (j + 1) % 3;
        let s = ((m[i][i] - (m[j][j] + m[k][k])) + 1.0).sqrt();
        q[i] = s * 0.5;
        let s = 0.5 / s;
        q[3] = (m[j][k] - m[k][j]) * s;
        q[j] = (m[i][j] + m[j][i]) * s;
        q[k] = (m[i][k] + m[k][i]) * s;
    }
    q
}

/// quatlib `q_from_euler`, returning (x, y, z, w).
pub fn quat_from_euler(yaw: f64, pitch: f64, roll: f64) -> [f64; 4] {
    let (cy, sy) = ((yaw / 2.0).cos(), (yaw / 2.0).sin());
    let (cp, sp) = ((pitch / 2.0).cos(), (pitch / 2.0).sin());
    let (cr, sr) = ((roll / 2.0).cos(), (roll / 2.0).sin());
    [
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    ]
}

/// quatlib `q_invert`: the conjugate divided by the squared norm.
pub fn quat_invert(q: &[f64; 4]) -> [f64; 4] {
    let n = 1.0 / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    [-q[0] * n, -q[1] * n, -q[2] * n, q[3] * n]
}

/// quatlib `q_mult`: the Hamilton product `a ⊗ b`, (x, y, z, w) layout.
pub fn quat_mult(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    let (ax, ay, az, aw) = (a[0], a[1], a[2], a[3]);
    let (bx, by, bz, bw) = (b[0], b[1], b[2], b[3]);
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by + ay * bw + az * bx - ax * bz,
        aw * bz + az * bw + ax * by - ay * bx,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// quatlib's π.
const Q_PI: f64 = std::f64::consts::PI;
/// quatlib's `Q_EPSILON`.
const Q_EPSILON: f64 = 1e-10;

/// quatlib `q_normalize`.
pub fn quat_normalize(q: &[f64; 4]) -> [f64; 4] {
    let f = 1.0 / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    [q[0] * f, q[1] * f, q[2] * f, q[3] * f]
}

/// quatlib `q_slerp` from `start` to `end` by `t`, (x, y, z, w).
pub fn quat_slerp(start: &[f64; 4], end: &[f64; 4], t: f64) -> [f64; 4] {
    let mut s = *start;
    let mut cos_omega = s[0] * end[0] + s[1] * end[1] + s[2] * end[2] + s[3] * end[3];
    if cos_omega < 0.0 {
        cos_omega *= -1.0;
        for v in &mut s {
            *v *= -1.0;
        }
    }
    let mut dest = [0.0; 4];
    if (1.0 + cos_omega) > Q_EPSILON {
        let (start_scale, end_scale) = if (1.0 - cos_omega) > Q_EPSILON {
            let omega = cos_omega.acos();
            let sin_omega = omega.sin();
            (
                ((1.0 - t) * omega).sin() / sin_omega,
                (t * omega).sin() / sin_omega,
            )
        } else {
            (1.0 - t, t)
        };
        for i in 0..4 {
            dest[i] = start_scale * s[i] + end_scale * end[i];
        }
    } else {
        dest = [-s[1], s[0], -s[3], s[2]];
        let start_scale = ((0.5 - t) * Q_PI).sin();
        let end_scale = (t * Q_PI).sin();
        for i in 0..3 {
            dest[i] = start_scale * s[i] + end_scale * dest[i];
        }
    }
    dest
}

/// quatlib `q_xyz_quat_invert`: the inverse of the transform (t, q).
pub fn xyz_quat_invert(t: [f64; 3], q: [f64; 4]) -> ([f64; 3], [f64; 4]) {
    let qi = quat_invert(&q);
    let v = [-t[0], -t[1], -t[2], 0.0];
    let tmp = quat_mult(&qi, &v);
    let r = quat_mult(&tmp, &quat_invert(&qi));
    ([r[0], r[1], r[2]], qi)
}

/// quatlib `q_to_col_matrix`.
pub fn col_matrix_from_quat(q: [f64; 4]) -> Mat4 {
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    let s = 2.0 / (x * x + y * y + z * z + w * w);
    let (xs, ys, zs) = (x * s, y * s, z * s);
    let (wx, wy, wz) = (w * xs, w * ys, w * zs);
    let (xx, xy, xz) = (x * xs, x * ys, x * zs);
    let (yy, yz, zz) = (y * ys, y * zs, z * zs);
    [
        [1.0 - (yy + zz), xy - wz, xz + wy, 0.0],
        [xy + wz, 1.0 - (xx + zz), yz - wx, 0.0],
        [xz - wy, yz + wx, 1.0 - (xx + yy), 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// Seconds from `earlier` to `later` as C++ computes them: Δusec / 1e6 + Δsec.
pub(crate) fn interval(later: TimeVal, earlier: TimeVal) -> f64 {
    (later.usec - earlier.usec) as f64 / 1e6 + (later.sec - earlier.sec) as f64
}

/// `1/update_rate` in single precision, widened; 1 s when the rate is 0.
pub(crate) fn update_interval(rate: f32) -> f64 {
    if rate == 0.0 {
        1.0
    } else {
        (1.0f32 / rate) as f64
    }
}

/// An analog source of a layered device.
pub(crate) struct AnalogSource {
    pub(crate) remote: AnalogRemote,
    local: bool,
}

/// A button source of a layered device.
pub(crate) struct ButtonSource {
    pub(crate) remote: ButtonRemote,
    local: bool,
}

impl AnalogSource {
    pub(crate) fn open(src: &DeviceRef, server: &Connection) -> Result<AnalogSource, Error> {
        Ok(match src {
            DeviceRef::Local(n) => AnalogSource {
                remote: AnalogRemote::on_connection(n, server)?,
                local: true,
            },
            DeviceRef::Remote(n) => AnalogSource {
                remote: {
                    let (device, conn) = RemoteCore::open_in(server.reactor().as_ref(), n)?;
                    AnalogRemote::on_connection(&device, &conn)?
                },
                local: false,
            },
        })
    }

    /// A second source reading `src` on the connection of this one, which was opened for the
    /// same device reference (C++ shares one connection per remote name, so every reader of a
    /// device sees its report in the same pass). Polling this one does nothing: this one's
    /// poll services the connection for both.
    pub(crate) fn alongside(&self, src: &DeviceRef) -> Result<AnalogSource, Error> {
        let device = match src {
            DeviceRef::Local(n) => n.clone(),
            DeviceRef::Remote(n) => crate::name::DeviceName::parse_remote(n)?.device,
        };
        Ok(AnalogSource {
            remote: AnalogRemote::on_connection(&device, self.remote.connection())?,
            local: true,
        })
    }

    /// Services the source's connection unless that is the server's own (which the server
    /// loop services, liveness pings included; local messages arrive as they are packed).
    pub(crate) fn poll(&self) {
        if !self.local {
            let _ = self.remote.mainloop();
        }
    }

    /// When the source's own connection next needs a pass (remote sources only).
    pub(crate) fn next_deadline(&self) -> Option<std::time::Instant> {
        if self.local {
            None
        } else {
            self.remote.connection().poll_timeout()
        }
    }
}

impl ButtonSource {
    pub(crate) fn open(src: &DeviceRef, server: &Connection) -> Result<ButtonSource, Error> {
        Ok(match src {
            DeviceRef::Local(n) => ButtonSource {
                remote: ButtonRemote::on_connection(n, server)?,
                local: true,
            },
            DeviceRef::Remote(n) => ButtonSource {
                remote: {
                    let (device, conn) = RemoteCore::open_in(server.reactor().as_ref(), n)?;
                    ButtonRemote::on_connection(&device, &conn)?
                },
                local: false,
            },
        })
    }

    /// See [`AnalogSource::poll`].
    pub(crate) fn poll(&self) {
        if !self.local {
            let _ = self.remote.mainloop();
        }
    }

    /// See [`AnalogSource::next_deadline`].
    pub(crate) fn next_deadline(&self) -> Option<std::time::Instant> {
        if self.local {
            None
        } else {
            self.remote.connection().poll_timeout()
        }
    }
}

/// A tracker source of a layered device (a filter of another tracker's poses).
pub(crate) struct TrackerSource {
    pub(crate) remote: TrackerRemote,
    local: bool,
}

impl TrackerSource {
    pub(crate) fn open(src: &DeviceRef, server: &Connection) -> Result<TrackerSource, Error> {
        Ok(match src {
            DeviceRef::Local(n) => TrackerSource {
                remote: TrackerRemote::on_connection(n, server)?,
                local: true,
            },
            DeviceRef::Remote(n) => TrackerSource {
                remote: {
                    let (device, conn) = RemoteCore::open_in(server.reactor().as_ref(), n)?;
                    TrackerRemote::on_connection(&device, &conn)?
                },
                local: false,
            },
        })
    }

    /// See [`AnalogSource::poll`].
    pub(crate) fn poll(&self) {
        if !self.local {
            let _ = self.remote.mainloop();
        }
    }

    /// See [`AnalogSource::next_deadline`].
    pub(crate) fn next_deadline(&self) -> Option<std::time::Instant> {
        if self.local {
            None
        } else {
            self.remote.connection().poll_timeout()
        }
    }
}

/// The records of a capture of C++ VRPN's output kept in `tests/fixtures/` (comment lines
/// start with `#`): each line a tag and numbers.
#[cfg(test)]
pub(crate) fn fixture_records(text: &str) -> Vec<(&str, Vec<f64>)> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let mut t = l.split_whitespace();
            let tag = t.next().unwrap_or("");
            let nums = t.map(|v| v.parse::<f64>().expect("a number")).collect();
            (tag, nums)
        })
        .collect()
}
