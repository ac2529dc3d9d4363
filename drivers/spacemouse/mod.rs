//! 3Dconnexion SpaceMouse family over USB HID (C++ `vrpn_3DConnexion_*`): six axes and the
//! device's buttons.
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_3DConnexion_Navigator NAME
//! vrpn_3DConnexion_Navigator_for_Notebooks NAME
//! vrpn_3DConnexion_Traveler NAME
//! vrpn_3DConnexion_SpaceMouse NAME
//! vrpn_3DConnexion_SpaceMousePro NAME
//! vrpn_3DConnexion_SpaceMouseCompact NAME
//! vrpn_3DConnexion_SpaceMouseWireless NAME
//! vrpn_3DConnexion_SpaceMouseWireless2 NAME
//! vrpn_3DConnexion_SpaceMouseProWireless NAME
//! vrpn_3DConnexion_SpaceExplorer NAME
//! vrpn_3DConnexion_SpaceBall5000 NAME
//! vrpn_3DConnexion_SpacePilot NAME
//! vrpn_3DConnexion_SpacePilotPro NAME
//! ```
//!
//! # What is sent
//!
//! An Analog with 6 channels and a Button with the model's button count ([`MODELS`]), both
//! named `NAME`. Channels 0-2 are translation X, Y, Z and 3-5 rotation, each a signed 16-bit
//! count × (1/400) in single precision (1/350 on the SpaceMouse Pro Wireless), clamped to
//! −1…1. Button *n* is bit *n % 8* of the report's byte *1 + n / 8*.
//!
//! # Reports
//!
//! Report 1 carries translation (`01 xl xh yl yh zl zh`), report 2 rotation, report 3 the
//! buttons (`03 b0 b1 …`). The SpaceMouse Pro Wireless sends 13-byte reports: report 1 with
//! all six axes, report 3 with the buttons, report 0x17 (ignored).
//!
//! # Differences from C++ VRPN
//!
//! * A button byte the report does not have reads as zero (C++ reads whatever an earlier
//!   report left in its buffer there).
//! * One hidraw report is one VRPN report (C++ cuts reads into 7-byte pieces and reports
//!   after each).

pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use crate::devices::ServerDevice;
use crate::hid::driver::HidOps;
use crate::hid::{DeviceHub, HidDevice, HidMatch};
use crate::{Connection, Error};

use super::hid_pad::{le_i16, Pad, PadDecoder, PadDriver, PadState, Skip};

/// Logitech's vendor id, which the older models carry.
pub const LOGITECH: u16 = 0x046d;
/// 3Dconnexion's own vendor id (newer models).
pub const THREEDCONNEXION: u16 = 0x256f;

/// How a model's reports are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// 7-byte reports: 1 translation, 2 rotation, 3 buttons.
    Classic,
    /// 13-byte reports: 1 all six axes, 3 buttons, 0x17 ignored.
    ProWireless,
}

/// One model: its keyword, USB ids and button count (C++'s).
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The vrpn.cfg keyword.
    pub keyword: &'static str,
    /// USB vendor id.
    pub vendor: u16,
    /// USB product id.
    pub product: u16,
    /// Buttons.
    pub buttons: usize,
    /// Report layout.
    pub layout: Layout,
}

const fn m(keyword: &'static str, vendor: u16, product: u16, buttons: usize) -> Model {
    Model {
        keyword,
        vendor,
        product,
        buttons,
        layout: Layout::Classic,
    }
}

/// Every model C++ 07.38 serves.
pub const MODELS: &[Model] = &[
    m("vrpn_3DConnexion_Navigator", LOGITECH, 0xc626, 2),
    m(
        "vrpn_3DConnexion_Navigator_for_Notebooks",
        LOGITECH,
        0xc628,
        2,
    ),
    m("vrpn_3DConnexion_Traveler", LOGITECH, 0xc623, 8),
    m("vrpn_3DConnexion_SpaceMouse", LOGITECH, 0xc603, 11),
    m("vrpn_3DConnexion_SpaceMousePro", LOGITECH, 0xc62b, 27),
    m(
        "vrpn_3DConnexion_SpaceMouseCompact",
        THREEDCONNEXION,
        0xc635,
        2,
    ),
    m(
        "vrpn_3DConnexion_SpaceMouseWireless",
        THREEDCONNEXION,
        0xc62f,
        2,
    ),
    m(
        "vrpn_3DConnexion_SpaceMouseWireless2",
        THREEDCONNEXION,
        0xc62e,
        2,
    ),
    Model {
        keyword: "vrpn_3DConnexion_SpaceMouseProWireless",
        vendor: THREEDCONNEXION,
        product: 0xc631,
        buttons: 32,
        layout: Layout::ProWireless,
    },
    m("vrpn_3DConnexion_SpaceExplorer", LOGITECH, 0xc627, 15),
    m("vrpn_3DConnexion_SpaceBall5000", LOGITECH, 0xc621, 12),
    m("vrpn_3DConnexion_SpacePilot", LOGITECH, 0xc625, 21),
    m("vrpn_3DConnexion_SpacePilotPro", LOGITECH, 0xc629, 31),
];

/// The model a keyword names.
pub fn model(keyword: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.keyword == keyword)
}

/// Decodes a model's reports.
#[derive(Clone, Copy, Debug)]
pub struct Decoder {
    layout: Layout,
    buttons: usize,
}

/// A signed count times `scale`, in single precision as C++ computes it, clamped to −1…1.
fn axis(count: i16, scale: f32) -> f64 {
    f64::from(f32::from(count) * scale).clamp(-1.0, 1.0)
}

impl Decoder {
    /// The decoder for `model`.
    pub fn new(model: &Model) -> Decoder {
        Decoder {
            layout: model.layout,
            buttons: model.buttons,
        }
    }

    fn buttons(&self, report: &[u8], state: &mut PadState) {
        for n in 0..self.buttons {
            let byte = report.get(1 + n / 8).copied().unwrap_or(0);
            state.button[n] = byte & (1 << (n % 8)) != 0;
        }
    }
}

impl PadDecoder for Decoder {
    fn decode(&mut self, report: &[u8], state: &mut PadState) -> Result<(), Skip> {
        let kind = *report.first().ok_or(Skip::Length(0))?;
        let b = |i: usize| report.get(i).copied().unwrap_or(0);
        let count = |i: usize| le_i16(&[b(i), b(i + 1)], 0);
        match self.layout {
            Layout::Classic => {
                let scale = 1.0f32 / 400.0f32;
                match kind {
                    1 | 2 => {
                        let first = if kind == 1 { 0 } else { 3 };
                        for k in 0..3 {
                            state.channel[first + k] = axis(count(1 + 2 * k), scale);
                        }
                    }
                    3 => self.buttons(report, state),
                    other => return Err(Skip::Kind(other)),
                }
            }
            Layout::ProWireless => {
                if report.len() % 13 != 0 {
                    return Err(Skip::Length(report.len()));
                }
                let scale = 1.0f32 / 350.0f32;
                match kind {
                    1 => {
                        for k in 0..6 {
                            state.channel[k] = axis(count(1 + 2 * k), scale);
                        }
                    }
                    3 => self.buttons(report, state),
                    0x17 => return Err(Skip::Quiet),
                    other => return Err(Skip::Kind(other)),
                }
            }
        }
        Ok(())
    }

    fn opened(&mut self, _state: &mut PadState, _ops: &mut HidOps) {}
}

/// The driver for one configuration line.
pub type SpaceMouseDriver = PadDriver<Decoder>;

/// The driver for `keyword NAME`.
pub fn driver(model: &Model, name: &str, conn: &Connection) -> Result<SpaceMouseDriver, Error> {
    let pad = Pad::new(name, conn, Some(6), Some(model.buttons), None)?;
    Ok(PadDriver::new(
        name,
        conn,
        HidMatch::product(model.vendor, model.product),
        pad,
        Decoder::new(model),
    ))
}

/// The running device for `keyword NAME`, waiting for the model to be plugged in.
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

/// The vrpn.cfg line that would serve `node`, if it is one of these models.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    let m = MODELS
        .iter()
        .find(|m| (m.vendor, m.product) == (h.vendor, h.product))?;
    Some(format!("{} SpaceMouse0", m.keyword))
}
