//! The GameTrak against C++ VRPN 07.38's own output, and its configuration lines.

use super::{tether_positions, GameTrak};
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::fixture_records;

/// See the header of the file.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_gametrak.txt");

#[test]
fn same_numbers_as_cxx_for_the_same_input() {
    let mapping = [1, 0, 2, 4, 3, 5];
    let mut expected: Vec<Vec<f64>> = Vec::new();
    let mut compared = 0;
    for (tag, v) in fixture_records(CXX_CAPTURE) {
        match tag {
            "IN" => {
                let n = v[2] as usize;
                let pos = tether_positions(&v[3..3 + n], &mapping);
                expected.clear();
                for (sensor, p) in pos.iter().enumerate() {
                    let mut e = vec![sensor as f64, v[0], v[1]];
                    e.extend_from_slice(p);
                    e.extend_from_slice(&[0.0, 0.0, 0.0, 1.0]);
                    expected.push(e);
                }
                expected.reverse();
            }
            "OUT" => {
                let want = expected.pop().expect("an output for each input");
                assert_eq!(v, want, "C++ sent {v:?}");
                compared += 1;
            }
            _ => panic!("unknown record {tag}"),
        }
    }
    assert_eq!(compared, 120);
}

fn parse(text: &str) -> Result<GameTrak, crate::config::ConfigError> {
    let entries = crate::server::config::parse_str(text, "gt.cfg")?;
    Ok(entries[0].spec::<GameTrak>().unwrap().clone())
}

#[test]
fn configuration_lines() {
    let g = parse("vrpn_Tracker_GameTrak GameTrak0 *RawGametrak\n\n").unwrap();
    assert_eq!(g.source, DeviceRef::Local("RawGametrak".into()));
    assert_eq!(g.mapping, [0, 1, 2, 3, 4, 5]);
    let g = parse("vrpn_Tracker_GameTrak G J@host\naxis_mapping 5 4 3\n").unwrap();
    assert_eq!(g.source, DeviceRef::Remote("J@host".into()));
    assert_eq!(g.mapping, [5, 4, 3, 3, 4, 5]);
    // The entry after the mapping line is read as usual.
    let e = crate::server::config::parse_str(
        "vrpn_Tracker_GameTrak G *J\naxis_mapping 1 0 2 4 3 5\nvrpn_Tracker_NULL T 1 60\n",
        "gt.cfg",
    )
    .unwrap();
    assert_eq!(e.len(), 2);
    for (text, kind, line) in [
        (
            "vrpn_Tracker_GameTrak G\n\n",
            ConfigErrorKind::MissingArguments,
            1,
        ),
        ("vrpn_Tracker_GameTrak G J\n\n", ConfigErrorKind::BadName, 1),
        (
            "vrpn_Tracker_GameTrak G *J\n",
            ConfigErrorKind::UnclosedBlock,
            1,
        ),
        (
            "vrpn_Tracker_GameTrak G *J\nvrpn_Tracker_NULL T 1 60\n",
            ConfigErrorKind::BadBlockLine,
            2,
        ),
        (
            "vrpn_Tracker_GameTrak G *J\naxis_mapping 0 1 2 3 4 128\n",
            ConfigErrorKind::OutOfRange,
            2,
        ),
        (
            "vrpn_Tracker_GameTrak G *J\naxis_mapping 0 1 x\n",
            ConfigErrorKind::BadNumber,
            2,
        ),
    ] {
        let e = parse(text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert_eq!(e.line(), Some(line), "{text}: {e}");
        assert!(e.to_string().starts_with("gt.cfg:"), "{e}");
    }
}
