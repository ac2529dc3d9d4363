//! The OSVR Hacker Dev Kit HMD (C++ `vrpn_Tracker_OSVRHackerDevKit`): its orientation as a
//! one-sensor tracker, with the angular velocity (report version 2 and later), and an Analog
//! with the report version (channel 0) and the video input status (channel 1).
//!
//! A report is 16 or 32 bytes: byte 0 the version (low nibble; bit 4 video present and bit 5
//! portrait, from version 3), byte 1 a sequence number, then the orientation x, y, z, w as
//! little-endian fixed-point (14 fractional bits), then (version 2 and later) the angular
//! velocity as fixed-point with 9 fractional bits. The velocity goes out as a rotation over
//! 1/50 s, computed with quatlib's arithmetic as C++ does.
//!
//! Channel 1: 0 unknown (before version 3, or no device), 1 no video input, 2 portrait, 3
//! landscape. Every 400th report sends the Analog whether or not it changed (as C++). When
//! the device goes away the channels return to 0 and 0 (version unknown, status unknown),
//! as C++ reports them.

use std::time::Instant;

use crate::devices::ServerDevice;
use crate::driver::text::with_text;
use crate::drivers::hid_pad::le_i16;
use crate::drivers::hid_quat::{exp, invert, mult, normalize, Quat};
use crate::hid::{DeviceHub, HidDevice, HidDriver, HidMatch, HidOps, NodeInfo};
use crate::time::Now;
use crate::{AnalogServer, Connection, Error, TextSeverity, TrackerServer};

/// The keyword.
pub const KEYWORD: &str = "vrpn_Tracker_OSVRHackerDevKit";
/// The HMD's ids, and the alternative ids of some units.
pub const IDS: [(u16, u16); 2] = [(0x1532, 0x0b00), (0x03eb, 0x2421)];
/// The velocity's time step.
pub const DT: f64 = 1.0 / 50.0;
/// Reports between two full Analog reports.
pub const STATUS_STRIDE: u32 = 400;

/// Status: unknown.
pub const STATUS_UNKNOWN: f64 = 0.0;
/// Status: no video input.
pub const STATUS_NO_VIDEO: f64 = 1.0;
/// Status: portrait video.
pub const STATUS_PORTRAIT: f64 = 2.0;
/// Status: landscape video.
pub const STATUS_LANDSCAPE: f64 = 3.0;

/// What one report says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Report {
    /// The report version.
    pub version: u8,
    /// Orientation `[x, y, z, w]`.
    pub quat: Quat,
    /// The rotation over [`DT`], from version 2.
    pub vel_quat: Option<Quat>,
    /// Video status (channel 1).
    pub status: f64,
}

/// Why a report was not used, with C++'s words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bad {
    /// Not 16 or 32 bytes.
    Length(usize),
    /// Version 2 must be 16 bytes.
    V2Length(usize),
}

/// Decodes one report.
pub fn decode(r: &[u8]) -> Result<Report, Bad> {
    if r.len() != 32 && r.len() != 16 {
        return Err(Bad::Length(r.len()));
    }
    let first = r[0];
    let version = first & 0x0f;
    if version == 2 && r.len() != 16 {
        return Err(Bad::V2Length(r.len()));
    }
    let fixed14 = |at: usize| f64::from(le_i16(r, at)) / f64::from(1 << 14);
    let quat = [fixed14(2), fixed14(4), fixed14(6), fixed14(8)];
    let vel_quat = (version >= 2).then(|| {
        let fixed9 = |at: usize| f64::from(le_i16(r, at)) / f64::from(1 << 9);
        let w = [fixed9(10), fixed9(12), fixed9(14)];
        let inverse = invert(&quat);
        let delta = normalize(&exp(&[
            w[0] * DT * 0.5,
            w[1] * DT * 0.5,
            w[2] * DT * 0.5,
            0.0,
        ]));
        mult(&quat, &mult(&delta, &inverse))
    });
    let status = if version < 3 {
        STATUS_UNKNOWN
    } else if first & 0x10 == 0 {
        STATUS_NO_VIDEO
    } else if first & 0x20 != 0 {
        STATUS_PORTRAIT
    } else {
        STATUS_LANDSCAPE
    };
    Ok(Report {
        version,
        quat,
        vel_quat,
        status,
    })
}

/// The HDK driver.
pub struct HdkDriver {
    name: String,
    tracker: TrackerServer,
    analog: AnalogServer,
    count: u32,
    greeted: bool,
}

impl HdkDriver {
    /// The driver for `vrpn_Tracker_OSVRHackerDevKit NAME`.
    pub fn new(name: &str, conn: &Connection) -> Result<HdkDriver, Error> {
        Ok(HdkDriver {
            name: name.to_string(),
            tracker: TrackerServer::new(name, conn, 1)?,
            analog: AnalogServer::new(name, conn, 2)?,
            count: 0,
            greeted: false,
        })
    }

    fn warn(&self, args: std::fmt::Arguments<'_>) {
        with_text(args, |t| {
            let _ = self.analog.send_text(TextSeverity::Warning, 0, t);
        });
    }
}

impl HidDriver for HdkDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        vec![HidMatch::product(IDS[0].0, IDS[0].1).or_product(IDS[1].0, IDS[1].1)]
    }

    fn opened(&mut self, _now: Now, _nodes: &[Option<NodeInfo>], _ops: &mut HidOps) {
        self.greeted = false;
    }

    fn report(&mut self, _interface: usize, r: &[u8], at: Now, _ops: &mut HidOps) {
        let rep = match decode(r) {
            Ok(rep) => rep,
            Err(Bad::Length(n)) => {
                return self.warn(format_args!(
                    "Received a report {n} in length, but expected it to be 32 or 16 bytes. \
                     Discarding. (May indicate issues with HID!)"
                ))
            }
            Err(Bad::V2Length(n)) => {
                return self.warn(format_args!(
                    "Received a v2 report {n} in length, but expected it to be 16 bytes. \
                     Discarding. (May indicate issues with HID!)"
                ))
            }
        };
        if !self.greeted {
            self.greeted = true;
            let v = rep.version;
            with_text(
                format_args!(
                    "Successfully connected to OSVR Hacker Dev Kit HMD, receiving version {v} \
                     reports."
                ),
                |t| {
                    let _ = self.analog.send_text(TextSeverity::Normal, 0, t);
                },
            );
            if v > 3 {
                self.warn(format_args!(
                    "Connected to OSVR Hacker Dev Kit HMD, receiving version {v} reports, newer \
                     than what is specifically recognized. You may want to update your server \
                     to best make use of this new report format."
                ));
            }
        }
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self
            .tracker
            .report_pose(0usize, at.wall, [0.0; 3], rep.quat);
        if let Some(vq) = rep.vel_quat {
            let _ = self
                .tracker
                .report_velocity(0usize, at.wall, [0.0; 3], vq, DT);
        }
        self.analog.set_channel(0, f64::from(rep.version));
        self.analog.set_channel(1, rep.status);
        let _ = if self.count == 0 {
            self.analog.report(Some(at.wall)).map(|_| true)
        } else {
            self.analog.report_changes(Some(at.wall))
        };
        self.count = (self.count + 1) % STATUS_STRIDE;
    }

    fn closed(&mut self, now: Now) {
        self.analog.set_channel(0, 0.0);
        self.analog.set_channel(1, STATUS_UNKNOWN);
        let _ = self.analog.report_changes(Some(now.wall));
    }

    fn next_deadline(&self) -> Option<Instant> {
        None
    }
}

/// The running device, waiting for the HMD to be plugged in.
pub fn build(
    name: &str,
    conn: &Connection,
    hub: &DeviceHub,
) -> Result<Box<dyn ServerDevice>, Error> {
    Ok(Box::new(HidDevice::new(
        HdkDriver::new(name, conn)?,
        hub,
        conn,
    )))
}
