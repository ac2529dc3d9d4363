//! A DTRACK controller simulator: frames of known content as the controller writes them,
//! sent over UDP, and the values a VRPN client must receive for them, computed here
//! independently of the driver (orientation from the axis and angle the rotation matrix was
//! built from, not from the matrix).

use std::fmt::Write as _;
use std::io;
use std::net::{SocketAddr, UdpSocket};

/// A rotation about a unit axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotation {
    /// Unit axis.
    pub axis: [f64; 3],
    /// Angle in radians.
    pub angle: f64,
}

impl Rotation {
    /// The rotation matrix (column-vector convention), row by row.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        let [x, y, z] = self.axis;
        let (s, c) = self.angle.sin_cos();
        let t = 1.0 - c;
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    }

    /// The matrix as DTrack sends it: column by column.
    pub fn dtrack_text(&self) -> String {
        let m = self.matrix();
        let mut s = String::new();
        for c in 0..3 {
            for row in &m {
                if !s.is_empty() {
                    s.push(' ');
                }
                let _ = write!(s, "{:.6}", row[c]);
            }
        }
        s
    }

    /// The quaternion (x, y, z, w) with w ≥ 0.
    pub fn quat(&self) -> [f64; 4] {
        let (s, c) = (self.angle / 2.0).sin_cos();
        [self.axis[0] * s, self.axis[1] * s, self.axis[2] * s, c]
    }
}

/// A tracked 6DOF target in a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// DTrack id.
    pub id: usize,
    /// Quality (−1: not tracked).
    pub quality: f32,
    /// Position in millimetres.
    pub loc: [f64; 3],
    /// Orientation.
    pub rot: Rotation,
}

/// A Flystick (`6df2`): a target with buttons and joystick values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stick {
    /// The 6DOF part.
    pub target: Target,
    /// Buttons as bits (button *i* = bit *i*), `nb` of them.
    pub buttons: u32,
    /// How many buttons.
    pub nb: usize,
    /// Joystick values (horizontal, vertical).
    pub joystick: [f64; 2],
}

/// What one frame holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// `fr`.
    pub counter: u32,
    /// `ts2` seconds, microseconds, latency (`None`: no `ts2` line).
    pub ts2: Option<(u32, u32, u32)>,
    /// `6dcal` total (bodies + tools; `6df2` Flysticks are not in it).
    pub calibrated: usize,
    /// Standard bodies.
    pub bodies: Vec<Target>,
    /// Flysticks (`6df2`).
    pub sticks: Vec<Stick>,
    /// Measurement tools counted in `6dmt`.
    pub tools: usize,
    /// Markers `(id, loc mm)` (`3d`).
    pub markers: Vec<(usize, [f64; 3])>,
}

fn block3(v: &[f64; 3]) -> String {
    format!("[{:.3} {:.3} {:.3}]", v[0], v[1], v[2])
}

impl Frame {
    /// Frame `k` of the standard sequence: two calibrated bodies (body 1 untracked in odd
    /// frames), one Flystick whose buttons count up and whose joystick sweeps, one tool,
    /// `k % 3` markers; `ts2` stamped `sec.usec`.
    pub fn standard(k: u32, sec: u32, usec: u32) -> Frame {
        let kf = k as f64;
        let rot = |a: f64, axis: [f64; 3]| {
            let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
            Rotation {
                axis: axis.map(|v| v / n),
                angle: a,
            }
        };
        let mut bodies = vec![Target {
            id: 0,
            quality: 1.0,
            loc: [100.0 + kf, -200.5 + 0.25 * kf, 1500.125],
            rot: rot(0.05 * kf, [0.0, 0.0, 1.0]),
        }];
        if k % 2 == 0 {
            bodies.push(Target {
                id: 1,
                quality: 0.5,
                loc: [-kf * 2.0, 10.0, 20.0],
                rot: rot(0.3 + 0.01 * kf, [1.0, 2.0, 2.0]),
            });
        }
        let sticks = vec![Stick {
            target: Target {
                id: 0,
                quality: 0.9,
                loc: [kf, kf * 0.5, 1000.0 - kf],
                rot: rot(1.0 + 0.02 * kf, [0.0, 1.0, 0.0]),
            },
            buttons: (k / 3) % 64,
            nb: 8,
            joystick: [((k % 21) as f64 - 10.0) / 10.0, 0.25],
        }];
        let markers = (0..(k % 3) as usize)
            .map(|i| (i + 1, [kf + i as f64, -kf, 3.5 * i as f64]))
            .collect();
        Frame {
            counter: k,
            ts2: Some((sec, usec, 1500)),
            calibrated: 3,
            bodies,
            sticks,
            tools: 1,
            markers,
        }
    }

    /// The datagram, as the controller writes it (CR LF line ends).
    pub fn text(&self) -> String {
        let mut s = format!("fr {}\r\n", self.counter);
        if let Some((sec, usec, lat)) = self.ts2 {
            let _ = write!(s, "ts2 {sec} {usec} {lat}\r\n");
        }
        let _ = write!(s, "6dcal {}\r\n", self.calibrated);
        let _ = write!(s, "6d {}", self.bodies.len());
        for b in &self.bodies {
            let _ = write!(
                s,
                " [{} {:.3}]{}[{}]",
                b.id,
                b.quality,
                block3(&b.loc),
                b.rot.dtrack_text()
            );
        }
        s.push_str("\r\n");
        let _ = write!(s, "6df2 {} {}", self.sticks.len(), self.sticks.len());
        for f in &self.sticks {
            let t = &f.target;
            let _ = write!(
                s,
                " [{} {:.3} {} 2]{}[{}][{} {:.2} {:.2}]",
                t.id,
                t.quality,
                f.nb,
                block3(&t.loc),
                t.rot.dtrack_text(),
                f.buttons,
                f.joystick[0],
                f.joystick[1]
            );
        }
        s.push_str("\r\n");
        let _ = write!(s, "6dmt {}\r\n", self.tools);
        let _ = write!(s, "3d {}", self.markers.len());
        for (id, loc) in &self.markers {
            let _ = write!(s, " [{id} 1.000]{}", block3(loc));
        }
        s.push_str("\r\n");
        s
    }

    /// Calibrated standard bodies as the driver counts them: `6dcal` less the tools.
    pub fn bodies_visible(&self) -> usize {
        self.calibrated - self.tools
    }

    /// The poses a client must receive, in order: `(sensor, pos m, quat)` for tracked
    /// bodies, the Flysticks after the calibrated bodies, then (with `markers`) the markers.
    pub fn expected_poses(&self, markers: bool) -> Vec<(usize, [f64; 3], [f64; 4])> {
        let nbody = self.bodies_visible();
        let mut out = Vec::new();
        for b in self.bodies.iter().filter(|b| b.quality >= 0.0) {
            out.push((b.id, b.loc.map(|v| v / 1000.0), b.rot.quat()));
        }
        for f in self.sticks.iter().filter(|f| f.target.quality >= 0.0) {
            let t = &f.target;
            out.push((nbody + t.id, t.loc.map(|v| v / 1000.0), t.rot.quat()));
        }
        if markers {
            let first = nbody + self.sticks.len();
            for (i, (_, loc)) in self.markers.iter().enumerate() {
                out.push((first + i, loc.map(|v| v / 1000.0), [0.0, 0.0, 0.0, 1.0]));
            }
        }
        out
    }
}

/// The controller: a UDP socket sending frames to the server.
pub struct Controller {
    sock: UdpSocket,
    to: SocketAddr,
}

impl Controller {
    /// A controller on a socket of its own, sending to `to`.
    pub fn new(to: SocketAddr) -> io::Result<Controller> {
        Ok(Controller {
            sock: UdpSocket::bind("127.0.0.1:0")?,
            to,
        })
    }

    /// A controller sending from `sock` (a multicast sender, the firewall's peer).
    pub fn on(sock: UdpSocket, to: SocketAddr) -> Controller {
        Controller { sock, to }
    }

    /// Sends one datagram.
    pub fn send(&self, bytes: &[u8]) -> io::Result<()> {
        self.sock.send_to(bytes, self.to).map(|_| ())
    }
}

/// A port free on every interface now (for a configuration line that needs a number).
pub fn free_udp_port() -> io::Result<u16> {
    Ok(UdpSocket::bind("0.0.0.0:0")?.local_addr()?.port())
}
