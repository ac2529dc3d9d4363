//! The `vrpn_Analog_5dtUSB_*` lines: `KEYWORD NAME`.

use super::{driver, model, Model};
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_Analog_5dtUSB_Glove5Left",
        "vrpn_Analog_5dtUSB_Glove5Right",
        "vrpn_Analog_5dtUSB_Glove14Left",
        "vrpn_Analog_5dtUSB_Glove14Right",
    ],
    parse,
    hints: &[],
};

/// A glove's line.
#[derive(Clone, Debug)]
pub struct GloveLine {
    /// The glove the keyword names.
    pub model: &'static Model,
    /// Device name.
    pub name: String,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(1, "name")?;
    let model = model(line.keyword()).expect("the registry sends only this family's keywords");
    Ok(Box::new(GloveLine {
        model,
        name: line.name(0)?,
    }))
}

impl DeviceSpec for GloveLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let d = driver(self.model, &self.name, cx.conn())?;
        Ok(vec![crate::hid::serve(d, cx)])
    }
}
