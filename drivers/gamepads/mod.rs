//! Game controllers over USB HID with a fixed report layout (C++ `vrpn_Microsoft_*`,
//! `vrpn_Afterglow_*`, `vrpn_Logitech_Extreme_3D_Pro`, `vrpn_Saitek_ST290_Pro`,
//! `vrpn_CHProducts_Fighterstick_USB`, `vrpn_Retrolink_*`, `vrpn_Futaba_InterLink_Elite`,
//! `vrpn_nVidia_shield_*`).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Microsoft_SideWinder_Precision_2 NAME
//! vrpn_Microsoft_SideWinder NAME
//! vrpn_Microsoft_Controller_Raw_Xbox_S NAME
//! vrpn_Microsoft_Controller_Raw_Xbox_360 NAME [VENDOR PRODUCT]
//! vrpn_Microsoft_Controller_Raw_Xbox_360_Wireless NAME
//! vrpn_Afterglow_Ax1_For_Xbox_360 NAME
//! vrpn_Logitech_Extreme_3D_Pro NAME
//! vrpn_Saitek_ST290_Pro NAME
//! vrpn_CHProducts_Fighterstick_USB NAME
//! vrpn_Retrolink_GameCube NAME
//! vrpn_Retrolink_Genesis NAME
//! vrpn_Futaba_InterLink_Elite NAME
//! vrpn_nVidia_shield_USB NAME
//! vrpn_nVidia_shield_stealth_USB NAME
//! ```
//!
//! `VENDOR PRODUCT` (hexadecimal, `0x` optional) serve any controller that reports like an
//! Xbox 360 one (C++ lists the Logitech F310 as `0x046D 0xC21D`).
//!
//! # What is sent
//!
//! An Analog, a Button and (where the C++ class has one) an empty Dial, all named `NAME`,
//! with C++'s counts ([`MODELS`]) and its channel and button numbering (see docs/DRIVERS.md
//! for the table per controller). Hats are four direction buttons plus a channel holding the
//! angle in degrees clockwise from up (−1 when centred).
//!
//! # Differences from C++ VRPN
//!
//! * Each report is sent as soon as it is read, stamped with its read time; controllers
//!   whose C++ driver sends its whole Analog every 1/30 s whether or not it changed still
//!   do, stamped with the pass that sends it.
//! * Reports of unknown length or type are counted and reported as text warnings (at most
//!   one a second) instead of lines on the server's standard error.

pub mod config;
pub mod decode;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use crate::devices::ServerDevice;
use crate::drivers::hid_pad::{Pad, PadDecoder, PadDriver, PadState, Skip};
use crate::hid::{DeviceHub, HidDevice, HidMatch};
use crate::{Connection, Error};

/// How a controller's reports are read.
pub type DecodeFn = fn(&[u8], &mut PadState) -> Result<(), Skip>;

/// One controller.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The vrpn.cfg keyword.
    pub keyword: &'static str,
    /// USB vendor id.
    pub vendor: u16,
    /// USB product id.
    pub product: u16,
    /// Analog channels.
    pub channels: usize,
    /// Buttons.
    pub buttons: usize,
    /// Whether the C++ class has a (zero-dial) Dial.
    pub dial: bool,
    /// Whether C++ sends the whole Analog every 1/30 s.
    pub repeat: bool,
    /// The report format.
    pub decode: DecodeFn,
}

#[allow(clippy::too_many_arguments)]
const fn m(
    keyword: &'static str,
    vendor: u16,
    product: u16,
    channels: usize,
    buttons: usize,
    dial: bool,
    repeat: bool,
    decode: DecodeFn,
) -> Model {
    Model {
        keyword,
        vendor,
        product,
        channels,
        buttons,
        dial,
        repeat,
        decode,
    }
}

/// Microsoft's vendor id.
pub const MICROSOFT: u16 = 0x045e;

/// Every controller C++ 07.38 serves.
pub const MODELS: &[Model] = &[
    m(
        "vrpn_Microsoft_SideWinder_Precision_2",
        MICROSOFT,
        0x0038,
        5,
        12,
        true,
        true,
        decode::sidewinder_precision_2,
    ),
    m(
        "vrpn_Microsoft_SideWinder",
        MICROSOFT,
        0x003c,
        3,
        8,
        true,
        true,
        decode::sidewinder,
    ),
    m(
        "vrpn_Microsoft_Controller_Raw_Xbox_S",
        MICROSOFT,
        0x0289,
        5,
        16,
        true,
        false,
        decode::xbox_s,
    ),
    m(
        "vrpn_Microsoft_Controller_Raw_Xbox_360",
        MICROSOFT,
        0x028e,
        6,
        18,
        true,
        true,
        decode::xbox_360,
    ),
    m(
        "vrpn_Microsoft_Controller_Raw_Xbox_360_Wireless",
        MICROSOFT,
        0x02a1,
        6,
        18,
        true,
        true,
        decode::xbox_360,
    ),
    m(
        "vrpn_Afterglow_Ax1_For_Xbox_360",
        0x0e6f,
        0x0213,
        6,
        18,
        true,
        true,
        decode::xbox_360,
    ),
    m(
        "vrpn_Logitech_Extreme_3D_Pro",
        0x046d,
        0xc215,
        5,
        16,
        true,
        true,
        decode::logitech_extreme_3d_pro,
    ),
    m(
        "vrpn_Saitek_ST290_Pro",
        0x06a3,
        0x0d60,
        5,
        10,
        true,
        true,
        decode::saitek_st290_pro,
    ),
    m(
        "vrpn_CHProducts_Fighterstick_USB",
        0x068e,
        0x00f3,
        8,
        24,
        true,
        true,
        decode::ch_fighterstick,
    ),
    m(
        "vrpn_Retrolink_GameCube",
        0x0079,
        0x0006,
        5,
        12,
        false,
        true,
        decode::retrolink_gamecube,
    ),
    m(
        "vrpn_Retrolink_Genesis",
        0x0079,
        0x0011,
        1,
        12,
        false,
        true,
        decode::retrolink_genesis,
    ),
    m(
        "vrpn_Futaba_InterLink_Elite",
        0x1781,
        0x0e56,
        5,
        18,
        true,
        true,
        decode::futaba_interlink_elite,
    ),
    m(
        "vrpn_nVidia_shield_USB",
        0x0955,
        0x7210,
        10,
        21,
        false,
        false,
        decode::shield,
    ),
    m(
        "vrpn_nVidia_shield_stealth_USB",
        0x0955,
        0x7214,
        10,
        21,
        false,
        false,
        decode::shield_stealth,
    ),
];

/// The controller a keyword names.
pub fn model(keyword: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.keyword == keyword)
}

/// A controller's decoder.
#[derive(Clone, Copy, Debug)]
pub struct Decoder {
    decode: DecodeFn,
    repeat: bool,
}

impl PadDecoder for Decoder {
    fn decode(&mut self, report: &[u8], state: &mut PadState) -> Result<(), Skip> {
        (self.decode)(report, state)
    }

    fn repeats_analog(&self) -> bool {
        self.repeat
    }
}

/// The driver for one configuration line.
pub type GamepadDriver = PadDriver<Decoder>;

/// The driver for `keyword NAME`, on the model's ids or on `ids` (vendor, product).
pub fn driver(
    model: &Model,
    name: &str,
    ids: Option<(u16, u16)>,
    conn: &Connection,
) -> Result<GamepadDriver, Error> {
    let pad = Pad::new(
        name,
        conn,
        Some(model.channels),
        Some(model.buttons),
        model.dial.then_some(0),
    )?;
    let (vendor, product) = ids.unwrap_or((model.vendor, model.product));
    Ok(PadDriver::new(
        name,
        conn,
        HidMatch::product(vendor, product),
        pad,
        Decoder {
            decode: model.decode,
            repeat: model.repeat,
        },
    ))
}

/// The running device for `keyword NAME`, waiting for the controller to be plugged in.
pub fn build(
    model: &Model,
    name: &str,
    ids: Option<(u16, u16)>,
    conn: &Connection,
    hub: &DeviceHub,
) -> Result<Box<dyn ServerDevice>, Error> {
    Ok(Box::new(HidDevice::new(
        driver(model, name, ids, conn)?,
        hub,
        conn,
    )))
}

/// A hexadecimal id as C++'s `%x` reads it (`045e`, `0x045E`).
pub fn parse_hex_id(s: &str) -> Option<u16> {
    let digits = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .unwrap_or(s);
    u16::from_str_radix(digits, 16).ok()
}

/// The vrpn.cfg line that would serve `node`, if it is one of these controllers.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    let m = MODELS
        .iter()
        .find(|m| (m.vendor, m.product) == (h.vendor, h.product))?;
    Some(format!("{} Gamepad0", m.keyword))
}
