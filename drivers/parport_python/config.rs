//! The `vrpn_Button_Python` line: its fields, its parser, what it serves and how it is built.

use super::source::Ppdev;
use super::PythonButtons;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::error::Error;

/// `vrpn_Button_Python NAME PORT [HEX_ADDRESS]`: the UNC button box on parallel port `PORT`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Python {
    /// Device name (Button with 5 buttons).
    pub name: String,
    /// Parallel port number, from 1 (`/dev/parport0`).
    pub port: u32,
    /// The I/O base address (Windows only; read and ignored, as C++ on Linux).
    pub address: Option<u32>,
}

impl Python {
    /// The `ppdev` device the port number names.
    pub fn device_path(&self) -> String {
        format!("/dev/parport{}", self.port - 1)
    }
}

/// Parses a `vrpn_Button_Python` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, parallel port (from 1), [hexadecimal I/O address]")?;
    let address = match line.arg(2) {
        None => None,
        Some(t) => {
            let digits = t
                .strip_prefix("0x")
                .or_else(|| t.strip_prefix("0X"))
                .unwrap_or(t);
            Some(u32::from_str_radix(digits, 16).map_err(|_| {
                line.err(
                    ConfigErrorKind::BadValue,
                    format!("the I/O address must be hexadecimal, found '{t}'"),
                )
            })?)
        }
    };
    Ok(Box::new(Python {
        name: line.name(0)?,
        port: line.uint(1, "parallel port", 1, 256)?,
        address,
    }))
}

impl DeviceSpec for Python {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let source = Ppdev::new(&self.device_path());
        let mut device = PythonButtons::new(&self.name, source, cx.conn())?;
        if let Some(sink) = cx.status() {
            device.report_status_to(sink.clone());
        }
        Ok(vec![Box::new(device)])
    }
}
