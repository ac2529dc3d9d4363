//! The `vrpn_Poser_Analog` entry: its first line and the six axis lines after it.

use crate::config::fields::{device_ref, f32_field, f64_field, int_in};
use crate::config::lines::c_tokens;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::devices::analog::CHANNEL_MAX;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::error::Error;

/// The axis lines, in the order they must come.
pub const AXES: [&str; 6] = ["X", "Y", "Z", "RX", "RY", "RZ"];

/// One axis line.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The Analog_Output driven; `None` for `NULL`.
    pub device: Option<DeviceRef>,
    /// Its channel; `None` for -1 (or a `NULL` device): the axis drives nothing.
    pub channel: Option<u32>,
    /// Subtracted from the position (read in single precision, as C++).
    pub offset: f64,
    /// Multiplies the difference (read in single precision, as C++).
    pub scale: f64,
    /// Workspace minimum on this axis (rotation axes: read, unused, as in C++).
    pub min: f64,
    /// Workspace maximum on this axis.
    pub max: f64,
}

/// The `vrpn_Poser_Analog` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct PoserAnalog {
    /// Device name of the poser (and of its tracker).
    pub name: String,
    /// Whether accepted requests are reported back as a tracker.
    pub tracker_reports: bool,
    /// X, Y, Z, RX, RY, RZ. Only X, Y and Z drive outputs (C++ has no rotation yet).
    pub axes: Vec<Axis>,
}

impl PoserAnalog {
    /// The workspace minimum of X, Y, Z.
    pub fn min(&self) -> [f64; 3] {
        [self.axes[0].min, self.axes[1].min, self.axes[2].min]
    }

    /// The workspace maximum of X, Y, Z.
    pub fn max(&self) -> [f64; 3] {
        [self.axes[0].max, self.axes[1].max, self.axes[2].max]
    }
}

pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        2,
        "name, send_tracker_reports (0 or 1), then six axis lines",
    )?;
    let name = line.name(0)?;
    let tracker_reports = line.int(1, "send_tracker_reports")? != 0;
    let mut axes = Vec::with_capacity(6);
    for want in AXES {
        let next = line.block_line(&format!(
            "the {want} line: '{want} DEVICE CHANNEL OFFSET SCALE MIN MAX'"
        ))?;
        let ctx = line.ctx().at(next.number);
        let t = c_tokens(next.text);
        if t.first() != Some(&want) {
            return Err(ctx.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "expected the {want} axis line of vrpn_Poser_Analog {name} \
                     ('{want} DEVICE CHANNEL OFFSET SCALE MIN MAX'), found '{}'",
                    next.content().trim()
                ),
            ));
        }
        if t.len() != 7 {
            return Err(ctx.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "the {want} line needs six values after '{want}' (DEVICE CHANNEL OFFSET \
                     SCALE MIN MAX), found {}",
                    t.len() - 1
                ),
            ));
        }
        let device = device_ref(&ctx, "analog output", t[1], true)?;
        let channel = int_in(&ctx, "channel", t[2], -1, CHANNEL_MAX as i64 - 1)?;
        let offset = f64::from(f32_field(&ctx, "offset", t[3])?);
        let scale = f64::from(f32_field(&ctx, "scale", t[4])?);
        // A NULL device leaves the axis as it was: no channel, offset 0, scale 1 (C++).
        let axis = Axis {
            channel: u32::try_from(channel).ok().filter(|_| device.is_some()),
            offset: if device.is_some() { offset } else { 0.0 },
            scale: if device.is_some() { scale } else { 1.0 },
            min: f64_field(&ctx, "min", t[5])?,
            max: f64_field(&ctx, "max", t[6])?,
            device,
        };
        axes.push(axis);
    }
    Ok(Box::new(PoserAnalog {
        name,
        tracker_reports,
        axes,
    }))
}

impl DeviceSpec for PoserAnalog {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Poser, Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(super::PoserAnalogDevice::new(
            self,
            cx.conn(),
        )?)])
    }
}
