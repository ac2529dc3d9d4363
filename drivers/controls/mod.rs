//! Knobs, shuttles and drums over USB HID: Contour ShuttleXpress and ShuttlePRO v2 (C++
//! `vrpn_Contour_*`), Griffin PowerMate (`vrpn_Griffin_PowerMate`), Dream Cheeky USB roll-up
//! drum kit (`vrpn_Dream_Cheeky_USB_roll_up_drums`).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Contour_ShuttleXpress NAME
//! vrpn_Contour_ShuttlePROv2 NAME
//! vrpn_Griffin_PowerMate NAME
//! vrpn_Dream_Cheeky_USB_roll_up_drums NAME
//! ```
//!
//! # What is sent
//!
//! - Contour: an Analog (channel 0 the shuttle ring, −1…1; channel 1 the jog wheel's total
//!   turns), a Button (5 on the Xpress, 15 on the PRO v2) and a Dial (the jog's turns, 1/10
//!   revolution per tick, from the second report on).
//! - PowerMate: a Button (the knob's press) and a Dial (the knob's turn in ticks, as C++
//!   reports it: one tick is 1.0), and an Analog with no channels.
//! - Drums: a Button with 6 pads. Each 8-byte report holds eight samples; a pad is pressed
//!   when at least four of them say so (C++'s debouncing).
//!
//! # Differences from C++ VRPN
//!
//! * Reports are sent as they are read, stamped with their read time (C++ sends the Contour
//!   and PowerMate state every 1/30 s; the PowerMate's Dial there repeats a zero turn every
//!   1/30 s between real ones, which is not reproduced).

pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use crate::devices::ServerDevice;
use crate::drivers::hid_pad::{normalize_byte_axis, Pad, PadDecoder, PadDriver, PadState, Skip};
use crate::hid::driver::HidOps;
use crate::hid::{DeviceHub, HidDevice, HidMatch};
use crate::{Connection, Error};

/// Which device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Contour ShuttleXpress.
    ShuttleXpress,
    /// Contour ShuttlePRO v2.
    ShuttlePro2,
    /// Griffin PowerMate.
    PowerMate,
    /// Dream Cheeky roll-up drums.
    Drums,
}

/// One device.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The vrpn.cfg keyword.
    pub keyword: &'static str,
    /// USB vendor id.
    pub vendor: u16,
    /// USB product id.
    pub product: u16,
    /// The device.
    pub kind: Kind,
    /// Analog channels (`None`: no Analog).
    pub channels: Option<usize>,
    /// Buttons.
    pub buttons: usize,
    /// Dials (`None`: no Dial).
    pub dials: Option<usize>,
}

/// Every device C++ 07.38 serves here.
pub const MODELS: &[Model] = &[
    Model {
        keyword: "vrpn_Contour_ShuttleXpress",
        vendor: 0x0b33,
        product: 0x0020,
        kind: Kind::ShuttleXpress,
        channels: Some(2),
        buttons: 5,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Contour_ShuttlePROv2",
        vendor: 0x0b33,
        product: 0x0030,
        kind: Kind::ShuttlePro2,
        channels: Some(2),
        buttons: 15,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Griffin_PowerMate",
        vendor: 0x077d,
        product: 0x0410,
        kind: Kind::PowerMate,
        channels: Some(0),
        buttons: 1,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Dream_Cheeky_USB_roll_up_drums",
        vendor: 0x1941,
        product: 0x8021,
        kind: Kind::Drums,
        channels: None,
        buttons: 6,
        dials: None,
    },
];

/// The device a keyword names.
pub fn model(keyword: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.keyword == keyword)
}

/// Decodes a device's reports.
#[derive(Clone, Copy, Debug)]
pub struct Decoder {
    kind: Kind,
    got_dial: bool,
    last_dial: u8,
}

impl Decoder {
    /// The decoder for `model`.
    pub fn new(model: &Model) -> Decoder {
        Decoder {
            kind: model.kind,
            got_dial: false,
            last_dial: 0,
        }
    }

    /// The Contours' jog wheel and shuttle ring (bytes 0 and 1).
    fn shuttle_and_jog(&mut self, r: &[u8], s: &mut PadState) {
        if self.got_dial {
            s.dial[0] = f64::from(r[1].wrapping_sub(self.last_dial) as i8) / 10.0;
        }
        self.got_dial = true;
        self.last_dial = r[1];
        // C++ maps the shuttle's −7…7 onto a byte in single precision, truncates it, then
        // centres it again.
        let value = (f32::from(r[0] as i8) * 128.0f32 / 7.0f32 + 128.0f32) as u32;
        s.channel[0] = normalize_byte_axis(value, 0, 1.0);
        s.channel[1] += s.dial[0];
    }
}

impl PadDecoder for Decoder {
    fn decode(&mut self, r: &[u8], s: &mut PadState) -> Result<(), Skip> {
        let want = match self.kind {
            Kind::ShuttleXpress | Kind::ShuttlePro2 => 5,
            Kind::PowerMate => 6,
            Kind::Drums => 8,
        };
        match self.kind {
            Kind::Drums if r.len() >= 8 => {
                for chunk in r.chunks_exact(8) {
                    for b in 0..6 {
                        let count = chunk.iter().filter(|x| *x & (1 << b) != 0).count();
                        s.button[b] = count >= 4;
                    }
                }
                return Ok(());
            }
            _ if r.len() != want => return Err(Skip::Length(r.len())),
            _ => {}
        }
        match self.kind {
            Kind::ShuttleXpress => {
                self.shuttle_and_jog(r, s);
                for b in 0..4 {
                    s.button[b] = r[3] & (0x10 << b) != 0;
                }
                s.button[4] = r[4] & 0x01 != 0;
            }
            Kind::ShuttlePro2 => {
                self.shuttle_and_jog(r, s);
                for b in 0..16 {
                    s.button[b] = r[3 + b / 8] & (1 << (b % 8)) != 0;
                }
            }
            Kind::PowerMate => {
                s.dial[0] = f64::from(r[1] as i8);
                s.button[0] = r[0] & 0x01 != 0;
            }
            Kind::Drums => {}
        }
        Ok(())
    }

    fn opened(&mut self, _s: &mut PadState, _ops: &mut HidOps) {
        self.got_dial = false;
        self.last_dial = 0;
    }
}

/// The driver for one configuration line.
pub type ControlDriver = PadDriver<Decoder>;

/// The driver for `keyword NAME`.
pub fn driver(model: &Model, name: &str, conn: &Connection) -> Result<ControlDriver, Error> {
    let pad = Pad::new(name, conn, model.channels, Some(model.buttons), model.dials)?;
    Ok(PadDriver::new(
        name,
        conn,
        HidMatch::product(model.vendor, model.product),
        pad,
        Decoder::new(model),
    ))
}

/// The running device for `keyword NAME`, waiting for it to be plugged in.
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

/// The vrpn.cfg line that would serve `node`, if it is one of these devices.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    let m = MODELS
        .iter()
        .find(|m| (m.vendor, m.product) == (h.vendor, h.product))?;
    Some(format!("{} Control0", m.keyword))
}
