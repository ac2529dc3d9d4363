//! The head tracker against C++ VRPN 07.38's own output, and its configuration lines.

use super::{quat_from_two_vecs, quat_xform, HeadTracker, WiimoteHead};
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::fixture_records;
use crate::time::TimeVal;

/// See the header of the file.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_wiimote_head.txt");

/// The LED spacing of the capture's configuration line, read as C++ reads it.
const SPACING: f32 = 0.25;

#[test]
fn same_poses_as_cxx_for_the_same_input() {
    let mut head = HeadTracker::new(f64::from(SPACING));
    let (mut inputs, mut compared, mut repeats, mut before_input) = (0, 0, 0, 0);
    // Whether the next OUT answers an input (else it is a periodic repeat, or one before any).
    let mut fresh = false;
    for (tag, v) in fixture_records(CXX_CAPTURE) {
        match tag {
            "IN" => {
                let n = v[2] as usize;
                let t = TimeVal {
                    sec: v[0] as i64,
                    usec: v[1] as i64,
                };
                head.wiimote_report(t, &v[3..3 + n]);
                fresh = true;
                inputs += 1;
            }
            "OUT" => {
                // Every report, periodic or not, runs the pose update once, as in C++.
                head.update_pose();
                let p = head.reported;
                let mut want = vec![0.0];
                match head.time {
                    Some(t) => want.extend([t.sec as f64, t.usec as f64]),
                    None => {
                        // C++ stamps 0 before the first Wiimote report; we use the clock.
                        assert_eq!((v[1], v[2]), (0.0, 0.0));
                        want.extend([0.0, 0.0]);
                        before_input += 1;
                    }
                }
                want.extend(p.xyz);
                want.extend(p.quat);
                assert_eq!(v, want, "C++ sent {v:?} (input {inputs})");
                if !fresh && head.time.is_some() {
                    repeats += 1;
                }
                fresh = false;
                compared += 1;
            }
            _ => panic!("unknown record {tag}"),
        }
    }
    assert_eq!(inputs, 60);
    assert_eq!(compared, 67);
    assert!(
        repeats >= 1 && before_input >= 1,
        "{repeats} {before_input}"
    );
}

#[test]
fn an_upside_down_first_pose_swaps_the_blobs() {
    let t = TimeVal { sec: 5, usec: 0 };
    // Gravity exactly +y: no correction.
    let mut channels = [0.0; 16];
    channels[2] = 1.0;
    // Blob 0 left of blob 1: rotated by π about z, the y axis points down.
    channels[4..10].copy_from_slice(&[300.0, 400.0, 2.0, 700.0, 400.0, 2.0]);
    let mut head = HeadTracker::new(0.145);
    head.wiimote_report(t, &channels);
    head.update_pose();
    assert!(head.locked());
    assert_eq!(
        head.reported.quat,
        crate::layered::quat_from_euler(0.0, 0.0, 0.0)
    );
    let up = quat_xform(&head.reported.quat, &[0.0, 1.0, 0.0]);
    assert!(up[1] > 0.0);
    // Losing a blob loses the lock and keeps the pose.
    let kept = head.reported;
    channels[7..10].copy_from_slice(&[0.0; 3]);
    head.wiimote_report(t, &channels);
    head.update_pose();
    assert!(!head.locked());
    assert_eq!(head.reported, kept);
    assert_eq!(head.blobs().count(), 1);
}

#[test]
fn rotation_between_two_vectors() {
    let q = quat_from_two_vecs(&[0.0, 0.0, 1.0], &[0.0, 0.0, 1.0]);
    assert_eq!(q, [0.0, 0.0, 0.0, 1.0]);
    let q = quat_from_two_vecs(&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0]);
    let r = quat_xform(&q, &[1.0, 0.0, 0.0]);
    assert!((r[0]).abs() < 1e-15 && (r[1] - 1.0).abs() < 1e-15, "{r:?}");
    // Opposed vectors turn about an axis normal to the first.
    let q = quat_from_two_vecs(&[0.0, 0.0, 2.0], &[0.0, 0.0, -1.0]);
    let r = quat_xform(&q, &[0.0, 0.0, 1.0]);
    assert!((r[2] + 1.0).abs() < 1e-15, "{r:?}");
}

fn parse(text: &str) -> Result<WiimoteHead, crate::config::ConfigError> {
    let entries = crate::server::config::parse_str(text, "wh.cfg")?;
    Ok(entries[0].spec::<WiimoteHead>().unwrap().clone())
}

#[test]
fn configuration_lines() {
    let w = parse("vrpn_Tracker_WiimoteHead Tracker0 WiiMote0@localhost\n").unwrap();
    assert_eq!(w.source, DeviceRef::Remote("WiiMote0@localhost".into()));
    assert_eq!((w.min_update_rate, w.led_spacing), (60.0, 0.205));
    assert_eq!(w.max_interval(), 1.0 / 60.0);
    let w = parse("vrpn_Tracker_WiimoteHead H *Wii 4 0.1\n").unwrap();
    assert_eq!(w.source, DeviceRef::Local("Wii".into()));
    assert_eq!((w.min_update_rate, w.led_spacing), (4.0, 0.1));
    assert_eq!(w.max_interval(), 0.25);
    let w = parse("vrpn_Tracker_WiimoteHead H *Wii 0\n").unwrap();
    assert_eq!((w.max_interval(), w.led_spacing), (1.0 / 60.0, 0.205));
    for (text, kind) in [
        (
            "vrpn_Tracker_WiimoteHead H\n",
            ConfigErrorKind::MissingArguments,
        ),
        ("vrpn_Tracker_WiimoteHead H Wii\n", ConfigErrorKind::BadName),
        (
            "vrpn_Tracker_WiimoteHead H NULL\n",
            ConfigErrorKind::BadName,
        ),
        (
            "vrpn_Tracker_WiimoteHead H *Wii fast\n",
            ConfigErrorKind::BadNumber,
        ),
        (
            "vrpn_Tracker_WiimoteHead H *Wii -1\n",
            ConfigErrorKind::OutOfRange,
        ),
        (
            "vrpn_Tracker_WiimoteHead H *Wii 60 wide\n",
            ConfigErrorKind::BadNumber,
        ),
    ] {
        let e = parse(text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert_eq!(e.line(), Some(1), "{text}: {e}");
        assert!(e.to_string().starts_with("wh.cfg:"), "{e}");
    }
}
