//! Three analog channels read as a vector, the input of the inertial devices
//! (`vrpn_IMU_Magnetometer`, the IMU combiner): their configuration line and the vector each
//! analog report gives, computed as C++ VRPN 07.38 does.

use crate::config::fields::{device_ref, f32_field, uint_in};
use crate::config::lines::c_tokens;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, Ctx, DeviceRef, MAX_CHANNELS};
use crate::time::TimeVal;

/// One axis line: `DEVICE CH OFFSET SCALE CH OFFSET SCALE CH OFFSET SCALE`.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisParams {
    /// The analog device read.
    pub source: DeviceRef,
    /// Channel of x, y and z.
    pub channels: [u32; 3],
    /// Subtracted from each channel (single precision, as C++ reads it).
    pub offsets: [f32; 3],
    /// Then multiplied by this.
    pub scales: [f32; 3],
}

impl AxisParams {
    /// The vector one analog report gives: `(channel - offset) × scale` per axis (channels
    /// the report does not carry read as 0).
    pub fn vector(&self, channels: &[f64]) -> [f64; 3] {
        let mut v = [0.0; 3];
        for (i, out) in v.iter_mut().enumerate() {
            let x = channels
                .get(self.channels[i] as usize)
                .copied()
                .unwrap_or(0.0);
            *out = (x - self.offsets[i] as f64) * self.scales[i] as f64;
        }
        v
    }
}

/// Reads the line after the device line as the axis line of `what` (C++ reads the next line
/// of the file, whatever it is).
pub fn axis_line(line: &mut ConfigLine<'_, '_>, what: &str) -> Result<AxisParams, ConfigError> {
    let ctx = line.ctx();
    let block = Ctx::new(ctx.file, ctx.line, format!("{} {what}", line.keyword()));
    let next = line.block_line_in(&block, &format!("the {what} line"))?;
    let ctx = block.at(next.number);
    let t = c_tokens(next.text);
    if t.len() < 10 {
        return Err(ctx.err(
            ConfigErrorKind::MissingArguments,
            format!(
                "the {what} line needs an analog device, then channel, offset and scale of \
                 x, y and z (10 values), found {}",
                t.len()
            ),
        ));
    }
    let source = device_ref(&ctx, &format!("{what} device"), t[0], false)?.ok_or_else(|| {
        ctx.err(
            ConfigErrorKind::BadName,
            format!("the {what} device cannot be NULL"),
        )
    })?;
    let mut p = AxisParams {
        source,
        channels: [0; 3],
        offsets: [0.0; 3],
        scales: [1.0; 3],
    };
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        let k = 1 + 3 * i;
        p.channels[i] = uint_in(
            &ctx,
            &format!("{what} {axis} channel"),
            t[k],
            0,
            MAX_CHANNELS - 1,
        )?;
        p.offsets[i] = f32_field(&ctx, &format!("{what} {axis} offset"), t[k + 1])?;
        p.scales[i] = f32_field(&ctx, &format!("{what} {axis} scale"), t[k + 2])?;
    }
    Ok(p)
}

/// Reads the line after the device line as the name of the device `what` (its first word,
/// `*NAME` or `NAME@host`; `NULL` for none).
pub fn device_line(
    line: &mut ConfigLine<'_, '_>,
    what: &str,
) -> Result<Option<DeviceRef>, ConfigError> {
    let ctx = line.ctx();
    let block = Ctx::new(ctx.file, ctx.line, format!("{} {what}", line.keyword()));
    let next = line.block_line_in(&block, &format!("the {what} line"))?;
    let ctx = block.at(next.number);
    let t = c_tokens(next.text);
    let Some(first) = t.first() else {
        return Err(ctx.err(
            ConfigErrorKind::MissingArguments,
            format!("the {what} line needs a device name (*NAME or NAME@host) or NULL"),
        ));
    };
    device_ref(&ctx, &format!("{what} device"), first, true)
}

/// The latest vector of an axis line and the time of the report it came from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuVector {
    /// The values (0 before any report, as in C++).
    pub values: [f64; 3],
    /// The report's time stamp.
    pub time: TimeVal,
}
