//! P.I. Engineering X-keys over USB HID (C++ `vrpn_Xkeys_*`): key pads, jog-and-shuttle and
//! joystick models, with their red and green LEDs showing whether a client is connected.
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Xkeys_Desktop NAME
//! vrpn_Xkeys_Pro NAME
//! vrpn_Xkeys_Joystick NAME
//! vrpn_Xkeys_Joystick12 NAME
//! vrpn_Xkeys_Jog_And_Shuttle NAME
//! vrpn_Xkeys_Jog_And_Shuttle12 NAME
//! vrpn_Xkeys_Jog_And_Shuttle68 NAME
//! vrpn_Xkeys_XK3 NAME
//! ```
//!
//! # What is sent
//!
//! Interfaces named `NAME`, as C++ ([`MODELS`]). Button 0 is the programming switch (set
//! when it is in the red position) on every model but the XK3; the keys follow in
//! column-major order. On the jog-and-shuttle models channel 0 is the shuttle (−1…1 in
//! sevenths), channel 1 the jog wheel (its position 0-255 on the original model, the sum of
//! its turns on the 12- and 68-key ones), and dial 0 the jog's turns (1/256 revolution per
//! tick on the original, 1/10 on the others). On the joysticks channels 0 and 1 are X and Y
//! (−1…1) and channel 2 the twist's total turns, dial 0 its turns (1/256 revolution per
//! tick).
//!
//! # LEDs
//!
//! Models with LEDs show red while no client is connected and green while one is, as C++:
//! red when the device opens with nobody connected, green on every client's connection,
//! red again when the last one leaves, both off when the server stops. The original models
//! take one 9-byte output report (byte 8: 0x80 red, 0x40 green); the 12- and 68-key models
//! two 36-byte reports (`00 b3 07 s` for red, `00 b3 06 s` for green, `s` 0 off, 1 on).
//!
//! # Differences from C++ VRPN
//!
//! * Reports are stamped with the time they were read (C++ stamps the time of the pass
//!   after the read).
//! * A report of unexpected length or failing its check is counted and reported as a text
//!   warning (at most one a second), not printed on the server's standard error.

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

use super::hid_pad::{Pad, PadDecoder, PadDriver, PadState, Skip};

/// P.I. Engineering's vendor id.
pub const VENDOR: u16 = 0x05f3;

/// How a model reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// 20 keys in 11-byte reports.
    Desktop,
    /// 58 keys in 8+6 or 14-byte reports.
    Pro,
    /// The original joystick model.
    Joystick,
    /// The 12-key joystick model, 32-byte reports.
    Joystick12,
    /// The original jog-and-shuttle.
    JogAndShuttle,
    /// The 12-key jog-and-shuttle, 32-byte reports.
    JogAndShuttle12,
    /// The 68-key jog-and-shuttle, 32-byte reports.
    JogAndShuttle68,
    /// The three-pedal foot switch, 32-byte reports.
    Xk3,
}

/// How a model's LEDs are set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leds {
    /// No LEDs: nothing is written.
    None,
    /// One 9-byte output report.
    V1,
    /// Two 36-byte output reports.
    V2,
}

/// One model.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The vrpn.cfg keyword.
    pub keyword: &'static str,
    /// USB product id.
    pub product: u16,
    /// Report layout.
    pub kind: Kind,
    /// LED protocol.
    pub leds: Leds,
    /// Analog channels (`None`: no Analog).
    pub channels: Option<usize>,
    /// Buttons.
    pub buttons: usize,
    /// Dials (`None`: no Dial).
    pub dials: Option<usize>,
}

/// Every model C++ 07.38 serves, with its interfaces.
pub const MODELS: &[Model] = &[
    Model {
        keyword: "vrpn_Xkeys_Desktop",
        product: 0x0281,
        kind: Kind::Desktop,
        leds: Leds::V1,
        channels: None,
        buttons: 21,
        dials: None,
    },
    Model {
        keyword: "vrpn_Xkeys_Pro",
        product: 0x0291,
        kind: Kind::Pro,
        leds: Leds::V1,
        channels: None,
        buttons: 59,
        dials: None,
    },
    Model {
        keyword: "vrpn_Xkeys_Joystick",
        product: 0x0251,
        kind: Kind::Joystick,
        leds: Leds::V1,
        channels: Some(2),
        buttons: 59,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Xkeys_Joystick12",
        product: 0x0429,
        kind: Kind::Joystick12,
        leds: Leds::V2,
        channels: Some(3),
        buttons: 13,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Xkeys_Jog_And_Shuttle",
        product: 0x0241,
        kind: Kind::JogAndShuttle,
        leds: Leds::V1,
        channels: Some(2),
        buttons: 59,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Xkeys_Jog_And_Shuttle12",
        product: 0x0426,
        kind: Kind::JogAndShuttle12,
        leds: Leds::V2,
        channels: Some(2),
        buttons: 13,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Xkeys_Jog_And_Shuttle68",
        product: 0x045a,
        kind: Kind::JogAndShuttle68,
        leds: Leds::V2,
        channels: Some(2),
        buttons: 69,
        dials: Some(1),
    },
    Model {
        keyword: "vrpn_Xkeys_XK3",
        product: 0x042c,
        kind: Kind::Xk3,
        leds: Leds::None,
        channels: None,
        buttons: 3,
        dials: None,
    },
];

/// The model a keyword names.
pub fn model(keyword: &str) -> Option<&'static Model> {
    MODELS.iter().find(|m| m.keyword == keyword)
}

/// An LED's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Led {
    /// Off.
    Off,
    /// On.
    On,
}

/// The output reports that set the LEDs, as C++ writes them.
pub fn led_reports(leds: Leds, red: Led, green: Led) -> Vec<Vec<u8>> {
    match leds {
        Leds::None => Vec::new(),
        Leds::V1 => {
            let mut r = vec![0u8; 9];
            if red == Led::On {
                r[8] |= 0x80;
            }
            if green == Led::On {
                r[8] |= 0x40;
            }
            vec![r]
        }
        Leds::V2 => [(7u8, red), (6u8, green)]
            .into_iter()
            .map(|(led, s)| {
                let mut r = vec![0u8; 36];
                r[1] = 0xb3;
                r[2] = led;
                r[3] = u8::from(s == Led::On);
                r
            })
            .collect(),
    }
}

/// Decodes a model's reports.
#[derive(Clone, Copy, Debug)]
pub struct Decoder {
    model: Model,
    got_dial: bool,
    last_dial: u8,
}

/// Keys 1… of the original models: 7 per byte from byte `first`.
fn keys7(
    buf: &[u8],
    first_byte: usize,
    keys: std::ops::Range<usize>,
    base: usize,
    s: &mut PadState,
) {
    for btn in keys {
        let local = btn - base;
        s.button[btn + 1] = buf[local / 7 + first_byte] & (1 << (local % 7)) != 0;
    }
}

/// The second half (6 bytes) of an original 14-byte report, or its end: the programming
/// switch and keys 35-57.
fn tail6(buf: &[u8], s: &mut PadState) -> Result<(), Skip> {
    if buf[5] & 0x08 == 0 {
        return Err(Skip::Corrupt);
    }
    s.button[0] = buf[5] & 0x10 != 0;
    keys7(buf, 0, 35..58, 35, s);
    Ok(())
}

/// A whole 14-byte report of an original model: the switch and keys 0-57.
fn whole14(r: &[u8], s: &mut PadState) -> Result<(), Skip> {
    if r[13] & 0x08 == 0 {
        return Err(Skip::Corrupt);
    }
    s.button[0] = r[13] & 0x10 != 0;
    keys7(r, 3, 0..58, 0, s);
    Ok(())
}

/// `(a - b)` as C++ computes `static_cast<vrpn_int8>(a - b)`.
fn delta(a: u8, b: u8) -> f64 {
    f64::from(a.wrapping_sub(b) as i8)
}

fn signed(b: u8) -> f64 {
    f64::from(b as i8)
}

impl Decoder {
    /// The decoder for `model`.
    pub fn new(model: &Model) -> Decoder {
        Decoder {
            model: *model,
            got_dial: false,
            last_dial: 0,
        }
    }

    fn dial256(&mut self, value: u8, s: &mut PadState, always: bool) {
        if always || self.got_dial {
            s.dial[0] = delta(value, self.last_dial) / 256.0;
        }
        self.got_dial = true;
        self.last_dial = value;
    }
}

impl PadDecoder for Decoder {
    fn decode(&mut self, r: &[u8], s: &mut PadState) -> Result<(), Skip> {
        let n = r.len();
        match self.model.kind {
            Kind::Desktop => {
                if n < 11 {
                    return Err(Skip::Length(n));
                }
                for c in r.chunks_exact(11) {
                    if c[10] & 0x08 == 0 {
                        return Err(Skip::Corrupt);
                    }
                    s.button[0] = c[10] & 0x10 != 0;
                    for btn in 0..20 {
                        s.button[btn + 1] = c[btn / 5] & (1 << (btn % 5)) != 0;
                    }
                }
            }
            Kind::Pro => match n {
                8 => keys7(r, 3, 0..35, 0, s),
                6 => tail6(r, s)?,
                14 => whole14(r, s)?,
                _ => return Err(Skip::Length(n)),
            },
            Kind::Joystick => match n {
                8 => {
                    s.channel[0] = f64::from(f32::from(r[0]) - 128.0) / 128.0;
                    s.channel[1] = f64::from(f32::from(r[1]) - 128.0) / 128.0;
                    s.channel[2] = f64::from(f32::from(r[2]) - 128.0) / 128.0;
                    keys7(r, 3, 0..35, 0, s);
                }
                6 => tail6(r, s)?,
                14 => {
                    whole14(r, s)?;
                    self.dial256(r[2], s, false);
                    // C++ sets channels 0 and 1 twice and adds the turn twice; the second
                    // assignment stands.
                    s.channel[2] += s.dial[0];
                    s.channel[0] = f64::from(f32::from(r[0]) - 128.0) / 128.0;
                    s.channel[1] = -f64::from(f32::from(r[1]) - 128.0) / 128.0;
                    s.channel[2] += s.dial[0];
                }
                _ => return Err(Skip::Length(n)),
            },
            Kind::JogAndShuttle => match n {
                8 | 14 => {
                    if n == 8 {
                        keys7(r, 3, 0..35, 0, s);
                    } else {
                        whole14(r, s)?;
                    }
                    s.channel[0] = signed(r[0]) / 7.0;
                    s.channel[1] = f64::from(r[1]);
                    self.dial256(r[1], s, true);
                }
                6 => tail6(r, s)?,
                _ => return Err(Skip::Length(n)),
            },
            Kind::JogAndShuttle12 | Kind::JogAndShuttle68 | Kind::Joystick12 => {
                if n == 0 || n % 32 != 0 {
                    return Err(Skip::Length(n));
                }
                for c in r.chunks_exact(32) {
                    // C++ also means to check that the tail bytes are zero, but its check
                    // has no effect; only the first byte counts.
                    if c[0] != 0 {
                        return Err(Skip::Corrupt);
                    }
                    s.button[0] = c[1] & 0x01 != 0;
                    match self.model.kind {
                        Kind::JogAndShuttle68 => {
                            for btn in 0..68 {
                                let slot = btn
                                    + 3 * (usize::from(btn > 28)
                                        + usize::from(btn > 33)
                                        + usize::from(btn > 38)
                                        + usize::from(btn > 43));
                                s.button[btn + 1] = c[slot / 8 + 2] & (1 << (slot % 8)) != 0;
                            }
                            s.dial[0] = signed(c[16]) / 10.0;
                            s.channel[0] = signed(c[17]) / 7.0;
                            s.channel[1] += s.dial[0];
                        }
                        _ => {
                            for btn in 0..12 {
                                s.button[btn + 1] = c[btn / 3 + 2] & (1 << (btn % 3)) != 0;
                            }
                            if self.model.kind == Kind::JogAndShuttle12 {
                                s.dial[0] = signed(c[6]) / 10.0;
                                s.channel[0] = signed(c[7]) / 7.0;
                                s.channel[1] += s.dial[0];
                            } else {
                                self.dial256(c[8], s, false);
                                s.channel[0] = signed(c[6]) / 127.0;
                                s.channel[1] = -signed(c[7]) / 127.0;
                                s.channel[2] += s.dial[0];
                            }
                        }
                    }
                }
            }
            Kind::Xk3 => {
                if n < 32 {
                    return Err(Skip::Length(n));
                }
                for c in r.chunks_exact(32) {
                    if c[0] != 0 || c[1] != 1 {
                        return Err(Skip::Corrupt);
                    }
                    s.button[0] = c[2] & 0x02 != 0;
                    s.button[1] = c[2] & 0x04 != 0;
                    s.button[2] = c[2] & 0x08 != 0;
                }
            }
        }
        Ok(())
    }

    fn opened(&mut self, _s: &mut PadState, _ops: &mut HidOps) {
        self.got_dial = false;
        self.last_dial = 0;
    }

    fn clients(&mut self, any: bool, ops: &mut HidOps) {
        let (red, green) = if any {
            (Led::Off, Led::On)
        } else {
            (Led::On, Led::Off)
        };
        for r in led_reports(self.model.leds, red, green) {
            ops.output(0, &r);
        }
    }

    fn shutdown(&mut self, ops: &mut HidOps) {
        for r in led_reports(self.model.leds, Led::Off, Led::Off) {
            ops.output(0, &r);
        }
    }
}

/// The driver for one configuration line.
pub type XkeysDriver = PadDriver<Decoder>;

/// The driver for `keyword NAME`.
pub fn driver(model: &Model, name: &str, conn: &Connection) -> Result<XkeysDriver, Error> {
    let pad = Pad::new(name, conn, model.channels, Some(model.buttons), model.dials)?;
    Ok(PadDriver::new(
        name,
        conn,
        HidMatch::product(VENDOR, model.product),
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
        .find(|m| (VENDOR, m.product) == (h.vendor, h.product))?;
    Some(format!("{} Xkeys0", m.keyword))
}
