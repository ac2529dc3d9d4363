//! The `vrpn_HID_Generic` line: `NAME VENDOR:PRODUCT [INTERFACE]`, `NAME "DEVICE NAME"
//! [INTERFACE]` or `NAME /dev/hidrawN`.

use super::GenericDriver;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::hid::{HidMatch, InterfaceRule, NodeKind, Select};

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_HID_Generic"],
    parse,
    hints: &[],
};

/// A `vrpn_HID_Generic` line.
#[derive(Clone, Debug)]
pub struct GenericLine {
    /// Device name.
    pub name: String,
    /// Which device.
    pub want: HidMatch,
}

/// A `VVVV:PPPP` pair of hexadecimal ids.
pub fn parse_ids(s: &str) -> Option<(u16, u16)> {
    let (v, p) = s.split_once(':')?;
    let hex = |t: &str| {
        let t = t.strip_prefix("0x").unwrap_or(t);
        (!t.is_empty() && t.len() <= 4)
            .then(|| u16::from_str_radix(t, 16).ok())
            .flatten()
    };
    Some((hex(v)?, hex(p)?))
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let usage =
        "NAME VENDOR:PRODUCT [INTERFACE], NAME \"DEVICE NAME\" [INTERFACE] or NAME /dev/hidrawN";
    line.need(2, usage)?;
    let name = line.name(0)?;
    let rest = line.text_from(1);
    let (select, after) = if let Some(q) = rest.strip_prefix('"') {
        let (dev, after) = q.split_once('"').ok_or_else(|| {
            line.err(
                ConfigErrorKind::BadValue,
                format!("the device name's closing quote is missing ({usage})"),
            )
        })?;
        (Select::Name(dev.to_string()), after)
    } else {
        let w = line.word(1)?;
        let after = rest[w.len()..].trim_start();
        if let Some((vendor, product)) = parse_ids(w) {
            (
                Select::Product {
                    vendor,
                    product,
                    mask: 0xffff,
                },
                after,
            )
        } else if w.starts_with('/') || w.starts_with("hidraw") {
            (Select::Path(w.to_string()), after)
        } else {
            return Err(line.err(
                ConfigErrorKind::BadValue,
                format!("expected VENDOR:PRODUCT in hexadecimal, a quoted device name or a hidraw path, found {w:?} ({usage})"),
            ));
        }
    };
    let interface = match after.split_whitespace().next() {
        None => InterfaceRule::Any,
        Some(t) => InterfaceRule::Is(t.parse::<u8>().map(i32::from).map_err(|_| {
            line.err(
                ConfigErrorKind::BadNumber,
                format!("the interface must be a number from 0 to 255, found {t:?}"),
            )
        })?),
    };
    let mut want = HidMatch::of(NodeKind::Hidraw, select);
    want.interface = interface;
    Ok(Box::new(GenericLine { name, want }))
}

impl DeviceSpec for GenericLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let d = GenericDriver::new(&self.name, self.want.clone(), cx.conn())?;
        Ok(vec![crate::hid::serve(d, cx)])
    }
}
