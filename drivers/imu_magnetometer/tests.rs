//! The magnetometer against C++ VRPN 07.38's own output, and its configuration lines.

use super::{Calibration, Magnetometer};
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::time::TimeVal;

/// See the fixture's header: analog reports fed to a C++ `vrpn_IMU_Magnetometer`, and what
/// it sent.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_imu_magnetometer.txt");

fn rows(kind: &str) -> Vec<(TimeVal, Vec<f64>)> {
    CXX_CAPTURE
        .lines()
        .filter_map(|l| l.strip_prefix(kind))
        .map(|l| {
            let v: Vec<&str> = l.split_whitespace().collect();
            let time = TimeVal {
                sec: v[0].parse().unwrap(),
                usec: v[1].parse().unwrap(),
            };
            (time, v[2..].iter().map(|x| x.parse().unwrap()).collect())
        })
        .collect()
}

fn parse_text(text: &str) -> Result<Magnetometer, crate::config::ConfigError> {
    let entries = crate::server::config::parse_str(text, "imu.cfg")?;
    Ok(entries[0].spec::<Magnetometer>().unwrap().clone())
}

#[test]
fn same_numbers_as_cxx_for_the_same_input() {
    let cfg = parse_text(
        "vrpn_IMU_Magnetometer Mag 1000.0\nFeed@localhost 6 0.1 1.0 7 0 -2.0 0 0.25 0.5\n",
    )
    .unwrap();
    let inputs = rows("F Feed ");
    let outputs = rows("A Mag ");
    assert!(inputs.len() >= 100, "{}", inputs.len());
    // The vector after each input.
    let mut cal = Calibration::default();
    let mut after = vec![cal.unit()];
    for (time, channels) in &inputs {
        cal.input(cfg.axes.vector(channels), *time);
        after.push(cal.unit());
    }
    // C++ stamps a report with the time it sends it: the input in effect is the latest one
    // sent before that time, or, while that one is still on its way, the one before.
    let mut k_min = 0;
    let mut advanced = 0;
    for (time, got) in &outputs {
        let sent = inputs.iter().take_while(|(t, _)| t < time).count();
        let k = (k_min.max(sent.saturating_sub(1))..=sent)
            .rev()
            .find(|&k| got.as_slice() == &after[k][..])
            .unwrap_or_else(|| panic!("report at {time:?}: not the vector after input {sent}"));
        advanced += usize::from(k > k_min);
        k_min = k;
    }
    assert!(outputs.len() >= 10 * inputs.len(), "{}", outputs.len());
    // Every input was reported.
    assert!(advanced + 2 >= inputs.len(), "{advanced}");
}

#[test]
fn configuration_lines_of_the_cpp_sample() {
    let m = parse_text(
        "vrpn_IMU_Magnetometer Magnetometer0 100.0\n*Oculus0 8 0 -1.0 9 0 -1.0 10 0 -1.0\n",
    )
    .unwrap();
    assert_eq!(m.update_rate, 100.0);
    assert_eq!(m.axes.source, DeviceRef::Local("Oculus0".into()));
    assert_eq!(m.axes.channels, [8, 9, 10]);
    assert_eq!(m.axes.scales, [-1.0; 3]);
    assert_eq!(m.axes.vector(&[0.0; 11][..]).map(|v| v == 0.0), [true; 3]);
    for (text, kind, line) in [
        (
            "vrpn_IMU_Magnetometer M 100\n",
            ConfigErrorKind::UnclosedBlock,
            1,
        ),
        (
            "vrpn_IMU_Magnetometer M 100\n*A 0 0 1 1 0 1 2 0\n",
            ConfigErrorKind::MissingArguments,
            2,
        ),
        (
            "vrpn_IMU_Magnetometer M 100\n*A 0 0 1 1 0 1 200 0 1\n",
            ConfigErrorKind::OutOfRange,
            2,
        ),
        (
            "vrpn_IMU_Magnetometer M 100\nNULL 0 0 1 1 0 1 2 0 1\n",
            ConfigErrorKind::BadName,
            2,
        ),
        (
            "vrpn_IMU_Magnetometer M fast\n*A 0 0 1 1 0 1 2 0 1\n",
            ConfigErrorKind::BadNumber,
            1,
        ),
    ] {
        let e = parse_text(text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert!(e.to_string().starts_with(&format!("imu.cfg:{line}")), "{e}");
    }
}

#[test]
fn unit_vector_edges() {
    let mut c = Calibration::default();
    assert_eq!(c.unit(), [1.0, 0.0, 0.0]);
    c.input([2.0, -2.0, 0.0], TimeVal::ZERO);
    // x at its maximum (1), y at its minimum (0), z at 0 = its only value (0).
    assert_eq!(c.unit(), [1.0, 0.0, 0.0]);
    c.input([f64::NAN, 1.0, 1.0], TimeVal::ZERO);
    assert!(c.unit()[0].is_nan());
}
