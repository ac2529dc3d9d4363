//! CSV export of one device's reports of one kind, floats in full precision.

use std::fmt::Write as _;
use std::io;

use super::decode::Decoded;
use super::walk::Walk;
use crate::log::reader::{LogError, LogReader};
use crate::time::TimeVal;

/// Which reports [`write_csv`] exports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsvKind {
    /// `time,sensor,x,y,z,qx,qy,qz,qw`.
    Pose,
    /// `time,sensor,vx,vy,vz,qx,qy,qz,qw,dt`.
    Velocity,
    /// `time,sensor,ax,ay,az,qx,qy,qz,qw,dt`.
    Acceleration,
    /// `time,button,state` (from `vrpn_Button Change`).
    Button,
    /// `time,n,ch0,…,chN-1`, N the most channels any report of the device has.
    Analog,
    /// `time,dial,change`.
    Dial,
}

impl CsvKind {
    /// Every kind, in the order usage text lists them.
    pub const ALL: [CsvKind; 6] = [
        CsvKind::Pose,
        CsvKind::Velocity,
        CsvKind::Acceleration,
        CsvKind::Button,
        CsvKind::Analog,
        CsvKind::Dial,
    ];

    /// The name used on the command line (and as [`Decoded::kind`]).
    pub fn name(self) -> &'static str {
        match self {
            CsvKind::Pose => "pose",
            CsvKind::Velocity => "velocity",
            CsvKind::Acceleration => "acceleration",
            CsvKind::Button => "button",
            CsvKind::Analog => "analog",
            CsvKind::Dial => "dial",
        }
    }

    /// Parses a command-line name.
    pub fn parse(s: &str) -> Option<CsvKind> {
        CsvKind::ALL.into_iter().find(|k| k.name() == s)
    }

    /// True when `d` is a report of this kind.
    pub fn matches(self, d: &Decoded<'_>) -> bool {
        d.kind() == self.name()
    }

    /// The header row (no newline); `width` is the analog column count.
    pub fn header(self, width: usize) -> String {
        match self {
            CsvKind::Pose => "time,sensor,x,y,z,qx,qy,qz,qw".to_owned(),
            CsvKind::Velocity => "time,sensor,vx,vy,vz,qx,qy,qz,qw,dt".to_owned(),
            CsvKind::Acceleration => "time,sensor,ax,ay,az,qx,qy,qz,qw,dt".to_owned(),
            CsvKind::Button => "time,button,state".to_owned(),
            CsvKind::Dial => "time,dial,change".to_owned(),
            CsvKind::Analog => {
                let mut h = "time,n".to_owned();
                for i in 0..width {
                    let _ = write!(h, ",ch{i}");
                }
                h
            }
        }
    }
}

/// Appends one CSV row (no newline) for a report of `kind`, floats in full precision (Rust
/// `{}`, which round-trips). An analog row is padded with empty cells to `width` channels.
/// Returns false, writing nothing, when `d` is not a report of `kind`.
pub fn csv_row(
    out: &mut String,
    kind: CsvKind,
    time: TimeVal,
    d: &Decoded<'_>,
    width: usize,
) -> bool {
    if !kind.matches(d) {
        return false;
    }
    let _ = write!(out, "{time}");
    fn nums(out: &mut String, vs: &[f64]) {
        for v in vs {
            let _ = write!(out, ",{v}");
        }
    }
    match d {
        Decoded::Pose { sensor, pos, quat } => {
            let _ = write!(out, ",{sensor}");
            nums(out, pos);
            nums(out, quat);
        }
        Decoded::Velocity {
            sensor,
            vel: v,
            quat,
            dt,
        }
        | Decoded::Acceleration {
            sensor,
            acc: v,
            quat,
            dt,
        } => {
            let _ = write!(out, ",{sensor}");
            nums(out, v);
            nums(out, quat);
            nums(out, &[*dt]);
        }
        Decoded::ButtonChange { button, state } => {
            let _ = write!(out, ",{button},{state}");
        }
        Decoded::Dial { dial, change } => {
            let _ = write!(out, ",{dial},{change}");
        }
        Decoded::Analog(ch) => {
            let _ = write!(out, ",{}", ch.len());
            nums(out, ch);
            for _ in ch.len()..width {
                out.push(',');
            }
        }
        _ => unreachable!("kind matched"),
    }
    true
}

/// Why a CSV export cannot start.
#[derive(Debug)]
pub enum CsvError {
    /// No user message in the log comes from the device.
    UnknownDevice {
        /// The device asked for.
        device: String,
        /// Senders of user messages in the log.
        devices: Vec<String>,
        /// Damage that ended the scan early, if any.
        damage: Option<LogError>,
    },
    /// The device sent no report of the kind asked for.
    NoReports {
        /// The device.
        device: String,
        /// The kind asked for.
        kind: CsvKind,
        /// Kinds ([`Decoded::kind`]) the device did send.
        kinds: Vec<&'static str>,
        /// Damage that ended the scan early, if any.
        damage: Option<LogError>,
    },
}

impl std::fmt::Display for CsvError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let damage = match self {
            CsvError::UnknownDevice {
                device,
                devices,
                damage,
            } => {
                write!(f, "no device {device:?} in the log; devices: ")?;
                if devices.is_empty() {
                    write!(f, "(none)")?;
                } else {
                    write!(f, "{}", devices.join(", "))?;
                }
                damage
            }
            CsvError::NoReports {
                device,
                kind,
                kinds,
                damage,
            } => {
                write!(
                    f,
                    "{device} sent no {} reports; it sent: {}",
                    kind.name(),
                    kinds.join(", ")
                )?;
                damage
            }
        };
        if let Some(e) = damage {
            write!(f, " (reading stopped early: {e})")?;
        }
        Ok(())
    }
}

impl std::error::Error for CsvError {}

/// What [`plan_csv`] found: how many rows and how wide.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CsvPlan {
    /// The device.
    pub device: String,
    /// The kind.
    pub kind: CsvKind,
    /// Rows to write.
    pub rows: u64,
    /// Analog channel columns (0 for other kinds).
    pub width: usize,
}

/// Scans the log for `device`'s reports of `kind`. Fails when the device sent no user
/// message at all, or none of that kind.
pub fn plan_csv(reader: &LogReader, device: &str, kind: CsvKind) -> Result<CsvPlan, CsvError> {
    let mut devices: Vec<String> = Vec::new();
    let mut kinds: Vec<&'static str> = Vec::new();
    let mut plan = CsvPlan {
        device: device.to_owned(),
        kind,
        rows: 0,
        width: 0,
    };
    let mut damage = None;
    let mut walk = Walk::new(reader);
    while let Some(rec) = walk.next_record() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                damage = Some(e);
                break;
            }
        };
        if rec.entry.is_system() {
            continue;
        }
        let label = rec.sender_label();
        if label != device {
            if !devices.contains(&label) {
                devices.push(label);
            }
            continue;
        }
        if !kinds.contains(&rec.decoded.kind()) {
            kinds.push(rec.decoded.kind());
        }
        if kind.matches(&rec.decoded) {
            plan.rows += 1;
            if let Decoded::Analog(ch) = &rec.decoded {
                plan.width = plan.width.max(ch.len());
            }
        }
    }
    if kinds.is_empty() {
        return Err(CsvError::UnknownDevice {
            device: device.to_owned(),
            devices,
            damage,
        });
    }
    if plan.rows == 0 {
        return Err(CsvError::NoReports {
            device: device.to_owned(),
            kind,
            kinds,
            damage,
        });
    }
    Ok(plan)
}

/// Writes the header and one row per report of `plan`; returns the rows written and the damage
/// that ended the walk early, if any.
pub fn write_csv(
    reader: &LogReader,
    plan: &CsvPlan,
    out: &mut dyn io::Write,
) -> io::Result<(u64, Option<LogError>)> {
    let mut line = plan.kind.header(plan.width);
    line.push('\n');
    out.write_all(line.as_bytes())?;
    let mut rows = 0;
    let mut walk = Walk::new(reader);
    while let Some(rec) = walk.next_record() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => return Ok((rows, Some(e))),
        };
        if !rec.is_from(&plan.device) {
            continue;
        }
        line.clear();
        if csv_row(
            &mut line,
            plan.kind,
            rec.entry.time(),
            &rec.decoded,
            plan.width,
        ) {
            line.push('\n');
            out.write_all(line.as_bytes())?;
            rows += 1;
        }
    }
    Ok((rows, None))
}

#[cfg(test)]
mod tests {
    use super::super::test_log::sample;
    use super::*;

    #[test]
    fn csv_export() {
        let r = sample().reader();
        let plan = plan_csv(&r, "Tracker0", CsvKind::Pose).unwrap();
        assert_eq!(plan.rows, 3);
        let mut out = Vec::new();
        let (rows, damage) = write_csv(&r, &plan, &mut out).unwrap();
        assert_eq!((rows, damage.is_none()), (3, true));
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines[0], "time,sensor,x,y,z,qx,qy,qz,qw");
        assert_eq!(lines[2], "10.500000,1,0.2,0.5,-1,0,0,0,1");

        let plan = plan_csv(&r, "Button0", CsvKind::Analog).unwrap();
        assert_eq!(plan.width, 3);
        let mut out = Vec::new();
        write_csv(&r, &plan, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "time,n,ch0,ch1,ch2\n10.300000,3,0.25,-0.5,0.001\n10.400000,1,0.75,,\n"
        );
        let plan = plan_csv(&r, "Button0", CsvKind::Button).unwrap();
        let mut out = Vec::new();
        write_csv(&r, &plan, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "time,button,state\n10.250000,1,1\n"
        );

        match plan_csv(&r, "Nobody", CsvKind::Pose) {
            Err(e @ CsvError::UnknownDevice { .. }) => assert_eq!(
                e.to_string(),
                "no device \"Nobody\" in the log; devices: Tracker0, Button0"
            ),
            other => panic!("{other:?}"),
        }
        match plan_csv(&r, "Button0", CsvKind::Dial) {
            Err(e @ CsvError::NoReports { .. }) => {
                assert_eq!(
                    e.to_string(),
                    "Button0 sent no dial reports; it sent: button, analog"
                )
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(CsvKind::parse("velocity"), Some(CsvKind::Velocity));
        assert_eq!(CsvKind::parse("poses"), None);
    }

    #[test]
    fn csv_floats_round_trip() {
        let vals = [0.1, 1.0 / 3.0, -2.5e-7, 123456.789, f64::MIN_POSITIVE];
        let mut s = String::new();
        assert!(csv_row(
            &mut s,
            CsvKind::Analog,
            TimeVal::new(5, 7),
            &Decoded::Analog(vals.to_vec()),
            5
        ));
        let cells: Vec<&str> = s.split(',').collect();
        assert_eq!(cells[0], "5.000007");
        for (cell, v) in cells[2..].iter().zip(vals) {
            assert_eq!(cell.parse::<f64>().unwrap().to_bits(), v.to_bits());
        }
        assert!(!csv_row(
            &mut s,
            CsvKind::Pose,
            TimeVal::ZERO,
            &Decoded::Ping,
            0
        ));
    }
}
