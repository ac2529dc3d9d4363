//! `vrpn_Tracker.cfg`, the per-tracker transform file: what a tracker answers to To_Room,
//! Unit_To_Sensor and Workspace requests.

use std::path::Path;

use super::parse::read_config_text;
use crate::config::fields::{f32_field, uint_in};
use crate::config::lines::{c_tokens, is_c_space, Reader};
use crate::config::{ConfigError, ConfigErrorKind, Ctx, MAX_TRACKER_SENSORS};

/// Default name of the per-tracker transform file, looked up in the working directory.
pub const TRACKER_CFG_FILE: &str = "vrpn_Tracker.cfg";

/// A rigid transform: translation then rotation quaternion `(x, y, z, w)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidTransform {
    /// Translation x, y, z.
    pub translation: [f32; 3],
    /// Rotation quaternion x, y, z, w.
    pub rotation: [f32; 4],
}

impl RigidTransform {
    /// No translation, no rotation.
    pub const IDENTITY: RigidTransform = RigidTransform {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
}

impl Default for RigidTransform {
    /// [`RigidTransform::IDENTITY`].
    fn default() -> Self {
        RigidTransform::IDENTITY
    }
}

/// The unit-to-sensor transform of one sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorTransform {
    /// Sensor index.
    pub sensor: u32,
    /// Unit-to-sensor transform.
    pub unit2sensor: RigidTransform,
}

/// One tracker's entry in `vrpn_Tracker.cfg`: what it answers to To_Room,
/// Unit_To_Sensor and Workspace requests.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerTransforms {
    /// Tracker-to-room transform.
    pub tracker2room: RigidTransform,
    /// Workspace minimum corner x, y, z.
    pub workspace_min: [f32; 3],
    /// Workspace maximum corner x, y, z.
    pub workspace_max: [f32; 3],
    /// Sensor count K from the file (trackers such as NULL override it with their own).
    pub num_sensors: u32,
    /// The K unit-to-sensor entries, in file order.
    pub unit2sensor: Vec<SensorTransform>,
}

impl Default for TrackerTransforms {
    /// What a tracker uses without a file: identities, workspace ±0.5, one sensor.
    fn default() -> Self {
        TrackerTransforms {
            tracker2room: RigidTransform::IDENTITY,
            workspace_min: [-0.5; 3],
            workspace_max: [0.5; 3],
            num_sensors: 1,
            unit2sensor: Vec::new(),
        }
    }
}

impl TrackerTransforms {
    /// The unit-to-sensor transform of `sensor` (the last entry for it), identity if none.
    pub fn unit2sensor_for(&self, sensor: u32) -> RigidTransform {
        self.unit2sensor
            .iter()
            .rev()
            .find(|s| s.sensor == sensor)
            .map_or(RigidTransform::IDENTITY, |s| s.unit2sensor)
    }
}

/// Whether `line` begins with `name` immediately followed by a whitespace character.
fn begins_with_name(line: &str, name: &str) -> bool {
    line.strip_prefix(name)
        .and_then(|rest| rest.chars().next())
        .is_some_and(is_c_space)
}

/// Reads the next line of a tracker entry and parses `N` floats from it.
fn tracker_floats<const N: usize>(
    ctx: &Ctx<'_>,
    reader: &mut Reader<'_>,
    what: &str,
    fields: [&str; N],
) -> Result<[f32; N], ConfigError> {
    let line = reader.block_line(ctx, &format!("its {what} line"))?;
    let here = ctx.at(line.number);
    let t = c_tokens(line.text);
    if t.len() < N {
        return Err(here.err(
            ConfigErrorKind::BadBlockLine,
            format!(
                "{what} line needs {N} numbers ({}), found {}",
                fields.join(" "),
                t.len()
            ),
        ));
    }
    let mut out = [0.0; N];
    for (i, v) in out.iter_mut().enumerate() {
        *v = f32_field(&here, &format!("{what} {}", fields[i]), t[i])?;
    }
    Ok(out)
}

/// Reads the next line of a tracker entry as one whole number in `0..=max`.
fn tracker_count(
    ctx: &Ctx<'_>,
    reader: &mut Reader<'_>,
    what: &str,
    max: u32,
) -> Result<u32, ConfigError> {
    let line = reader.block_line(ctx, &format!("its {what} line"))?;
    let here = ctx.at(line.number);
    match c_tokens(line.text).first() {
        Some(tok) => uint_in(&here, what, tok, 0, max),
        None => Err(here.err(
            ConfigErrorKind::BadBlockLine,
            format!("{what} line is empty; expected a whole number"),
        )),
    }
}

/// Reads one `vrpn_Tracker.cfg` unit-to-sensor entry (3 lines).
fn sensor_entry(ctx: &Ctx<'_>, reader: &mut Reader<'_>) -> Result<SensorTransform, ConfigError> {
    let sensor = tracker_count(ctx, reader, "sensor index", MAX_TRACKER_SENSORS - 1)?;
    let translation = tracker_floats(
        ctx,
        reader,
        &format!("sensor {sensor} unit-to-sensor translation"),
        ["x", "y", "z"],
    )?;
    let rotation = tracker_floats(
        ctx,
        reader,
        &format!("sensor {sensor} unit-to-sensor quaternion"),
        ["x", "y", "z", "w"],
    )?;
    Ok(SensorTransform {
        sensor,
        unit2sensor: RigidTransform {
            translation,
            rotation,
        },
    })
}

/// Finds and parses the entry for `tracker_name` (its full name, `@host` included for a
/// client) in `vrpn_Tracker.cfg` text.
///
/// An absent name is a [`ConfigErrorKind::TrackerNotFound`] error (C++ prints "Found config
/// file vrpn_Tracker.cfg, but cannot read info for NAME" and keeps its defaults; a caller
/// wanting that behaviour uses [`TrackerTransforms::default`]). Unlike C++, which silently
/// stops at a malformed unit-to-sensor entry, every malformed or missing line is an error.
pub fn parse_tracker_cfg(
    text: &str,
    file_name: &str,
    tracker_name: &str,
) -> Result<TrackerTransforms, ConfigError> {
    let mut reader = Reader::new(text, file_name);
    let header = loop {
        match reader.next_raw() {
            Some(Ok(line)) if begins_with_name(line.text, tracker_name) => break line,
            Some(Ok(_)) => {}
            Some(Err(e)) => return Err(e),
            None => {
                return Err(ConfigError::at_line(
                    ConfigErrorKind::TrackerNotFound,
                    file_name,
                    reader.last_number,
                    format!(
                        "no entry for tracker '{tracker_name}' (a line starting with the name \
                         followed by a blank); it keeps the default transforms"
                    ),
                ))
            }
        }
    };
    let ctx = Ctx::new(
        file_name,
        header.number,
        format!("tracker '{tracker_name}'"),
    );
    let t2r_pos = tracker_floats(
        &ctx,
        &mut reader,
        "tracker-to-room translation",
        ["x", "y", "z"],
    )?;
    let t2r_quat = tracker_floats(
        &ctx,
        &mut reader,
        "tracker-to-room quaternion",
        ["x", "y", "z", "w"],
    )?;
    let workspace = tracker_floats(
        &ctx,
        &mut reader,
        "workspace",
        ["min_x", "min_y", "min_z", "max_x", "max_y", "max_z"],
    )?;
    let num_sensors = tracker_count(&ctx, &mut reader, "sensor count", MAX_TRACKER_SENSORS)?;
    let mut unit2sensor = Vec::new();
    for _ in 0..num_sensors {
        unit2sensor.push(sensor_entry(&ctx, &mut reader)?);
    }
    Ok(TrackerTransforms {
        tracker2room: RigidTransform {
            translation: t2r_pos,
            rotation: t2r_quat,
        },
        workspace_min: [workspace[0], workspace[1], workspace[2]],
        workspace_max: [workspace[3], workspace[4], workspace[5]],
        num_sensors,
        unit2sensor,
    })
}

/// Loads `tracker_name`'s entry from a `vrpn_Tracker.cfg` file. A missing file is `Ok(None)`
/// (silent, as in C++); other read failures and parse problems are errors.
pub fn load_tracker_cfg(
    path: &Path,
    tracker_name: &str,
) -> Result<Option<TrackerTransforms>, ConfigError> {
    if !path.exists() {
        return Ok(None);
    }
    let text = read_config_text(path)?;
    parse_tracker_cfg(&text, &path.display().to_string(), tracker_name).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracker_name_prefix() {
        assert!(begins_with_name("Tracker0 x\n", "Tracker0"));
        assert!(begins_with_name("Tracker0\n", "Tracker0"));
        assert!(!begins_with_name("Tracker01\n", "Tracker0"));
        assert!(!begins_with_name("Tracker0", "Tracker0"));
    }
}
