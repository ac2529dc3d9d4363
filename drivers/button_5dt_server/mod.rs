//! `vrpn_Button_5DT_Server`: a 5DT Data Glove 16's sixteen sensor values (an Analog, usually
//! a `vrpn_5dt16` of the same server) become sixteen buttons, each pressed while its value is
//! above its threshold.
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Button_5DT_Server NAME GLOVE T0 T1 ... T15
//! ```
//!
//! `GLOVE` is a device of this server, written `NAME` as in C++ (or `*NAME`), or
//! `NAME@host` for one on another server (C++ reads only its own server's). Sixteen
//! thresholds, one per sensor. See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! A Button with sixteen buttons: button `i` is pressed while channel `i` of the glove's
//! last report is strictly above `Ti`. Changes go out at the next server pass after the
//! glove's report (one `vrpn_Button Change` per changed button, toggle modes honoured, as
//! C++'s `vrpn_Button_Filter`), stamped with the glove report's time (C++ stamps 0).

#[cfg(test)]
mod tests;

use std::rc::Rc;
use std::time::Instant;

use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::devices::button::ButtonServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::AnalogSource;
use crate::time::Now;
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Button_5DT_Server"],
    parse,
    hints: &[],
};

/// Buttons (and thresholds) of the device: the glove's sixteen sensors.
pub const BUTTONS: usize = 16;

/// The `vrpn_Button_5DT_Server` line.
#[derive(Clone, Debug, PartialEq)]
pub struct Button5dtServer {
    /// Device name of the buttons.
    pub name: String,
    /// The glove's Analog.
    pub source: DeviceRef,
    /// A button is pressed while its channel is above its threshold.
    pub thresholds: [f64; BUTTONS],
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        2 + BUTTONS,
        "name, glove (NAME or *NAME on this server, NAME@host), 16 thresholds",
    )?;
    if line.args().len() > 2 + BUTTONS {
        return Err(line.err(
            ConfigErrorKind::BadValue,
            format!(
                "{} arguments; expected 18 (name, glove and 16 thresholds)",
                line.args().len()
            ),
        ));
    }
    let glove = line.word(1)?;
    // C++ reads a bare name on its own connection: a device of this server.
    let source = if glove.starts_with('*') || glove.contains('@') || glove == "NULL" {
        line.device_ref(1, "glove", false)?
            .ok_or_else(|| line.err(ConfigErrorKind::BadName, "the glove cannot be NULL"))?
    } else {
        DeviceRef::Local(line.name(1)?)
    };
    let mut thresholds = [0.0; BUTTONS];
    for (i, t) in thresholds.iter_mut().enumerate() {
        *t = line.f64(2 + i, "threshold")?;
    }
    Ok(Box::new(Button5dtServer {
        name: line.name(0)?,
        source,
        thresholds,
    }))
}

impl DeviceSpec for Button5dtServer {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(Button5dtDevice::new(self, cx.conn())?)])
    }
}

/// The buttons one glove report gives: pressed where the channel is above its threshold
/// (channels the report lacks read as 0).
pub fn pressed(channels: &[f64], thresholds: &[f64; BUTTONS]) -> [bool; BUTTONS] {
    let mut b = [false; BUTTONS];
    for (i, p) in b.iter_mut().enumerate() {
        *p = channels.get(i).copied().unwrap_or(0.0) > thresholds[i];
    }
    b
}

/// The running device.
pub struct Button5dtDevice {
    name: String,
    buttons: Rc<ButtonServer>,
    source: AnalogSource,
}

impl Button5dtDevice {
    /// The device `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &Button5dtServer, conn: &Connection) -> Result<Button5dtDevice, Error> {
        let buttons = Rc::new(ButtonServer::new(&cfg.name, conn, BUTTONS)?);
        let source = AnalogSource::open(&cfg.source, conn)?;
        let (b, thresholds) = (buttons.clone(), cfg.thresholds);
        source.remote.on_report(move |r| {
            for (i, p) in pressed(r.channels(), &thresholds).iter().enumerate() {
                b.set_button(i, *p);
            }
            b.set_timestamp(r.sender_time);
        });
        Ok(Button5dtDevice {
            name: cfg.name.clone(),
            buttons,
            source,
        })
    }
}

impl ServerDevice for Button5dtDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        self.source.poll();
        let _ = self.buttons.report_changes();
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.source.next_deadline()
    }
}
