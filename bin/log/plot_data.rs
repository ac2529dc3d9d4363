//! The series `vrpn_log plot` draws, read from a log: one device's poses per sensor,
//! analog channels, button changes, dial turns, and the intervals between its reports.

use std::collections::BTreeMap;

use vrpn::log::tools::{Decoded, Walk};
use vrpn::log::{LogError, LogReader};

/// One device's reports, times in seconds since its first report.
#[derive(Default)]
pub struct PlotData {
    pub device: String,
    /// The first report's time, seconds since the epoch.
    pub start: f64,
    /// The last report's time, seconds after `start`.
    pub end: f64,
    pub poses: BTreeMap<i32, Vec<(f64, [f64; 3])>>,
    pub analog: Vec<(f64, Vec<f64>)>,
    /// Per button, its changes (time, pressed), starting from released.
    pub buttons: BTreeMap<i32, Vec<(f64, bool)>>,
    /// Per dial, its total turn in revolutions after each update.
    pub dials: BTreeMap<i32, Vec<(f64, f64)>>,
    /// Per stream ("sensor 0", "analog", …), the interval before each report: (time, ms).
    pub intervals: BTreeMap<String, Vec<(f64, f64)>>,
}

impl PlotData {
    /// True when nothing plottable came from the device.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
            && self.analog.is_empty()
            && self.buttons.is_empty()
            && self.dials.is_empty()
    }
}

/// What reading the log gave: the data, the devices seen (for a message when `device`
/// sent nothing), and the damage that ended the walk, if any.
pub struct Read {
    pub data: PlotData,
    pub found: bool,
    pub devices: Vec<String>,
    pub damage: Option<LogError>,
}

/// Reads `device`'s reports from `reader`.
pub fn read(reader: &LogReader, device: &str) -> Read {
    let mut d = PlotData {
        device: device.to_string(),
        ..PlotData::default()
    };
    let mut found = false;
    let mut devices: Vec<String> = Vec::new();
    let mut damage = None;
    let mut last: BTreeMap<String, f64> = BTreeMap::new();
    let mut start = None;
    let mut walk = Walk::new(reader);
    while let Some(rec) = walk.next_record() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                damage = Some(e);
                break;
            }
        };
        if !rec.is_from(device) {
            if !rec.entry.is_system() {
                let l = rec.sender_label();
                if !devices.contains(&l) {
                    devices.push(l);
                }
            }
            continue;
        }
        found = true;
        let abs = rec.entry.time().as_secs_f64();
        let stream = match &rec.decoded {
            Decoded::Pose { sensor, .. } => format!("sensor {sensor}"),
            Decoded::Analog(_) => "analog".to_string(),
            Decoded::ButtonChange { .. } | Decoded::ButtonStates(_) => "buttons".to_string(),
            Decoded::Dial { .. } => "dials".to_string(),
            _ => continue,
        };
        // Some C++ devices stamp their first reports with time zero (a Joylin's button
        // states): they are drawn at the start and have no interval.
        let t = if abs == 0.0 {
            0.0
        } else {
            let t = abs - *start.get_or_insert(abs);
            if let Some(prev) = last.insert(stream.clone(), t) {
                d.intervals
                    .entry(stream)
                    .or_default()
                    .push((t, (t - prev) * 1000.0));
            }
            t
        };
        d.end = d.end.max(t);
        match &rec.decoded {
            Decoded::Pose { sensor, pos, .. } => {
                d.poses.entry(*sensor).or_default().push((t, *pos))
            }
            Decoded::Analog(ch) => d.analog.push((t, ch.clone())),
            Decoded::ButtonChange { button, state } => change(&mut d, t, *button, *state != 0),
            Decoded::ButtonStates(states) => {
                for (i, s) in states.iter().enumerate() {
                    change(&mut d, t, i as i32, *s != 0);
                }
            }
            Decoded::Dial { dial, change } => {
                let v = d.dials.entry(*dial).or_default();
                let total = v.last().map_or(0.0, |p| p.1) + change;
                v.push((t, total));
            }
            _ => {}
        }
    }
    d.start = start.unwrap_or(0.0);
    Read {
        data: d,
        found,
        devices,
        damage,
    }
}

/// Records a button's state at `t` when it differs from the last one known.
fn change(d: &mut PlotData, t: f64, button: i32, pressed: bool) {
    let v = d.buttons.entry(button).or_default();
    if v.last().map_or(true, |p| p.1 != pressed) {
        v.push((t, pressed));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn golden(name: &str) -> LogReader {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/golden");
        LogReader::open(dir.join(name)).unwrap()
    }

    /// C++ vrpn_server's 30 Hz spinning tracker: every pose, its intervals about 33 ms.
    #[test]
    fn a_tracker_log_gives_every_pose_and_its_intervals() {
        let r = read(&golden("tracker_spin.out.vrpn"), "Tracker0");
        assert!(r.found && r.damage.is_none());
        let poses = &r.data.poses[&0];
        assert_eq!(poses.len(), 90, "the summary counts 90 Pos_Quat");
        assert_eq!(poses[0].0, 0.0);
        assert!(poses.windows(2).all(|w| w[0].0 <= w[1].0));
        let iv = &r.data.intervals["sensor 0"];
        assert_eq!(iv.len(), 89);
        let mut ms: Vec<f64> = iv.iter().map(|p| p.1).collect();
        ms.sort_by(f64::total_cmp);
        assert!(
            (ms[ms.len() / 2] - 33.3).abs() < 3.0,
            "median {}",
            ms[ms.len() / 2]
        );
        assert!((r.data.end - poses.last().unwrap().0).abs() < 1e-9);
    }

    /// Buttons as changes, analogs per report, dials summed; reports stamped zero (a C++
    /// Joylin's first button states) sit at the start.
    #[test]
    fn buttons_analogs_and_dials() {
        let log = golden("button_analog_dial.out.vrpn");
        let b = read(&log, "Button0").data;
        assert!(!b.buttons.is_empty());
        for changes in b.buttons.values() {
            assert!(
                changes.windows(2).all(|w| w[0].1 != w[1].1),
                "repeated state"
            );
        }
        let a = read(&log, "Analog0").data;
        assert_eq!(a.analog.len(), 79);
        assert!(
            a.end < 10.0,
            "zero timestamps stretched the time axis: {}",
            a.end
        );
        assert!(!a.buttons.is_empty());
        let d = read(&log, "Dial0").data;
        let updates: usize = d.dials.values().map(Vec::len).sum();
        assert_eq!(updates, 82);
        let missing = read(&log, "Nothing");
        assert!(!missing.found);
        assert_eq!(missing.devices, ["Button0", "Dial0", "Analog0"]);
    }
}
