//! The combiner against C++ VRPN 07.38's own output, and its configuration lines.

use super::model::{replay, Combiner, Heard};
use super::SimpleCombiner;
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::imu::AxisParams;
use crate::time::TimeVal;

/// See the fixture's header: analog reports fed to two C++ `vrpn_IMU_SimpleCombiner`s, and
/// every report they sent.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_imu_simple_combiner.txt");

fn rows(prefix: &str) -> Vec<(TimeVal, Vec<f64>)> {
    CXX_CAPTURE
        .lines()
        .filter_map(|l| l.strip_prefix(prefix))
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

fn parse_text(text: &str) -> Result<SimpleCombiner, crate::config::ConfigError> {
    let entries = crate::server::config::parse_str(text, "imu.cfg")?;
    Ok(entries[0].spec::<SimpleCombiner>().unwrap().clone())
}

/// The fixture's combiner `name` with its configuration lines `cfg`: every report it sent is
/// what the model computes from the same inputs over the same times.
fn same_as_cxx(name: &str, cfg: &str) {
    let cfg = parse_text(cfg).unwrap();
    let north = AxisParams {
        source: DeviceRef::Local("Feed".into()),
        channels: [0, 1, 2],
        offsets: [0.0; 3],
        scales: [1.0; 3],
    };
    let inputs: Vec<[[f64; 3]; 3]> = rows("F Feed ")
        .iter()
        .map(|(_, ch)| {
            [
                cfg.accel.vector(ch),
                cfg.rotation.vector(ch),
                north.vector(ch),
            ]
        })
        .collect();
    let heard: Vec<Heard> = rows(&format!("P {name} "))
        .iter()
        .map(|(t, v)| (*t, [v[0], v[1], v[2], v[3]], [v[4], v[5], v[6], v[7]]))
        .collect();
    assert!(inputs.len() >= 50 && heard.len() >= 10 * inputs.len());
    let advanced = replay(cfg.magnetometer.is_some(), &inputs, &heard).unwrap();
    // Every input was taken in (two may have come in the same pass).
    assert!(
        advanced + 2 >= inputs.len(),
        "{advanced} of {}",
        inputs.len()
    );
    // The capture covers both sides of the gravity test: inputs near gravity's length
    // (corrections made) and far from it (none).
    let lengths: Vec<f64> = inputs
        .iter()
        .map(|[a, _, _]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt())
        .collect();
    assert!(lengths.iter().any(|l| (l - 9.80665).abs() > 1.0));
    assert!(
        lengths
            .iter()
            .filter(|l| (*l - 9.80665).abs() < 1.0)
            .count()
            > 40
    );
    // And the orientation turned well away from the start (by more than 10°).
    let least_w = heard.iter().map(|h| h.1[3].abs()).fold(1.0, f64::min);
    assert!(least_w < (5.0f64.to_radians()).cos(), "{least_w}");
}

#[test]
fn same_numbers_as_cxx_with_a_magnetometer() {
    same_as_cxx(
        "Comb",
        "vrpn_IMU_SimpleCombiner Comb 1000000.0\n\
         Feed@localhost:1 3 0.05 1.0 4 0 1.0 5 0 -1.0\n\
         Feed@localhost:1 6 0 1.0 7 0 1.0 8 0 1.0\n\
         Feed@localhost:1\n",
    );
}

#[test]
fn same_numbers_as_cxx_without_a_magnetometer() {
    same_as_cxx(
        "Gyro",
        "vrpn_IMU_SimpleCombiner Gyro 1000000.0\n\
         Feed@localhost:1 3 0 1.0 4 0 1.0 5 0 1.0\n\
         Feed@localhost:1 8 0 -1.0 7 0.1 2.0 6 0 1.0\n\
         NULL\n",
    );
}

#[test]
fn a_wrong_input_or_time_is_caught() {
    let inputs = [[[0.0, -9.8, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, -1.0]]];
    let t = |usec| TimeVal { sec: 10, usec };
    let start = Combiner::new(true);
    let mut m = start;
    [m.accel, m.rotation] = [inputs[0][0], inputs[0][1]];
    m.north = Some(inputs[0][2]);
    m.step(0.001);
    let good: Vec<Heard> = vec![
        (t(0), start.quat, start.vel_quat),
        (t(1000), m.quat, m.vel_quat),
    ];
    assert_eq!(replay(true, &inputs, &good), Ok(1));
    let mut late = good.clone();
    late[1].0 = t(1001);
    assert!(replay(true, &inputs, &late).is_err());
    assert!(replay(false, &inputs, &good).is_err());
}

#[test]
fn gyro_alone_turns_at_its_rate_and_gravity_levels() {
    // 0.5 rad/s about Y for 2 s in 1 ms passes, no accelerometer: a turn of 1 rad about Y.
    let mut c = Combiner::new(false);
    c.rotation = [0.0, 0.5, 0.0];
    for _ in 0..2000 {
        c.step(0.001);
    }
    let [x, y, z, w] = c.quat;
    assert!(x.abs() < 1e-12 && z.abs() < 1e-12, "{:?}", c.quat);
    assert!((2.0 * y.atan2(w) - 1.0).abs() < 1e-9, "{:?}", c.quat);
    // Gravity seen along +X in the sensor's frame is brought to -Y: turn about Z by -90°...
    let mut c = Combiner::new(false);
    c.accel = [9.80665, 0.0, 0.0];
    for _ in 0..20_000 {
        c.step(0.001);
    }
    let down = super::model::xform(&c.quat, &[1.0, 0.0, 0.0]);
    assert!((down[1] + 1.0).abs() < 1e-6, "{down:?}");
}

#[test]
fn configuration_lines_of_the_cpp_sample() {
    let c = parse_text(
        "vrpn_IMU_SimpleCombiner Tracker0 400.0\n\
         *Oculus0 2 0 -1.0 3 0 -1.0 4 0 -1.0\n\
         *Oculus0 5 0 1.0 6 0 1.0 7 0 1.0\n\
         *Magnetometer0\n",
    )
    .unwrap();
    assert_eq!(c.update_rate, 400.0);
    assert_eq!(c.accel.source, DeviceRef::Local("Oculus0".into()));
    assert_eq!(c.accel.channels, [2, 3, 4]);
    assert_eq!(c.accel.scales, [-1.0; 3]);
    assert_eq!(c.rotation.channels, [5, 6, 7]);
    assert_eq!(
        c.magnetometer,
        Some(DeviceRef::Local("Magnetometer0".into()))
    );
    let c = parse_text(
        "vrpn_IMU_SimpleCombiner T 0\n*V 1 0 -1.0 0 0 1.0 2 0 1.0\nV@h 4 0 -1.0 3 0 1.0 5 0 1.0\nNULL\n",
    )
    .unwrap();
    assert_eq!(c.magnetometer, None);
    assert_eq!(c.rotation.source, DeviceRef::Remote("V@h".into()));
    for (text, kind, line) in [
        (
            "vrpn_IMU_SimpleCombiner T 400\n",
            ConfigErrorKind::UnclosedBlock,
            1,
        ),
        (
            "vrpn_IMU_SimpleCombiner T 400\n*A 0 0 1 1 0 1 2 0 1\n*A 3 0 1 4 0 1 5 0 1\n",
            ConfigErrorKind::UnclosedBlock,
            1,
        ),
        (
            "vrpn_IMU_SimpleCombiner T 400\n*A 0 0 1 1 0 1 2 0 1\n*A 3 0 1 4 0 1\nNULL\n",
            ConfigErrorKind::MissingArguments,
            3,
        ),
        (
            "vrpn_IMU_SimpleCombiner T 400\n*A 0 0 1 1 0 1 2 0 1\n*A 3 0 1 4 0 1 5 0 1\n\n",
            ConfigErrorKind::MissingArguments,
            4,
        ),
        (
            "vrpn_IMU_SimpleCombiner T -1\n*A 0 0 1 1 0 1 2 0 1\n*A 3 0 1 4 0 1 5 0 1\nNULL\n",
            ConfigErrorKind::OutOfRange,
            1,
        ),
        (
            "vrpn_IMU_SimpleCombiner T\n",
            ConfigErrorKind::MissingArguments,
            1,
        ),
    ] {
        let e = parse_text(text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert!(e.to_string().starts_with(&format!("imu.cfg:{line}")), "{e}");
    }
}
