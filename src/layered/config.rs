//! The layered fly trackers as `vrpn.cfg` entries, `vrpn_Tracker_AnalogFly` and
//! `vrpn_Tracker_ButtonFly`: the references to the devices they read, their typed
//! configurations, their block parsers and their registry entries.

use crate::config::fields::{block_need, device_ref, f32_field, uint_in};
use crate::config::lines::c_tokens;
use crate::config::{
    ConfigError, ConfigErrorKind, ConfigLine, Ctx, DeviceRef, MAX_BUTTONS, MAX_CHANNELS,
};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// Most axis lines in one ButtonFly block.
pub const MAX_BUTTONFLY_AXES: usize = 200;

/// Longest device name in a ButtonFly axis line.
pub const MAX_BUTTONFLY_NAME: usize = 199;

/// `vrpn_Tracker_AnalogFly`.
pub static ANALOG_FLY: Driver = Driver {
    keywords: &["vrpn_Tracker_AnalogFly"],
    parse: parse_analog_fly,
    hints: &[],
};

/// `vrpn_Tracker_ButtonFly`.
pub static BUTTON_FLY: Driver = Driver {
    keywords: &["vrpn_Tracker_ButtonFly"],
    parse: parse_button_fly,
    hints: &[],
};

/// A button of another device.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ButtonRef {
    /// The button device.
    pub device: DeviceRef,
    /// The button index on that device (0-based).
    pub button: u32,
}

/// Whether a fly tracker's inputs are poses or rates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FlyMode {
    /// Inputs are positions / orientations.
    Absolute,
    /// Inputs are velocities / angular rates, integrated over time.
    Differential,
}

impl FlyMode {
    /// Parses `absolute` or `differential` (exact, lower case).
    pub fn parse(tok: &str) -> Option<FlyMode> {
        match tok {
            "absolute" => Some(FlyMode::Absolute),
            "differential" => Some(FlyMode::Differential),
            _ => None,
        }
    }
}

/// One of the six AnalogFly axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// Translation along x.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation about x.
    RX,
    /// Rotation about y.
    RY,
    /// Rotation about z.
    RZ,
}

impl Axis {
    /// All axes in the order C++ services them.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::RX, Axis::RY, Axis::RZ];

    /// The axis keyword in an AnalogFly block (`X` .. `RZ`).
    pub fn keyword(self) -> &'static str {
        match self {
            Axis::X => "X",
            Axis::Y => "Y",
            Axis::Z => "Z",
            Axis::RX => "RX",
            Axis::RY => "RY",
            Axis::RZ => "RZ",
        }
    }

    /// Parses an axis keyword (case-sensitive, as in C++).
    pub fn from_keyword(tok: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|a| a.keyword() == tok)
    }

    /// Position in [`Axis::ALL`] and in [`AnalogFly::axes`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One AnalogFly axis: which analog channel drives it and how its value is shaped.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogFlyAxis {
    /// The analog device, or `None` (`NULL` or not configured): the axis stays 0.
    pub source: Option<DeviceRef>,
    /// Channel index on that device, 0..[`MAX_CHANNELS`].
    pub channel: u32,
    /// Subtracted from the channel value first.
    pub offset: f32,
    /// Values within ±threshold of the offset count as 0.
    pub threshold: f32,
    /// Multiplier, applied inside the power.
    pub scale: f32,
    /// Exponent.
    pub power: f32,
}

impl Default for AnalogFlyAxis {
    /// A disabled axis: no device, channel 0, offset 0, threshold 0, scale 1, power 1.
    fn default() -> Self {
        AnalogFlyAxis {
            source: None,
            channel: 0,
            offset: 0.0,
            threshold: 0.0,
            scale: 1.0,
            power: 1.0,
        }
    }
}

/// `vrpn_Tracker_AnalogFly NAME RATE absolute|differential` followed by axis, `RESET`,
/// `CLUTCH` and `WORLDFRAME` lines, ended by an empty line.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogFly {
    /// Device name of the produced tracker.
    pub name: String,
    /// Reports per second, >= 0 (0 means one report per second, as in C++).
    pub update_rate: f32,
    /// Absolute or differential.
    pub mode: FlyMode,
    /// Differential motion in the world frame (a `WORLDFRAME` line).
    pub world_frame: bool,
    /// The axes, indexed by [`Axis::index`]; unmentioned axes are disabled.
    pub axes: [AnalogFlyAxis; 6],
    /// Reset button (`RESET`), `None` when absent or `NULL`.
    pub reset: Option<ButtonRef>,
    /// Clutch button (`CLUTCH`), `None` when absent or `NULL` (always engaged).
    pub clutch: Option<ButtonRef>,
}

impl AnalogFly {
    /// The configuration of one axis.
    pub fn axis(&self, axis: Axis) -> &AnalogFlyAxis {
        &self.axes[axis.index()]
    }
}

/// One ButtonFly axis line (`absolute` or `differential`).
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonFlyAxis {
    /// The button that drives it.
    pub button: ButtonRef,
    /// Absolute (jump to a pose) or differential (move while held).
    pub mode: FlyMode,
    /// Position in metres (absolute) or velocity in m/s (differential).
    pub vec: [f32; 3],
    /// Orientation in revolutions about x, y, z (absolute) or rev/s (differential).
    pub rot: [f32; 3],
}

/// A ButtonFly `vel_scale` / `rot_scale` analog.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleAnalog {
    /// The analog device.
    pub source: DeviceRef,
    /// Channel index, 0..[`MAX_CHANNELS`].
    pub channel: u32,
    /// Subtracted from the channel value first.
    pub offset: f32,
    /// Multiplier.
    pub scale: f32,
    /// Exponent.
    pub power: f32,
}

/// `vrpn_Tracker_ButtonFly NAME RATE` followed by `absolute`, `differential`, `vel_scale`,
/// `rot_scale` lines and a closing `end` line.
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonFly {
    /// Device name of the produced tracker.
    pub name: String,
    /// Reports per second, >= 0 (0 means one report per second, as in C++).
    pub update_rate: f32,
    /// Axis lines in file order, at most [`MAX_BUTTONFLY_AXES`].
    pub axes: Vec<ButtonFlyAxis>,
    /// Analog scaling all translation rates (`vel_scale`), if any.
    pub vel_scale: Option<ScaleAnalog>,
    /// Analog scaling all rotation rates (`rot_scale`), if any.
    pub rot_scale: Option<ScaleAnalog>,
}

// ---------------------------------------------------------------------------------------------
// AnalogFly block
// ---------------------------------------------------------------------------------------------

fn parse_analog_fly(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, update_rate, absolute|differential")?;
    let name = line.name(0)?;
    let update_rate = line.rate_or_zero(1, "update_rate")?;
    let third = line.word(2)?;
    let mode = FlyMode::parse(third).ok_or_else(|| {
        line.err(
            ConfigErrorKind::BadValue,
            format!("the third argument must be 'absolute' or 'differential', found '{third}'"),
        )
    })?;
    let mut fly = AnalogFly {
        name,
        update_rate,
        mode,
        world_frame: false,
        axes: Default::default(),
        reset: None,
        clutch: None,
    };
    let ctx = line.ctx();
    let block = Ctx::new(
        ctx.file,
        ctx.line,
        format!("{} {}", line.keyword(), fly.name),
    );
    loop {
        let next = line.block_line_in(
            &block,
            "the empty line that must end the block (add an empty line after its last line)",
        )?;
        // Only a truly empty line ends the block (not blanks, not "\r\n").
        if next.text.starts_with('\n') {
            return Ok(Box::new(fly));
        }
        analog_fly_line(&block.at(next.number), &c_tokens(next.text), &mut fly)?;
    }
}

/// Applies one line of an AnalogFly block; unknown first tokens are ignored, as in C++.
fn analog_fly_line(ctx: &Ctx<'_>, t: &[&str], fly: &mut AnalogFly) -> Result<(), ConfigError> {
    let Some(&first) = t.first() else {
        return Ok(());
    };
    if let Some(axis) = Axis::from_keyword(first) {
        fly.axes[axis.index()] = analog_fly_axis(ctx, first, &t[1..])?;
    } else if first == "RESET" || first == "CLUTCH" {
        let button = button_line(ctx, first, &t[1..])?;
        if first == "RESET" {
            fly.reset = button;
        } else {
            fly.clutch = button;
        }
    } else if first == "WORLDFRAME" {
        fly.world_frame = true;
    }
    Ok(())
}

fn analog_fly_axis(ctx: &Ctx<'_>, axis: &str, t: &[&str]) -> Result<AnalogFlyAxis, ConfigError> {
    block_need(
        ctx,
        axis,
        t,
        6,
        "device or NULL, channel, offset, threshold, scale, power",
    )?;
    let field = |f: &str| format!("axis {axis} {f}");
    Ok(AnalogFlyAxis {
        source: device_ref(ctx, &field("device"), t[0], true)?,
        channel: uint_in(ctx, &field("channel"), t[1], 0, MAX_CHANNELS - 1)?,
        offset: f32_field(ctx, &field("offset"), t[2])?,
        threshold: f32_field(ctx, &field("threshold"), t[3])?,
        scale: f32_field(ctx, &field("scale"), t[4])?,
        power: f32_field(ctx, &field("power"), t[5])?,
    })
}

/// A `RESET` / `CLUTCH` line: `NULL` gives `None`.
fn button_line(ctx: &Ctx<'_>, what: &str, t: &[&str]) -> Result<Option<ButtonRef>, ConfigError> {
    block_need(ctx, what, t, 2, "button device or NULL, button index")?;
    let device = device_ref(ctx, &format!("{what} device"), t[0], true)?;
    let button = uint_in(
        ctx,
        &format!("{what} button index"),
        t[1],
        0,
        MAX_BUTTONS - 1,
    )?;
    Ok(device.map(|device| ButtonRef { device, button }))
}

// ---------------------------------------------------------------------------------------------
// ButtonFly block
// ---------------------------------------------------------------------------------------------

fn parse_button_fly(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, update_rate")?;
    let mut fly = ButtonFly {
        name: line.name(0)?,
        update_rate: line.rate_or_zero(1, "update_rate")?,
        axes: Vec::new(),
        vel_scale: None,
        rot_scale: None,
    };
    let ctx = line.ctx();
    let block = Ctx::new(
        ctx.file,
        ctx.line,
        format!("{} {}", line.keyword(), fly.name),
    );
    loop {
        let next = line.block_line_in(&block, "the 'end' line that must close the block")?;
        let here = block.at(next.number);
        let t = c_tokens(next.text);
        match t.first().copied() {
            None => {
                return Err(here.err(
                    ConfigErrorKind::BadBlockLine,
                    "empty line inside the block; remove it (the block ends at a line 'end')",
                ))
            }
            Some("end") => return Ok(Box::new(fly)),
            Some(m @ ("absolute" | "differential")) => {
                if fly.axes.len() >= MAX_BUTTONFLY_AXES {
                    return Err(here.err(
                        ConfigErrorKind::BadBlockLine,
                        format!("too many axis lines; at most {MAX_BUTTONFLY_AXES} are allowed"),
                    ));
                }
                fly.axes.push(button_fly_axis(&here, m, &t[1..])?);
            }
            Some(s @ ("vel_scale" | "rot_scale")) => {
                let scale = scale_analog(&here, s, &t[1..])?;
                if s == "vel_scale" {
                    fly.vel_scale = scale;
                } else {
                    fly.rot_scale = scale;
                }
            }
            Some(_) => {}
        }
    }
}

fn button_fly_axis(ctx: &Ctx<'_>, mode: &str, t: &[&str]) -> Result<ButtonFlyAxis, ConfigError> {
    block_need(
        ctx,
        mode,
        t,
        8,
        "button device, button index, x, y, z, rx, ry, rz",
    )?;
    if t[0].len() > MAX_BUTTONFLY_NAME {
        return Err(ctx.err(
            ConfigErrorKind::BadName,
            format!(
                "button device name is {} characters long; at most {MAX_BUTTONFLY_NAME} allowed",
                t[0].len()
            ),
        ));
    }
    let device = device_ref(ctx, "button device", t[0], false)?
        .ok_or_else(|| ctx.err(ConfigErrorKind::BadName, "button device cannot be NULL"))?;
    let f = |i: usize, name: &str| f32_field(ctx, name, t[i]);
    Ok(ButtonFlyAxis {
        button: ButtonRef {
            device,
            button: uint_in(ctx, "button index", t[1], 0, MAX_BUTTONS - 1)?,
        },
        mode: FlyMode::parse(mode).unwrap_or(FlyMode::Differential),
        vec: [f(2, "x")?, f(3, "y")?, f(4, "z")?],
        rot: [f(5, "rx")?, f(6, "ry")?, f(7, "rz")?],
    })
}

fn scale_analog(ctx: &Ctx<'_>, what: &str, t: &[&str]) -> Result<Option<ScaleAnalog>, ConfigError> {
    block_need(
        ctx,
        what,
        t,
        5,
        "analog device or NULL, channel, offset, scale, power",
    )?;
    let Some(source) = device_ref(ctx, &format!("{what} device"), t[0], true)? else {
        return Ok(None);
    };
    Ok(Some(ScaleAnalog {
        source,
        channel: uint_in(ctx, &format!("{what} channel"), t[1], 0, MAX_CHANNELS - 1)?,
        offset: f32_field(ctx, &format!("{what} offset"), t[2])?,
        scale: f32_field(ctx, &format!("{what} scale"), t[3])?,
        power: f32_field(ctx, &format!("{what} power"), t[4])?,
    }))
}

impl DeviceSpec for AnalogFly {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(super::TrackerAnalogFly::new(
            self,
            cx.conn(),
        )?)])
    }
}

impl DeviceSpec for ButtonFly {
    fn name(&self) -> &str {
        &self.name
    }
    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(super::TrackerButtonFly::new(
            self,
            cx.conn(),
        )?)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes() {
        assert_eq!(Axis::from_keyword("RY"), Some(Axis::RY));
        assert_eq!(Axis::from_keyword("ry"), None);
        assert!(Axis::ALL.iter().enumerate().all(|(i, a)| a.index() == i));
    }
}
