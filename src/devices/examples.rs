//! The built-in example devices as `vrpn.cfg` entries: their configurations, their line
//! parsers and their registry entries. They register the same way a hardware driver does.

use super::analog::AnalogExample as AnalogExampleDevice;
use super::button::ButtonExample as ButtonExampleDevice;
use super::dial::DialExample as DialExampleDevice;
use super::text_device::TextExample as TextExampleDevice;
use super::tracker::{TrackerNull as TrackerNullDevice, TrackerSpin as TrackerSpinDevice};
use super::ServerDevice;
use crate::config::{
    ConfigError, ConfigLine, MAX_BUTTONS, MAX_CHANNELS, MAX_DIALS, MAX_TRACKER_SENSORS,
};
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// `vrpn_Tracker_NULL NAME SENSORS RATE`: identity poses at a fixed rate.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerNull {
    /// Device name.
    pub name: String,
    /// Number of sensors, 1..=[`MAX_TRACKER_SENSORS`].
    pub sensors: u32,
    /// Reports per second, > 0.
    pub rate: f32,
}

/// `vrpn_Tracker_Spin NAME SENSORS RATE AXIS_X AXIS_Y AXIS_Z SPIN_HZ`: a tracker spinning
/// about an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerSpin {
    /// Device name.
    pub name: String,
    /// Number of sensors, 1..=[`MAX_TRACKER_SENSORS`].
    pub sensors: u32,
    /// Reports per second, > 0.
    pub rate: f32,
    /// Rotation axis (need not be normalised; all zero gives the identity).
    pub axis: [f32; 3],
    /// Revolutions per second (negative spins the other way).
    pub spin_hz: f32,
}

/// `vrpn_Button_Example NAME BUTTONS RATE`: buttons that all flip together.
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonExample {
    /// Device name.
    pub name: String,
    /// Number of buttons, 1..=[`MAX_BUTTONS`] (C++ clamps larger values; we reject them).
    pub buttons: u32,
    /// Transitions per second, > 0.
    pub rate: f32,
}

/// `vrpn_Dial_Example NAME DIALS SPIN_RATE UPDATE_RATE`: dials turning at a constant rate.
#[derive(Clone, Debug, PartialEq)]
pub struct DialExample {
    /// Device name.
    pub name: String,
    /// Number of dials, 1..=[`MAX_DIALS`].
    pub dials: u32,
    /// Revolutions per second of every dial (any sign).
    pub spin_rate: f32,
    /// Reports per second, > 0.
    pub update_rate: f32,
}

/// **Our extension** (not in C++ VRPN): `vrpn_Analog_Example NAME CHANNELS RATE`, an analog
/// server whose channels change over time, reporting `RATE` times per second.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogExample {
    /// Device name.
    pub name: String,
    /// Number of channels, 1..=[`MAX_CHANNELS`].
    pub channels: u32,
    /// Reports per second, > 0.
    pub rate: f32,
}

/// **Our extension** (not in C++ VRPN): `vrpn_Text_Example NAME PERIOD_SECONDS MESSAGE...`,
/// a text sender that sends `MESSAGE` every `PERIOD_SECONDS`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextExample {
    /// Device name.
    pub name: String,
    /// Seconds between messages, > 0.
    pub period: f32,
    /// The text: everything after the period, with surrounding blanks removed and inner
    /// spacing kept.
    pub message: String,
}

/// `vrpn_Tracker_NULL`.
pub static TRACKER_NULL: Driver = Driver {
    keywords: &["vrpn_Tracker_NULL"],
    parse: |line| {
        line.need(3, "name, sensors, rate")?;
        Ok(Box::new(TrackerNull {
            name: line.name(0)?,
            sensors: line.uint(1, "sensors", 1, MAX_TRACKER_SENSORS)?,
            rate: line.rate(2, "rate")?,
        }))
    },
    hints: &[],
};

/// `vrpn_Tracker_Spin`.
pub static TRACKER_SPIN: Driver = Driver {
    keywords: &["vrpn_Tracker_Spin"],
    parse: |line| {
        line.need(7, "name, sensors, rate, axis_x, axis_y, axis_z, spin_hz")?;
        Ok(Box::new(TrackerSpin {
            name: line.name(0)?,
            sensors: line.uint(1, "sensors", 1, MAX_TRACKER_SENSORS)?,
            rate: line.rate(2, "rate")?,
            axis: [
                line.f32(3, "axis_x")?,
                line.f32(4, "axis_y")?,
                line.f32(5, "axis_z")?,
            ],
            spin_hz: line.f32(6, "spin_hz")?,
        }))
    },
    hints: &[],
};

/// `vrpn_Button_Example`.
pub static BUTTON_EXAMPLE: Driver = Driver {
    keywords: &["vrpn_Button_Example"],
    parse: |line| {
        line.need(3, "name, buttons, rate")?;
        Ok(Box::new(ButtonExample {
            name: line.name(0)?,
            buttons: line.uint(1, "buttons", 1, MAX_BUTTONS)?,
            rate: line.rate(2, "rate")?,
        }))
    },
    hints: &[],
};

/// `vrpn_Dial_Example`.
pub static DIAL_EXAMPLE: Driver = Driver {
    keywords: &["vrpn_Dial_Example"],
    parse: |line| {
        line.need(4, "name, dials, spin_rate, update_rate")?;
        Ok(Box::new(DialExample {
            name: line.name(0)?,
            dials: line.uint(1, "dials", 1, MAX_DIALS)?,
            spin_rate: line.f32(2, "spin_rate")?,
            update_rate: line.rate(3, "update_rate")?,
        }))
    },
    hints: &[],
};

/// `vrpn_Analog_Example` (our extension).
pub static ANALOG_EXAMPLE: Driver = Driver {
    keywords: &["vrpn_Analog_Example"],
    parse: |line| {
        line.need(3, "name, channels, rate")?;
        Ok(Box::new(AnalogExample {
            name: line.name(0)?,
            channels: line.uint(1, "channels", 1, MAX_CHANNELS)?,
            rate: line.rate(2, "rate")?,
        }))
    },
    hints: &[],
};

/// `vrpn_Text_Example` (our extension).
pub static TEXT_EXAMPLE: Driver = Driver {
    keywords: &["vrpn_Text_Example"],
    parse: parse_text_example,
    hints: &[],
};

fn parse_text_example(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, period_seconds, message")?;
    Ok(Box::new(TextExample {
        name: line.name(0)?,
        period: line.period(1, "period_seconds")?,
        message: line.text_from(2).to_owned(),
    }))
}

/// One device, boxed, as [`DeviceSpec::build`] returns it.
fn one(device: impl ServerDevice + 'static) -> Vec<Box<dyn ServerDevice>> {
    vec![Box::new(device)]
}

impl DeviceSpec for TrackerNull {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let (sensors, rate) = (self.sensors as usize, f64::from(self.rate));
        Ok(one(TrackerNullDevice::new(
            &self.name,
            cx.conn(),
            sensors,
            rate,
        )?))
    }
}

impl DeviceSpec for TrackerSpin {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(one(TrackerSpinDevice::new(
            &self.name,
            cx.conn(),
            self.sensors as usize,
            f64::from(self.rate),
            self.axis.map(f64::from),
            f64::from(self.spin_hz),
        )?))
    }
}

impl DeviceSpec for ButtonExample {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Button])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(one(ButtonExampleDevice::new(
            &self.name,
            cx.conn(),
            self.buttons as usize,
            f64::from(self.rate),
        )?))
    }
}

impl DeviceSpec for DialExample {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Dial])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(one(DialExampleDevice::new(
            &self.name,
            cx.conn(),
            self.dials as usize,
            f64::from(self.spin_rate),
            f64::from(self.update_rate),
        )?))
    }
}

impl DeviceSpec for AnalogExample {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(one(AnalogExampleDevice::new(
            &self.name,
            cx.conn(),
            self.channels as usize,
            f64::from(self.rate),
        )?))
    }
}

impl DeviceSpec for TextExample {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Text])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(one(TextExampleDevice::new(
            &self.name,
            cx.conn(),
            f64::from(self.period),
            &self.message,
        )?))
    }
}
