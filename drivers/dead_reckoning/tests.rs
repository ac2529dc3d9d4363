//! The predictor against C++ VRPN 07.38's own output, and its configuration line.

use super::predict::{ahead, Prediction, Sensor};
use super::DeadReckoning;
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::time::TimeVal;

/// See the fixture's header: a DTrack tracker and a spinning tracker, each predicted by a C++
/// `vrpn_Tracker_DeadReckoning_Rotation`, as a client heard them.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_dead_reckoning.txt");

/// One captured report.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Report<'a> {
    velocity: bool,
    device: &'a str,
    time: TimeVal,
    sensor: usize,
    pos: [f64; 3],
    quat: [f64; 4],
    dt: f64,
}

fn capture() -> Vec<Report<'static>> {
    CXX_CAPTURE
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let v: Vec<&str> = l.split_whitespace().collect();
            let f = |i: usize| v[i].parse::<f64>().unwrap();
            Report {
                velocity: v[0] == "V",
                device: v[1],
                time: TimeVal {
                    sec: v[2].parse().unwrap(),
                    usec: v[3].parse().unwrap(),
                },
                sensor: v[4].parse().unwrap(),
                pos: [f(5), f(6), f(7)],
                quat: [f(8), f(9), f(10), f(11)],
                dt: if v[0] == "V" { f(12) } else { 0.0 },
            }
        })
        .collect()
}

/// Replays `source`'s reports through a fresh predictor of `sensors` sensors predicting
/// `prediction` seconds, returning what it would send, `(reported, comparable)`: a report
/// is comparable once its sensor's state no longer depends on reports the client missed.
fn replay(
    reports: &[Report<'static>],
    source: &str,
    sensors: usize,
    prediction: f32,
) -> Vec<(Report<'static>, bool)> {
    let mut state = vec![Sensor::default(); sensors];
    let mut out = vec![];
    let prediction = prediction as f64;
    let mut push = |s: &Sensor, sensor: usize, known: bool| {
        if let Some(Prediction { time, pos, quat }) = s.predict(prediction) {
            out.push((
                Report {
                    velocity: false,
                    device: "",
                    time,
                    sensor,
                    pos,
                    quat,
                    dt: 0.0,
                },
                known,
            ));
        }
        out.len()
    };
    let mut known = vec![false; sensors];
    let mut velocities = vec![];
    for r in reports.iter().filter(|r| r.device == source) {
        let i = r.sensor;
        if i >= sensors {
            continue;
        }
        if r.velocity {
            state[i].velocity(r.quat, r.dt);
            known[i] = true;
            let n = push(&state[i], i, known[i]);
            velocities.push((n, *r));
        } else {
            // A source that never reports velocities is fully heard from its first pose.
            if !source.starts_with("Spin") {
                known[i] = true;
            }
            state[i].pose(r.time, r.pos, r.quat);
            push(&state[i], i, known[i]);
        }
    }
    // Velocities are passed through after the prediction they cause.
    for (k, (n, v)) in velocities.into_iter().enumerate() {
        out.insert(n + k, (v, true));
    }
    out
}

fn compare(source: &str, device: &str, sensors: usize, prediction: f32) -> usize {
    let reports = capture();
    let want: Vec<&Report> = reports.iter().filter(|r| r.device == device).collect();
    let got = replay(&reports, source, sensors, prediction);
    assert!(
        got.len() >= want.len() && got.len() <= want.len() + 2 * sensors,
        "{device}: {} computed, {} captured",
        got.len(),
        want.len()
    );
    let mut compared = 0;
    for ((g, known), w) in got.iter().zip(&want) {
        assert_eq!(g.velocity, w.velocity, "{device} at {:?}", w.time);
        if !known {
            continue;
        }
        assert_eq!((g.time, g.sensor), (w.time, w.sensor), "{device}");
        assert_eq!(g.pos, w.pos, "{device} position at {:?}", w.time);
        assert_eq!(g.quat, w.quat, "{device} orientation at {:?}", w.time);
        assert_eq!(g.dt, w.dt, "{device} dt at {:?}", w.time);
        compared += 1;
    }
    compared
}

#[test]
fn poses_only_source_same_numbers_as_cxx() {
    // DTrack reports no velocities: the rotation is estimated from successive poses.
    let n = compare("DTrack", "DRd", 3, 0.0333);
    assert!(n >= 130, "{n}");
}

#[test]
fn velocity_source_same_numbers_as_cxx() {
    // Spin reports velocities: predictions use them (1.7 s ahead, over a rotation per 1.5 s:
    // one whole step and a fraction), and they are passed through.
    let n = compare("Spin", "DRs", 2, 1.7);
    assert!(n >= 600, "{n}");
}

#[test]
fn degenerate_intervals_never_hang() {
    let mut s = Sensor::default();
    let t = TimeVal {
        sec: 100,
        usec: 999_990,
    };
    let q = [0.0, 0.0, 0.38268343236508984, 0.9238795325112867];
    s.pose(t, [1.0, 2.0, 3.0], q);
    // Two poses with the same time: the interval is 0 (C++ would loop forever).
    s.pose(t, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]);
    let p = s.predict(0.5).unwrap();
    assert_eq!(p.quat, [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(
        p.time,
        TimeVal {
            sec: 101,
            usec: 499_990
        }
    );
    // A velocity over a microscopic interval: bounded work.
    s.velocity([0.0, 0.0, 1e-9, 1.0], 1e-12);
    let p = s.predict(1000.0).unwrap();
    assert!(p.quat.iter().all(|v| v.is_finite()));
    // Not a number anywhere: no panic, the orientation is passed on.
    s.velocity([f64::NAN; 4], f64::NAN);
    assert!(s.predict(0.1).is_some());
}

#[test]
fn time_ahead_is_carried_as_cxx_does() {
    let t = TimeVal {
        sec: 10,
        usec: 900_000,
    };
    assert_eq!(
        ahead(t, 0.0333f32 as f64),
        TimeVal {
            sec: 10,
            usec: 933_300
        }
    );
    assert_eq!(
        ahead(t, 1.7f32 as f64),
        TimeVal {
            sec: 12,
            usec: 600_000
        }
    );
}

fn parse_line(text: &str) -> Result<DeadReckoning, crate::config::ConfigError> {
    let cfg = format!("{text}\n");
    let entries = crate::server::config::parse_str(&cfg, "dr.cfg")?;
    Ok(entries[0].spec::<DeadReckoning>().unwrap().clone())
}

#[test]
fn configuration_line_of_the_cpp_sample() {
    let d = parse_line("vrpn_Tracker_DeadReckoning_Rotation Tracker1 *Tracker0 2 0.0333").unwrap();
    assert_eq!(d.source, DeviceRef::Local("Tracker0".into()));
    assert_eq!((d.sensors, d.prediction), (2, 0.0333f32));
    let d = parse_line("vrpn_Tracker_DeadReckoning_Rotation T T0@host 1 0").unwrap();
    assert_eq!(d.source, DeviceRef::Remote("T0@host".into()));
    for (line, kind) in [
        (
            "vrpn_Tracker_DeadReckoning_Rotation T *T0 2",
            ConfigErrorKind::MissingArguments,
        ),
        (
            "vrpn_Tracker_DeadReckoning_Rotation T *T0 0 0.1",
            ConfigErrorKind::OutOfRange,
        ),
        (
            "vrpn_Tracker_DeadReckoning_Rotation T *T0 2 -0.1",
            ConfigErrorKind::OutOfRange,
        ),
        (
            "vrpn_Tracker_DeadReckoning_Rotation T *T0 2 soon",
            ConfigErrorKind::BadNumber,
        ),
    ] {
        let e = parse_line(line).unwrap_err();
        assert_eq!(e.kind(), kind, "{line}: {e}");
        assert!(e.to_string().starts_with("dr.cfg:1: "), "{e}");
    }
}
