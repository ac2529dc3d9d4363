//! The game controllers' lines: `KEYWORD NAME`, and `vrpn_Microsoft_Controller_Raw_Xbox_360
//! NAME [VENDOR PRODUCT]` (hexadecimal ids, as C++'s `%x` reads them).

use super::{driver, model, parse_hex_id, Model};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry: every game controller keyword.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_Microsoft_SideWinder_Precision_2",
        "vrpn_Microsoft_SideWinder",
        "vrpn_Microsoft_Controller_Raw_Xbox_S",
        "vrpn_Microsoft_Controller_Raw_Xbox_360",
        "vrpn_Microsoft_Controller_Raw_Xbox_360_Wireless",
        "vrpn_Afterglow_Ax1_For_Xbox_360",
        "vrpn_Logitech_Extreme_3D_Pro",
        "vrpn_Saitek_ST290_Pro",
        "vrpn_CHProducts_Fighterstick_USB",
        "vrpn_Retrolink_GameCube",
        "vrpn_Retrolink_Genesis",
        "vrpn_Futaba_InterLink_Elite",
        "vrpn_nVidia_shield_USB",
        "vrpn_nVidia_shield_stealth_USB",
    ],
    parse,
    hints: &[],
};

/// A game controller's line.
#[derive(Clone, Debug)]
pub struct GamepadLine {
    /// The controller the keyword names.
    pub model: &'static Model,
    /// Device name.
    pub name: String,
    /// Other USB ids (Xbox 360 compatibles).
    pub ids: Option<(u16, u16)>,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(1, "name")?;
    let model = model(line.keyword()).expect("the registry sends only this family's keywords");
    let mut ids = None;
    if model.keyword == "vrpn_Microsoft_Controller_Raw_Xbox_360" && line.args().len() > 1 {
        line.need(3, "name, [vendor product]")?;
        let id = |i: usize, field: &str| {
            let w = line.word(i)?;
            parse_hex_id(w).ok_or_else(|| {
                line.err(
                    ConfigErrorKind::BadValue,
                    format!("{field} must be a hexadecimal USB id such as 0x045e, found {w:?}"),
                )
            })
        };
        ids = Some((id(1, "vendor")?, id(2, "product")?));
    }
    Ok(Box::new(GamepadLine {
        model,
        name: line.name(0)?,
        ids,
    }))
}

impl DeviceSpec for GamepadLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        let mut v = vec![Interface::Analog, Interface::Button];
        if self.model.dial {
            v.push(Interface::Dial);
        }
        Served::all(&self.name, &v)
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let d = driver(self.model, &self.name, self.ids, cx.conn())?;
        Ok(vec![crate::hid::serve(d, cx)])
    }
}
