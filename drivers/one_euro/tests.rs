//! The 1€ filter against C++ VRPN 07.38's own output, and its configuration line.

use super::filter::{quat_normalize, OrientationFilter, Params, PositionFilter};
use super::FilterOneEuro;
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::interval;
use crate::time::TimeVal;

/// Poses captured from a C++ VRPN 07.38 `vrpn_server` (built from the public source, not part
/// of this repository) serving `vrpn_Tracker_DTrack DTrack PORT` and
/// `vrpn_Tracker_FilterOneEuro Filter0 *DTrack 5 1.15 1.0 1.2 1.5 5.0 1.2`, fed the DTrack
/// simulator's standard frames (`drivers/dtrack/sim.rs`), read by this crate's
/// `TrackerRemote` with full precision: lines `FRAME text` (the datagram, `|` for CR LF),
/// then `DTrack SEC USEC SENSOR X Y Z QX QY QZ QW` and `Filter0 ...` in the order C++ sent
/// them.
pub(crate) const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_dtrack_one_euro.txt");

/// One pose line of the capture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Captured {
    pub time: TimeVal,
    pub sensor: usize,
    pub pos: [f64; 3],
    pub quat: [f64; 4],
}

pub(crate) fn captured(device: &str) -> Vec<Captured> {
    CXX_CAPTURE
        .lines()
        .filter_map(|l| l.strip_prefix(device)?.strip_prefix(' '))
        .map(|l| {
            let v: Vec<&str> = l.split_whitespace().collect();
            let f = |i: usize| v[i].parse::<f64>().unwrap();
            Captured {
                time: TimeVal {
                    sec: v[0].parse().unwrap(),
                    usec: v[1].parse().unwrap(),
                },
                sensor: v[2].parse().unwrap(),
                pos: [f(3), f(4), f(5)],
                quat: [f(6), f(7), f(8), f(9)],
            }
        })
        .collect()
}

#[test]
fn same_numbers_as_cxx_for_the_same_input() {
    let source = captured("DTrack");
    let want = captured("Filter0");
    assert!(source.len() > 100 && source.len() == want.len());
    let params = |a, b, c| Params {
        min_cutoff: a,
        beta: b,
        derivative_cutoff: c,
    };
    let mut pos = vec![PositionFilter::new(params(1.15, 1.0, 1.2)); 5];
    let mut rot = vec![OrientationFilter::new(params(1.5, 5.0, 1.2)); 5];
    let mut last = [TimeVal::ZERO; 5];
    for (s, w) in source.iter().zip(&want) {
        let i = s.sensor;
        let mut dt = interval(s.time, last[i]);
        if dt <= 0.0 {
            dt = 1.0;
        }
        last[i] = s.time;
        let p = pos[i].filter(dt, &s.pos);
        let q = quat_normalize(&rot[i].filter(dt, &s.quat));
        assert_eq!((w.time, w.sensor), (s.time, i));
        assert_eq!(p, w.pos, "position, sensor {i} at {:?}", s.time);
        assert_eq!(q, w.quat, "orientation, sensor {i} at {:?}", s.time);
    }
}

fn parse_line(text: &str) -> Result<FilterOneEuro, crate::config::ConfigError> {
    let cfg = format!("{text}\n");
    let entries = crate::server::config::parse_str(&cfg, "filter.cfg")?;
    Ok(entries[0].spec::<FilterOneEuro>().unwrap().clone())
}

#[test]
fn configuration_line_of_the_cpp_sample() {
    let f = parse_line("vrpn_Tracker_FilterOneEuro Filter0 *Tracker0 2 1.15 1.0 1.2 1.5 5.0 1.2")
        .unwrap();
    assert_eq!(f.source, DeviceRef::Local("Tracker0".into()));
    assert_eq!(f.sensors, 2);
    assert_eq!(f.position.beta, 1.0);
    assert_eq!(f.orientation.min_cutoff, 1.5);
    let f = parse_line("vrpn_Tracker_FilterOneEuro F T@host 1 1 1 1 1 1 1").unwrap();
    assert_eq!(f.source, DeviceRef::Remote("T@host".into()));
    for (line, kind) in [
        (
            "vrpn_Tracker_FilterOneEuro F *T 2 1 1 1 1 1",
            ConfigErrorKind::MissingArguments,
        ),
        (
            "vrpn_Tracker_FilterOneEuro F *T 0 1 1 1 1 1 1",
            ConfigErrorKind::OutOfRange,
        ),
        (
            "vrpn_Tracker_FilterOneEuro F *T 2 1 x 1 1 1 1",
            ConfigErrorKind::BadNumber,
        ),
    ] {
        let e = parse_line(line).unwrap_err();
        assert_eq!(e.kind(), kind, "{line}: {e}");
        assert!(e.to_string().starts_with("filter.cfg:1: "), "{e}");
    }
}
