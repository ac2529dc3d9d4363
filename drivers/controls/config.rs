//! The Contour, Griffin and Dream Cheeky lines: `KEYWORD NAME`.

use super::{driver, model, Model};
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_Contour_ShuttleXpress",
        "vrpn_Contour_ShuttlePROv2",
        "vrpn_Griffin_PowerMate",
        "vrpn_Dream_Cheeky_USB_roll_up_drums",
    ],
    parse,
    hints: &[],
};

/// One of these devices' lines.
#[derive(Clone, Debug)]
pub struct ControlLine {
    /// The device the keyword names.
    pub model: &'static Model,
    /// Device name.
    pub name: String,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(1, "name")?;
    let model = model(line.keyword()).expect("the registry sends only this family's keywords");
    Ok(Box::new(ControlLine {
        model,
        name: line.name(0)?,
    }))
}

impl DeviceSpec for ControlLine {
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
