//! Any HID game controller without a table (`vrpn_HID_Generic`, beyond C++): the driver reads
//! the device's report descriptor when it opens and serves its axes, hats and buttons as an
//! Analog and a Button.
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_HID_Generic NAME VENDOR:PRODUCT [INTERFACE]
//! vrpn_HID_Generic NAME "DEVICE NAME" [INTERFACE]
//! vrpn_HID_Generic NAME /dev/hidrawN
//! ```
//!
//! `VENDOR:PRODUCT` are hexadecimal USB ids (`045e:02e0`); `"DEVICE NAME"` is the kernel's
//! name for the device (`vrpn_server --list-devices` shows it); `INTERFACE` picks one USB
//! interface of a device that has several.
//!
//! # What is sent
//!
//! From the descriptor's variable input fields, in descriptor order:
//!
//! - axes (Generic Desktop X, Y, Z, Rx, Ry, Rz, slider, dial, wheel; every Simulation
//!   Controls usage: throttle, rudder, brake, …): one channel each, −1…1 — a signed range
//!   divided by its larger bound, an unsigned one mapped linearly from its minimum (−1) to
//!   its maximum (+1);
//! - hat switches: one channel each after the axes, the direction in degrees clockwise from
//!   up (−1 when centred), the logical range cut into eight directions as the Linux input
//!   layer does; and four buttons each (up, right, down, left) after the other buttons;
//! - buttons (the Button page, and one-bit system and consumer controls such as a
//!   controller's home button): one button each.
//!
//! Vendor-defined, LED, battery and undefined-page fields are not served. Each report is sent
//! as it is read: the Analog if a channel changed, then the buttons that changed.

pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use std::io;

use crate::devices::text::TextSeverity;
use crate::drivers::hid_pad::{Pad, PadState, MAX_BUTTONS, MAX_CHANNELS};
use crate::hid::descriptor::{self, page, usage, Descriptor, Field};
use crate::hid::{HidDriver, HidMatch, HidOps, NodeInfo};
use crate::time::Now;
use crate::{Connection, Error};

/// What a field is served as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// An axis: a channel.
    Axis,
    /// A hat switch: a channel and four buttons.
    Hat,
    /// A button.
    Button,
}

/// How a field is served, or `None` when it is not.
pub fn role(f: &Field) -> Option<Role> {
    match (f.page, f.usage) {
        (page::GENERIC_DESKTOP, u) if (usage::X..=usage::WHEEL).contains(&u) => Some(Role::Axis),
        (page::GENERIC_DESKTOP, usage::HAT_SWITCH) => Some(Role::Hat),
        (page::GENERIC_DESKTOP, 0x80..=0x9f) if f.bit_size == 1 => Some(Role::Button),
        (page::SIMULATION, _) if f.bit_size > 1 => Some(Role::Axis),
        (page::BUTTON, _) => Some(Role::Button),
        (page::CONSUMER, _) if f.bit_size == 1 => Some(Role::Button),
        _ => None,
    }
}

/// A device's layout: which fields become which channels and buttons.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    /// Axis fields, channel `i` for the `i`th.
    pub axes: Vec<Field>,
    /// Hat fields, channel `axes.len() + i` and buttons `buttons.len() + 4 * i ..`.
    pub hats: Vec<Field>,
    /// Button fields, button `i` for the `i`th.
    pub buttons: Vec<Field>,
    /// Reports start with their id.
    pub uses_report_ids: bool,
}

/// An axis value in −1…1 (see the module documentation).
pub fn normalize(f: &Field, v: i32) -> f64 {
    let (lo, hi) = (f64::from(f.logical_min), f64::from(f.logical_max));
    let v = f64::from(v);
    let n = if lo < 0.0 {
        let m = lo.abs().max(hi.abs());
        if m == 0.0 {
            0.0
        } else {
            v / m
        }
    } else if hi > lo {
        2.0 * (v - lo) / (hi - lo) - 1.0
    } else {
        0.0
    };
    n.clamp(-1.0, 1.0)
}

/// A hat's direction: 0-7 clockwise from up, `None` when centred (out of range).
pub fn hat_direction(f: &Field, v: i32) -> Option<u32> {
    let (lo, hi) = (i64::from(f.logical_min), i64::from(f.logical_max));
    let v = i64::from(v);
    if v < lo || v > hi || hi < lo {
        return None;
    }
    Some(((v - lo) * 8 / (hi - lo + 1)) as u32)
}

impl Layout {
    /// The layout of a parsed descriptor.
    pub fn new(d: &Descriptor) -> Layout {
        let mut l = Layout {
            uses_report_ids: d.uses_report_ids,
            ..Layout::default()
        };
        for f in &d.fields {
            match role(f) {
                Some(Role::Axis) => l.axes.push(*f),
                Some(Role::Hat) => l.hats.push(*f),
                Some(Role::Button) => l.buttons.push(*f),
                None => {}
            }
        }
        // Within what a VRPN device carries.
        l.axes.truncate(MAX_CHANNELS);
        l.hats.truncate(MAX_CHANNELS - l.axes.len());
        l.buttons
            .truncate(MAX_BUTTONS.saturating_sub(4 * l.hats.len()));
        l
    }

    /// Channels served.
    pub fn channels(&self) -> usize {
        self.axes.len() + self.hats.len()
    }

    /// Buttons served.
    pub fn button_count(&self) -> usize {
        self.buttons.len() + 4 * self.hats.len()
    }

    /// Applies one report; `false` when it carries none of the served fields.
    pub fn decode(&self, report: &[u8], s: &mut PadState) -> bool {
        let (id, data) = match (self.uses_report_ids, report.split_first()) {
            (true, Some((id, rest))) => (*id, rest),
            (true, None) => return false,
            (false, _) => (0, report),
        };
        let mut any = false;
        for (i, f) in self.axes.iter().enumerate() {
            if f.report_id == id {
                if let Some(v) = f.extract(data) {
                    s.channel[i] = normalize(f, v);
                    any = true;
                }
            }
        }
        for (i, f) in self.buttons.iter().enumerate() {
            if f.report_id == id {
                if let Some(v) = f.extract(data) {
                    s.button[i] = v != 0;
                    any = true;
                }
            }
        }
        let first_hat_button = self.buttons.len();
        for (i, f) in self.hats.iter().enumerate() {
            if f.report_id != id {
                continue;
            }
            let Some(v) = f.extract(data) else { continue };
            any = true;
            let dir = hat_direction(f, v);
            s.channel[self.axes.len() + i] = dir.map_or(-1.0, |d| 45.0 * f64::from(d));
            let b = first_hat_button + 4 * i;
            for k in 0..4 {
                s.button[b + k] = false;
            }
            if let Some(d) = dir {
                let d = d as usize;
                s.button[b + d / 2] = true;
                if d % 2 == 1 {
                    s.button[b + (d / 2 + 1) % 4] = true;
                }
            }
        }
        any
    }
}

/// The generic driver.
pub struct GenericDriver {
    name: String,
    want: HidMatch,
    pad: Pad,
    layout: Option<Layout>,
}

impl GenericDriver {
    /// The driver for `vrpn_HID_Generic NAME …` on the node `want` finds.
    pub fn new(name: &str, want: HidMatch, conn: &Connection) -> Result<GenericDriver, Error> {
        Ok(GenericDriver {
            name: name.to_string(),
            want,
            pad: Pad::new(name, conn, Some(0), Some(0), None)?,
            layout: None,
        })
    }

    /// The layout read from the device (once it opened).
    pub fn layout(&self) -> Option<&Layout> {
        self.layout.as_ref()
    }
}

impl HidDriver for GenericDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        vec![self.want.clone()]
    }

    fn wants_descriptor(&self) -> bool {
        true
    }

    fn descriptor(&mut self, _interface: usize, d: io::Result<&[u8]>) {
        let parsed = d
            .map_err(|e| e.to_string())
            .and_then(|bytes| descriptor::parse(bytes).map_err(|e| e.to_string()));
        match parsed {
            Ok(d) => {
                let l = Layout::new(&d);
                let (c, b, h) = (l.axes.len(), l.buttons.len(), l.hats.len());
                self.pad.resize(l.channels(), l.button_count());
                self.pad.say(
                    TextSeverity::Normal,
                    format_args!(
                        "{}: report descriptor read: {c} axes, {h} hats, {b} buttons",
                        self.name
                    ),
                );
                self.layout = Some(l);
            }
            Err(e) => {
                self.layout = None;
                self.pad.say(
                    TextSeverity::Error,
                    format_args!("{}: cannot read the report descriptor: {e}", self.name),
                );
            }
        }
    }

    fn opened(&mut self, _now: Now, _nodes: &[Option<NodeInfo>], _ops: &mut HidOps) {}

    fn report(&mut self, _interface: usize, report: &[u8], at: Now, _ops: &mut HidOps) {
        if let Some(l) = &self.layout {
            if l.decode(report, &mut self.pad.state) {
                self.pad.report_changes(at.wall);
            }
        }
    }
}

/// The `vrpn_HID_Generic` line that would serve `node`, if its descriptor describes a
/// joystick, game pad or multi-axis controller with something to serve.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    let h = node.hid()?;
    let d = descriptor::parse(&h.report_descriptor().ok()?).ok()?;
    let wanted = d
        .applications
        .iter()
        .any(|(p, u)| *p == page::GENERIC_DESKTOP && matches!(*u, 0x04 | 0x05 | 0x08));
    let l = Layout::new(&d);
    if !wanted || l.channels() + l.button_count() == 0 {
        return None;
    }
    let iface = h.interface.map(|i| format!(" {i}")).unwrap_or_default();
    Some(format!(
        "vrpn_HID_Generic Device0 {:04x}:{:04x}{iface}",
        h.vendor, h.product
    ))
}
