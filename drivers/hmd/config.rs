//! The head-mounted displays' lines: `KEYWORD NAME`.

use super::{hdk, model, ImuDriver, Model};
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_Oculus_DK1",
        "vrpn_Oculus_DK2_LEDs",
        "vrpn_Oculus_DK2_inertial",
        "vrpn_Laputa",
        "vrpn_Vality_vGlass",
        hdk::KEYWORD,
    ],
    parse,
    hints: &[],
};

/// A head-mounted display's line.
#[derive(Clone, Debug)]
pub struct HmdLine {
    /// The inertial unit the keyword names (`None`: the OSVR HDK).
    pub model: Option<&'static Model>,
    /// Device name.
    pub name: String,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(1, "name")?;
    Ok(Box::new(HmdLine {
        model: model(line.keyword()),
        name: line.name(0)?,
    }))
}

impl DeviceSpec for HmdLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        match self.model {
            Some(_) => Served::all(&self.name, &[Interface::Analog]),
            None => Served::all(&self.name, &[Interface::Tracker, Interface::Analog]),
        }
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![match self.model {
            Some(m) => crate::hid::serve(ImuDriver::new(m, &self.name, cx.conn())?, cx),
            None => crate::hid::serve(hdk::HdkDriver::new(&self.name, cx.conn())?, cx),
        }])
    }
}
