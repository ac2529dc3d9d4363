//! The `vrpn_Xkeys_*` lines: `KEYWORD NAME`.

use super::{driver, model, Model};
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry: every `vrpn_Xkeys_*` keyword.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_Xkeys_Desktop",
        "vrpn_Xkeys_Pro",
        "vrpn_Xkeys_Joystick",
        "vrpn_Xkeys_Joystick12",
        "vrpn_Xkeys_Jog_And_Shuttle",
        "vrpn_Xkeys_Jog_And_Shuttle12",
        "vrpn_Xkeys_Jog_And_Shuttle68",
        "vrpn_Xkeys_XK3",
    ],
    parse,
    hints: &[],
};

/// A `vrpn_Xkeys_*` line.
#[derive(Clone, Debug)]
pub struct XkeysLine {
    /// The model the keyword names.
    pub model: &'static Model,
    /// Device name.
    pub name: String,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(1, "name")?;
    let model = model(line.keyword()).expect("the registry sends only this family's keywords");
    Ok(Box::new(XkeysLine {
        model,
        name: line.name(0)?,
    }))
}

impl DeviceSpec for XkeysLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        let mut v = Vec::new();
        if self.model.channels.is_some() {
            v.push(Interface::Analog);
        }
        v.push(Interface::Button);
        if self.model.dials.is_some() {
            v.push(Interface::Dial);
        }
        Served::all(&self.name, &v)
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let d = driver(self.model, &self.name, cx.conn())?;
        Ok(vec![crate::hid::serve(d, cx)])
    }
}
