//! The evdev lines: `vrpn_DevInput NAME "DEVICE NAME" TYPE [PARAM]`, `vrpn_Mouse NAME`,
//! `vrpn_Event_Mouse NAME EVENT_DEVICE`.

use super::{DevInputKind, EvdevDriver};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_DevInput", "vrpn_Mouse", "vrpn_Event_Mouse"],
    parse,
    hints: &[],
};

/// What an evdev line reads.
#[derive(Clone, Debug, PartialEq)]
pub enum EvdevKind {
    /// `vrpn_DevInput`: the device's kernel name and what it is.
    DevInput {
        /// The name the device's event node has.
        device: String,
        /// Keyboard, relative or absolute.
        kind: DevInputKind,
    },
    /// `vrpn_Mouse`: the first mouse.
    Mouse,
    /// `vrpn_Event_Mouse`: the mouse at this event node.
    EventMouse {
        /// The node's path.
        path: String,
    },
}

/// An evdev line.
#[derive(Clone, Debug)]
pub struct EvdevLine {
    /// Device name.
    pub name: String,
    /// What it reads.
    pub kind: EvdevKind,
}

/// The rest of a `vrpn_DevInput` line after the name: `"DEVICE NAME" TYPE [PARAM]`, read as
/// C++'s `sscanf(" \"%[^\"]\" %s %d")` reads it.
fn dev_input(line: &ConfigLine<'_, '_>) -> Result<EvdevKind, ConfigError> {
    let usage = "expected NAME \"DEVICE NAME\" keyboard|relative|absolute [NUMBER]";
    let rest = line.text_from(1);
    let bad = |what: &str| line.err(ConfigErrorKind::BadValue, format!("{what} ({usage})"));
    let quoted = rest
        .strip_prefix('"')
        .ok_or_else(|| bad("the device name must be in double quotes"))?;
    let (device, after) = quoted
        .split_once('"')
        .ok_or_else(|| bad("the device name's closing quote is missing"))?;
    if device.is_empty() {
        return Err(bad("the device name is empty"));
    }
    let mut words = after.split_whitespace();
    let kind = words.next().ok_or_else(|| {
        line.err(
            ConfigErrorKind::MissingArguments,
            format!("the type is missing ({usage})"),
        )
    })?;
    // C++ reads the number if there is one, and leaves it 0 otherwise.
    let param: i64 = words.next().and_then(|w| w.parse().ok()).unwrap_or(0);
    let kind = match kind {
        "keyboard" => {
            if !(1..=255).contains(&param) {
                return Err(line.err(
                    ConfigErrorKind::OutOfRange,
                    format!("a keyboard's number of keys must be 1 to 255, found {param}"),
                ));
            }
            DevInputKind::Keyboard(param as usize)
        }
        "relative" => DevInputKind::Relative,
        "absolute" => DevInputKind::Absolute(param as f64),
        other => {
            return Err(line.err(
                ConfigErrorKind::BadValue,
                format!("the type must be keyboard, absolute or relative, found {other:?}"),
            ))
        }
    };
    Ok(EvdevKind::DevInput {
        device: device.to_string(),
        kind,
    })
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let kind = match line.keyword() {
        "vrpn_DevInput" => {
            line.need(3, "name, \"device name\", type, [number]")?;
            dev_input(line)?
        }
        "vrpn_Mouse" => {
            line.need(1, "name")?;
            EvdevKind::Mouse
        }
        _ => {
            line.need(2, "name, event device")?;
            EvdevKind::EventMouse {
                path: line.word(1)?.to_owned(),
            }
        }
    };
    Ok(Box::new(EvdevLine {
        name: line.name(0)?,
        kind,
    }))
}

impl DeviceSpec for EvdevLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let conn = cx.conn();
        let driver = match &self.kind {
            EvdevKind::DevInput { device, kind } => {
                EvdevDriver::dev_input(&self.name, device, *kind, conn)?
            }
            EvdevKind::Mouse => EvdevDriver::mouse(&self.name, conn)?,
            EvdevKind::EventMouse { path } => EvdevDriver::event_mouse(&self.name, path, conn)?,
        };
        Ok(vec![crate::hid::serve(driver, cx)])
    }
}
