//! Trackers over USB HID: PNI SpacePoint Fusion (C++ `vrpn_Tracker_SpacePoint`), Razer Hydra
//! (`vrpn_Tracker_RazerHydra`, [`hydra`]) and VR Space WinTracker III
//! (`vrpn_Tracker_Wintracker`).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Tracker_SpacePoint NAME [INDEX]
//! vrpn_Tracker_RazerHydra NAME
//! vrpn_Tracker_Wintracker NAME S0 S1 S2 EXT HEMI
//! ```
//!
//! `INDEX` (default 0) picks the `INDEX`th SpacePoint (counting from 0) when several are
//! plugged in. For the WinTracker only the first character of each word counts: `S0`-`S2`
//! are sent as the sensors' activation state, `EXT` `1` turns the range extender on, `HEMI`
//! `Z` selects the upper hemisphere (otherwise the front one).
//!
//! # What is sent
//!
//! - SpacePoint: a Tracker with one sensor (orientation; position zero) and a Button with
//!   two buttons. A report is 15 bytes; the quaternion x, y, z, w is four little-endian
//!   `u16` from byte 6, each (v − 32768) / 32768; the buttons are bits 0 and 1 of byte 14.
//! - WinTracker: a Tracker with three sensors. At open the driver writes C++'s commands as
//!   output reports (`00 'S' 'A' S0 S1 S2 '\n'`, then `00 'S' 'H' 'U' '\n'` for the upper
//!   hemisphere, `00 'S' 'L' '\n'` for the range extender). A report is 24 bytes: byte 1 the
//!   sensor as `'0'`-`'2'`, position x, y, z as little-endian `i16` / 10000 m at 2, and the
//!   quaternion w, x, y, z / 10000 at 14.
//!
//! # Differences from C++ VRPN
//!
//! * A SpacePoint report of another length is skipped with a warning (C++ reconnects, to try
//!   the device's other interface; here the interface is chosen from sysfs).
//! * SpacePoint button 1 is reported pressed as 1 (C++ sends the bit's value, 2).
//! * The WinTracker's settings are VRPN text messages instead of lines on the server's
//!   standard output.

pub mod config;
pub mod hydra;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use std::time::Instant;

use crate::devices::ServerDevice;
use crate::driver::text::with_text;
use crate::drivers::hid_pad::{le_i16, le_u16};
use crate::hid::{DeviceHub, HidDevice, HidDriver, HidMatch, HidOps, InterfaceRule, NodeInfo};
use crate::time::Now;
use crate::{ButtonServer, Connection, Error, TextSeverity, TrackerServer};

/// The SpacePoint's ids.
pub const SPACEPOINT: (u16, u16) = (0x20ff, 0x0100);
/// The WinTracker's ids.
pub const WINTRACKER: (u16, u16) = (0x09d9, 0x64df);

/// A SpacePoint report: quaternion `[x, y, z, w]` and the two buttons.
pub fn decode_spacepoint(r: &[u8]) -> Option<([f64; 4], [bool; 2])> {
    (r.len() == 15).then(|| {
        let q = |i: usize| f64::from(i32::from(le_u16(r, 6 + 2 * i)) - 32768) / 32768.0;
        ([q(0), q(1), q(2), q(3)], [r[14] & 1 != 0, r[14] & 2 != 0])
    })
}

/// A WinTracker report: the sensor (`None`: keep the last one, as C++), position and
/// quaternion `[x, y, z, w]`.
pub fn decode_wintracker(r: &[u8]) -> Option<(Option<usize>, [f64; 3], [f64; 4])> {
    (r.len() == 24).then(|| {
        let v = |at: usize| f64::from(le_i16(r, at)) / 10000.00;
        let sensor = match r[1] {
            b'0' => Some(0),
            b'1' => Some(1),
            b'2' => Some(2),
            _ => None,
        };
        (sensor, [v(2), v(4), v(6)], [v(16), v(18), v(20), v(14)])
    })
}

/// The WinTracker's set-up commands, as output reports.
pub fn wintracker_commands(sensors: [u8; 3], ext: u8, hemisphere: u8) -> Vec<Vec<u8>> {
    let mut v = vec![vec![
        0, b'S', b'A', sensors[0], sensors[1], sensors[2], b'\n',
    ]];
    if hemisphere == b'Z' {
        v.push(vec![0, b'S', b'H', b'U', b'\n']);
    }
    if ext == b'1' {
        v.push(vec![0, b'S', b'L', b'\n']);
    }
    v
}

/// Which of the two simple trackers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    SpacePoint,
    Wintracker {
        sensors: [u8; 3],
        ext: u8,
        hemisphere: u8,
    },
}

/// The SpacePoint and WinTracker driver.
pub struct SimpleTracker {
    name: String,
    kind: Kind,
    want: HidMatch,
    tracker: TrackerServer,
    buttons: Option<ButtonServer>,
    sensor: usize,
    last_skip_text: Option<Instant>,
    skipped: u64,
}

impl SimpleTracker {
    /// `vrpn_Tracker_SpacePoint NAME INDEX`.
    pub fn spacepoint(name: &str, index: usize, conn: &Connection) -> Result<SimpleTracker, Error> {
        Ok(SimpleTracker {
            name: name.to_string(),
            kind: Kind::SpacePoint,
            want: HidMatch::product(SPACEPOINT.0, SPACEPOINT.1)
                .interface(InterfaceRule::IsOrUnknown(1))
                .nth(index),
            tracker: TrackerServer::new(name, conn, 1)?,
            buttons: Some(ButtonServer::new(name, conn, 2)?),
            sensor: 0,
            last_skip_text: None,
            skipped: 0,
        })
    }

    /// `vrpn_Tracker_Wintracker NAME S0 S1 S2 EXT HEMI` (the first character of each).
    pub fn wintracker(
        name: &str,
        sensors: [u8; 3],
        ext: u8,
        hemisphere: u8,
        conn: &Connection,
    ) -> Result<SimpleTracker, Error> {
        Ok(SimpleTracker {
            name: name.to_string(),
            kind: Kind::Wintracker {
                sensors,
                ext,
                hemisphere,
            },
            want: HidMatch::product(WINTRACKER.0, WINTRACKER.1),
            tracker: TrackerServer::new(name, conn, 3)?,
            buttons: None,
            sensor: 0,
            last_skip_text: None,
            skipped: 0,
        })
    }

    /// Reports skipped.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    fn skip(&mut self, len: usize, at: Now) {
        self.skipped += 1;
        if self
            .last_skip_text
            .is_some_and(|t| at.mono < t + std::time::Duration::from_secs(1))
        {
            return;
        }
        self.last_skip_text = Some(at.mono);
        let name = &self.name;
        with_text(
            format_args!("{name}: ignored a report of unexpected length {len}"),
            |t| {
                let _ = self.tracker.send_text(TextSeverity::Warning, 0, t);
            },
        );
    }
}

impl HidDriver for SimpleTracker {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        vec![self.want.clone()]
    }

    fn opened(&mut self, _now: Now, _nodes: &[Option<NodeInfo>], ops: &mut HidOps) {
        if let Kind::Wintracker {
            sensors,
            ext,
            hemisphere,
        } = self.kind
        {
            for c in wintracker_commands(sensors, ext, hemisphere) {
                ops.output(0, &c);
            }
            let [a, b, c] = sensors.map(char::from);
            let hemi = if hemisphere == b'Z' {
                "upper (Z<0)"
            } else {
                "front (X>0)"
            };
            let extender = if ext == b'1' { "on" } else { "off" };
            with_text(
                format_args!(
                    "WinTracker III: sensors {a} {b} {c}, hemisphere {hemi}, range extender \
                     {extender}"
                ),
                |t| {
                    let _ = self.tracker.send_text(TextSeverity::Normal, 0, t);
                },
            );
        }
    }

    fn report(&mut self, _interface: usize, r: &[u8], at: Now, _ops: &mut HidOps) {
        match self.kind {
            Kind::SpacePoint => {
                let Some((quat, buttons)) = decode_spacepoint(r) else {
                    return self.skip(r.len(), at);
                };
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.tracker.report_pose(0usize, at.wall, [0.0; 3], quat);
                if let Some(b) = &self.buttons {
                    b.set_button(0, buttons[0]);
                    b.set_button(1, buttons[1]);
                    b.set_timestamp(at.wall);
                    let _ = b.report_changes();
                }
            }
            Kind::Wintracker { .. } => {
                let Some((sensor, pos, quat)) = decode_wintracker(r) else {
                    return self.skip(r.len(), at);
                };
                if let Some(s) = sensor {
                    self.sensor = s;
                }
                let _ = self.tracker.report_pose(self.sensor, at.wall, pos, quat);
            }
        }
    }
}

/// The running SpacePoint, waiting for it to be plugged in.
pub fn build_spacepoint(
    name: &str,
    index: usize,
    conn: &Connection,
    hub: &DeviceHub,
) -> Result<Box<dyn ServerDevice>, Error> {
    Ok(Box::new(HidDevice::new(
        SimpleTracker::spacepoint(name, index, conn)?,
        hub,
        conn,
    )))
}

/// The running WinTracker, waiting for it to be plugged in.
pub fn build_wintracker(
    name: &str,
    sensors: [u8; 3],
    ext: u8,
    hemisphere: u8,
    conn: &Connection,
    hub: &DeviceHub,
) -> Result<Box<dyn ServerDevice>, Error> {
    Ok(Box::new(HidDevice::new(
        SimpleTracker::wintracker(name, sensors, ext, hemisphere, conn)?,
        hub,
        conn,
    )))
}

/// The vrpn.cfg line that would serve `node`, if it is one of these trackers (a Hydra is
/// named once, at its data interface).
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    match (h.vendor, h.product) {
        SPACEPOINT if h.interface.map_or(true, |i| i == 1 || i < 0) => {
            Some("vrpn_Tracker_SpacePoint SpacePoint0 0".to_string())
        }
        hydra::IDS if h.interface == Some(0) => {
            Some("vrpn_Tracker_RazerHydra Tracker0".to_string())
        }
        WINTRACKER => Some("vrpn_Tracker_Wintracker Wintracker0 1 1 1 0 Z".to_string()),
        _ => None,
    }
}
