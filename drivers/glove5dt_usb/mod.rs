//! 5DT Data Glove over USB HID (C++ `vrpn_Analog_5dtUSB_*`): finger flexure as analog
//! channels.
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Analog_5dtUSB_Glove5Left NAME
//! vrpn_Analog_5dtUSB_Glove5Right NAME
//! vrpn_Analog_5dtUSB_Glove14Left NAME
//! vrpn_Analog_5dtUSB_Glove14Right NAME
//! ```
//!
//! # Which glove
//!
//! Vendor 0x5d70; the product id's bit 0 says left hand, bit 4 a 5-sensor glove (the other
//! bits, wired or wireless port, do not matter), as C++ selects it. When the glove opens, a
//! normal text says what it is: `Successfully connected to 5DT glove, left hand, 5 sensors,
//! wired USB`.
//!
//! # What is sent
//!
//! An Analog named `NAME` with 5 or 14 channels. Every report is 64 bytes: sixteen signed
//! 16-bit big-endian values, each × 1/4096 in single precision. The 14-sensor glove sends
//! values 0-13 on channels 0-13; the 5-sensor glove values 0, 3, 6, 9, 12 on channels 0-4.
//! A report of another length is skipped with a warning text (at most one a second).
//!
//! # Differences from C++ VRPN
//!
//! * One Analog report per glove report (C++ sends one after setting each channel, so a
//!   client sees up to 14 intermediate states).

pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use crate::devices::ServerDevice;
use crate::drivers::hid_pad::{be_i16, Pad, PadDecoder, PadDriver, PadState, Skip};
use crate::hid::{DeviceHub, HidDevice, HidMatch, InterfaceRule, NodeInfo, NodeKind, Select};
use crate::{Connection, Error};

/// 5DT's vendor id.
pub const VENDOR: u16 = 0x5d70;
/// Product bit: left hand.
pub const LEFT: u16 = 0x0001;
/// Product bit: wireless, port A.
pub const WIRELESS_A: u16 = 0x0002;
/// Product bits: wireless, port B.
pub const WIRELESS_B: u16 = 0x0006;
/// Product bit: the 5-sensor glove.
pub const FIVE: u16 = 0x0010;

/// One glove.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The vrpn.cfg keyword.
    pub keyword: &'static str,
    /// Sensors (channels).
    pub sensors: usize,
    /// Left hand.
    pub left: bool,
}

/// The four keywords.
pub const MODELS: &[Model] = &[
    Model {
        keyword: "vrpn_Analog_5dtUSB_Glove5Left",
        sensors: 5,
        left: true,
    },
    Model {
        keyword: "vrpn_Analog_5dtUSB_Glove5Right",
        sensors: 5,
        left: false,
    },
    Model {
        keyword: "vrpn_Analog_5dtUSB_Glove14Left",
        sensors: 14,
        left: true,
    },
    Model {
        keyword: "vrpn_Analog_5dtUSB_Glove14Right",
        sensors: 14,
        left: false,
    },
];

/// The glove a keyword names.
pub fn model(keyword: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.keyword == keyword)
}

impl Model {
    /// The product bits that select this glove.
    pub fn product_bits(&self) -> u16 {
        (if self.left { LEFT } else { 0 }) | (if self.sensors == 5 { FIVE } else { 0 })
    }

    /// How a glove is selected: vendor, and the hand and size bits of the product.
    pub fn matcher(&self) -> HidMatch {
        HidMatch {
            kind: NodeKind::Hidraw,
            any_of: vec![Select::Product {
                vendor: VENDOR,
                product: self.product_bits(),
                mask: LEFT | FIVE,
            }],
            interface: InterfaceRule::Any,
            nth: 0,
        }
    }
}

/// What C++ says a product id is.
pub fn description(product: u16) -> String {
    let hand = if product & LEFT != 0 { "left" } else { "right" };
    let sensors = if product & FIVE != 0 { "5" } else { "14" };
    let link = if product & WIRELESS_A != 0 {
        "wireless port A"
    } else if product & WIRELESS_B != 0 {
        "wireless port B"
    } else {
        "wired USB"
    };
    format!("{hand} hand, {sensors} sensors, {link}")
}

/// Decodes a glove's reports.
#[derive(Clone, Copy, Debug)]
pub struct Decoder {
    sensors: usize,
}

impl Decoder {
    /// The decoder for `model`.
    pub fn new(model: &Model) -> Decoder {
        Decoder {
            sensors: model.sensors,
        }
    }
}

impl PadDecoder for Decoder {
    fn decode(&mut self, r: &[u8], s: &mut PadState) -> Result<(), Skip> {
        if r.len() != 64 {
            return Err(Skip::Length(r.len()));
        }
        let raw = |i: usize| f64::from(f32::from(be_i16(r, 2 * i)) * (1.0f32 / 4096.0f32));
        let stride = if self.sensors == 5 { 3 } else { 1 };
        for i in 0..self.sensors {
            s.channel[i] = raw(i * stride);
        }
        Ok(())
    }

    fn greeting(&self, node: Option<&NodeInfo>) -> Option<String> {
        let product = node.map_or(0, |n| n.ids().1);
        Some(format!(
            "Successfully connected to 5DT glove, {}",
            description(product)
        ))
    }
}

/// The driver for one configuration line.
pub type GloveDriver = PadDriver<Decoder>;

/// The driver for `keyword NAME`.
pub fn driver(model: &Model, name: &str, conn: &Connection) -> Result<GloveDriver, Error> {
    let pad = Pad::new(name, conn, Some(model.sensors), None, None)?;
    Ok(PadDriver::new(
        name,
        conn,
        model.matcher(),
        pad,
        Decoder::new(model),
    ))
}

/// The running device for `keyword NAME`, waiting for the glove to be plugged in.
pub fn build(
    model: &Model,
    name: &str,
    conn: &Connection,
    hub: &DeviceHub,
) -> Result<Box<dyn ServerDevice>, Error> {
    Ok(Box::new(HidDevice::new(
        driver(model, name, conn)?,
        hub,
        conn,
    )))
}

/// The vrpn.cfg line that would serve `node`, if it is a 5DT glove.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    let m = MODELS
        .iter()
        .find(|m| h.vendor == VENDOR && h.product & (LEFT | FIVE) == m.product_bits())?;
    Some(format!("{} Glove0", m.keyword))
}
