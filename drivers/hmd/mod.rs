//! Head-mounted displays over USB HID: the inertial units of the Oculus Rift DK1 and DK2
//! (C++ `vrpn_Oculus_*`), the Laputa (`vrpn_Laputa`) and the Vality vGlass
//! (`vrpn_Vality_vGlass`) as analog channels, and the OSVR Hacker Dev Kit's orientation as a
//! tracker (`vrpn_Tracker_OSVRHackerDevKit`, [`hdk`]).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Oculus_DK1 NAME
//! vrpn_Oculus_DK2_LEDs NAME
//! vrpn_Oculus_DK2_inertial NAME
//! vrpn_Laputa NAME
//! vrpn_Vality_vGlass NAME
//! vrpn_Tracker_OSVRHackerDevKit NAME
//! ```
//!
//! # What is sent (inertial units)
//!
//! An Analog named `NAME`: channel 0 the temperature (°C), 1 the sample counter, 2-4 the
//! accelerometer (m/s²), 5-7 the gyroscope (rad/s), 8-10 the magnetometer (gauss); on the
//! DK2 with LEDs, channel 11 the device's clock (s). One Analog report per inertial sample
//! (a device report carries up to three), all stamped with the report's read time. The
//! vGlass has 9 channels: accelerometer (0-2) and gyroscope (3-5).
//!
//! # Keep-alive and LEDs
//!
//! The Oculus units stream only while the host keeps them alive: the driver sends C++'s
//! keep-alive feature report when the device opens and every 9 s after (`08 00 00 10 27` on
//! the DK1; `11 00 00 FF 10 27` on the DK2, where `FF` is 0x0b with the tracking LEDs on for
//! `vrpn_Oculus_DK2_LEDs`, 0x01 for `vrpn_Oculus_DK2_inertial`).
//!
//! # Differences from C++ VRPN
//!
//! * The first keep-alive goes out when the device opens (C++ waits 9 s, so a unit that is
//!   not already streaming stays silent that long).

pub mod config;
pub mod hdk;
pub mod imu;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use std::time::Instant;

use self::imu::Imu;
use crate::devices::ServerDevice;
use crate::driver::text::with_text;
use crate::drivers::hid_pad::Skip;
use crate::hid::{DeviceHub, HidDevice, HidDriver, HidMatch, HidOps, NodeInfo};
use crate::time::Now;
use crate::{AnalogServer, Connection, Error, TextSeverity};

/// Which inertial unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Oculus Rift DK1.
    Dk1,
    /// Oculus Rift DK2, tracking LEDs on or off.
    Dk2 {
        /// LEDs on.
        leds: bool,
    },
    /// Laputa.
    Laputa,
    /// Vality vGlass.
    Vality,
}

/// One unit.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The vrpn.cfg keyword.
    pub keyword: &'static str,
    /// USB vendor id.
    pub vendor: u16,
    /// USB product id.
    pub product: u16,
    /// The unit.
    pub kind: Kind,
    /// Analog channels.
    pub channels: usize,
}

/// Every inertial unit C++ 07.38 serves (the HDK is in [`hdk`]).
pub const MODELS: &[Model] = &[
    Model {
        keyword: "vrpn_Oculus_DK1",
        vendor: 0x2833,
        product: 0x0001,
        kind: Kind::Dk1,
        channels: 11,
    },
    Model {
        keyword: "vrpn_Oculus_DK2_LEDs",
        vendor: 0x2833,
        product: 0x0021,
        kind: Kind::Dk2 { leds: true },
        channels: 12,
    },
    Model {
        keyword: "vrpn_Oculus_DK2_inertial",
        vendor: 0x2833,
        product: 0x0021,
        kind: Kind::Dk2 { leds: false },
        channels: 11,
    },
    Model {
        keyword: "vrpn_Laputa",
        vendor: 0x2633,
        product: 0x0006,
        kind: Kind::Laputa,
        channels: 11,
    },
    Model {
        keyword: "vrpn_Vality_vGlass",
        vendor: 0x0483,
        product: 0x5740,
        kind: Kind::Vality,
        channels: 9,
    },
];

/// The unit a keyword names.
pub fn model(keyword: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.keyword == keyword)
}

/// An inertial unit's driver: see the module documentation.
pub struct ImuDriver {
    name: String,
    want: HidMatch,
    kind: Kind,
    analog: AnalogServer,
    imu: Imu,
    next_keep_alive: Option<Instant>,
    skipped: u64,
    last_skip_text: Option<Instant>,
}

impl ImuDriver {
    /// The driver for `model`'s line named `name`.
    pub fn new(model: &Model, name: &str, conn: &Connection) -> Result<ImuDriver, Error> {
        Ok(ImuDriver {
            name: name.to_string(),
            want: HidMatch::product(model.vendor, model.product),
            kind: model.kind,
            analog: AnalogServer::new(name, conn, model.channels)?,
            imu: Imu::default(),
            next_keep_alive: None,
            skipped: 0,
            last_skip_text: None,
        })
    }

    /// The Analog.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// Reports skipped.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    fn keep_alive(&mut self, now: Now, ops: &mut HidOps) {
        match self.kind {
            Kind::Dk1 => ops.set_feature(0, &imu::dk1_keep_alive()),
            Kind::Dk2 { leds } => ops.set_feature(0, &imu::dk2_keep_alive(leds)),
            Kind::Laputa | Kind::Vality => return,
        }
        self.next_keep_alive = Some(now.mono + imu::KEEP_ALIVE_PERIOD);
    }

    fn skip(&mut self, skip: Skip, at: Now) {
        self.skipped += 1;
        if self
            .last_skip_text
            .is_some_and(|t| at.mono < t + std::time::Duration::from_secs(1))
        {
            return;
        }
        self.last_skip_text = Some(at.mono);
        let name = &self.name;
        let send = |t: &str| {
            let _ = self.analog.send_text(TextSeverity::Warning, 0, t);
        };
        match skip {
            Skip::Length(n) => with_text(
                format_args!("{name}: unexpected report length {n}, ignoring"),
                send,
            ),
            Skip::Kind(k) => with_text(
                format_args!("{name}: unexpected report type {k}, ignoring"),
                send,
            ),
            _ => {}
        }
    }
}

impl HidDriver for ImuDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        vec![self.want.clone()]
    }

    fn opened(&mut self, now: Now, _nodes: &[Option<NodeInfo>], ops: &mut HidOps) {
        self.keep_alive(now, ops);
    }

    fn report(&mut self, _interface: usize, r: &[u8], at: Now, _ops: &mut HidOps) {
        let n = self.analog.num_channels();
        let analog = &mut self.analog;
        let mut send = |imu: &Imu| {
            analog.channels_mut().copy_from_slice(&imu.channel[..n]);
            // A failed send is the connection's business (it reports and drops the peer).
            let _ = analog.report_changes(Some(at.wall));
        };
        let result = match (self.kind, r.first()) {
            (Kind::Vality, _) => imu::vality(r, &mut self.imu).map(|()| send(&self.imu)),
            (_, Some(1)) => imu::type_1(r, &mut self.imu, send),
            (Kind::Dk2 { .. }, Some(11)) => imu::type_11(r, &mut self.imu, send),
            (_, Some(k)) => Err(Skip::Kind(*k)),
            (_, None) => Err(Skip::Length(0)),
        };
        if let Err(skip) = result {
            self.skip(skip, at);
        }
    }

    fn poll(&mut self, now: Now, ops: &mut HidOps) {
        if self.next_keep_alive.is_some_and(|t| now.mono >= t) {
            self.keep_alive(now, ops);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.next_keep_alive
    }

    fn closed(&mut self, _now: Now) {
        self.next_keep_alive = None;
    }
}

/// The running device for `keyword NAME`, waiting for the unit to be plugged in.
pub fn build(
    model: &Model,
    name: &str,
    conn: &Connection,
    hub: &DeviceHub,
) -> Result<Box<dyn ServerDevice>, Error> {
    Ok(Box::new(HidDevice::new(
        ImuDriver::new(model, name, conn)?,
        hub,
        conn,
    )))
}

/// The vrpn.cfg line that would serve `node`, if it is one of these displays.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    if hdk::IDS.contains(&(h.vendor, h.product)) {
        return Some(format!("{} Tracker0", hdk::KEYWORD));
    }
    let m = MODELS
        .iter()
        .find(|m| (m.vendor, m.product) == (h.vendor, h.product))?;
    Some(format!("{} Hmd0", m.keyword))
}
