//! The `vrpn_3DConnexion_*` lines: `KEYWORD NAME` (words after the name are ignored, as C++
//! ignores them).

use super::{driver, model, Model};
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry: every `vrpn_3DConnexion_*` keyword.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_3DConnexion_Navigator",
        "vrpn_3DConnexion_Navigator_for_Notebooks",
        "vrpn_3DConnexion_Traveler",
        "vrpn_3DConnexion_SpaceMouse",
        "vrpn_3DConnexion_SpaceMousePro",
        "vrpn_3DConnexion_SpaceMouseCompact",
        "vrpn_3DConnexion_SpaceMouseWireless",
        "vrpn_3DConnexion_SpaceMouseWireless2",
        "vrpn_3DConnexion_SpaceMouseProWireless",
        "vrpn_3DConnexion_SpaceExplorer",
        "vrpn_3DConnexion_SpaceBall5000",
        "vrpn_3DConnexion_SpacePilot",
        "vrpn_3DConnexion_SpacePilotPro",
    ],
    parse,
    hints: &[],
};

/// A `vrpn_3DConnexion_*` line.
#[derive(Clone, Debug)]
pub struct SpaceMouseLine {
    /// The model the keyword names.
    pub model: &'static Model,
    /// Device name (Analog and Button under it).
    pub name: String,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(1, "name")?;
    let model = model(line.keyword()).expect("the registry sends only this family's keywords");
    Ok(Box::new(SpaceMouseLine {
        model,
        name: line.name(0)?,
    }))
}

impl DeviceSpec for SpaceMouseLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let d = driver(self.model, &self.name, cx.conn())?;
        Ok(vec![crate::hid::serve(d, cx)])
    }
}
