//! JoyFly against C++ VRPN 07.38's own output, its file and its configuration line.

use super::{Flight, JoyFly, JoyFlyFile};
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::fixture_records;
use crate::time::TimeVal;

/// See the header of the file.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_joyfly.txt");
const CXX_FILE: &str = include_str!("../../tests/fixtures/cxx_joyfly.cfg");

#[test]
fn same_numbers_as_cxx_for_the_same_input() {
    let mut flight = Flight::new(JoyFlyFile::parse(CXX_FILE).unwrap());
    let mut expected = None;
    let mut compared = 0;
    for (tag, v) in fixture_records(CXX_CAPTURE) {
        match tag {
            "IN" => {
                assert_eq!(expected, None, "C++ sent nothing for a report");
                let n = v[2] as usize;
                let t = TimeVal {
                    sec: v[0] as i64,
                    usec: v[1] as i64,
                };
                expected = flight.step(t, &v[3..3 + n]);
            }
            "OUT" => {
                let (p, q) = expected.take().expect("a report C++ sent");
                let want = [&[0.0, 0.0, 0.0][..], &p, &q].concat();
                assert_eq!(v, want);
                compared += 1;
            }
            _ => panic!("unknown record {tag}"),
        }
    }
    assert_eq!(compared, 53);
}

#[test]
fn file_and_line() {
    let f = JoyFlyFile::parse(CXX_FILE).unwrap();
    assert_eq!(f.accel[6], 3.0);
    assert_eq!(f.power[2], 3);
    assert_eq!(f.init[3], [0.1, 0.2, 0.3, 1.0]);
    assert!(JoyFlyFile::parse("1 1\n")
        .unwrap_err()
        .contains("channel 1"));
    assert!(JoyFlyFile::parse(&CXX_FILE.replace("3 2", "3 x"))
        .unwrap_err()
        .contains("power"));
    assert!(JoyFlyFile::parse(&CXX_FILE[..CXX_FILE.len() - 2])
        .unwrap_err()
        .contains("15 of its 16"));
    let dir = std::env::temp_dir().join(format!("joyfly-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("good.cfg");
    std::fs::write(&good, CXX_FILE).unwrap();
    let bad = dir.join("bad.cfg");
    std::fs::write(&bad, "1 1 2").unwrap();
    let parse = |text: String| {
        crate::server::config::parse_str(&text, "j.cfg")
            .map(|e| e[0].spec::<JoyFly>().unwrap().clone())
    };
    let j = parse(format!(
        "vrpn_JoyFly walk-joybox *joybox {}\n",
        good.display()
    ))
    .unwrap();
    assert_eq!(j.source, DeviceRef::Local("joybox".into()));
    assert_eq!(j.file, Some(f));
    // A missing file is C++'s defaults.
    let j = parse("vrpn_JoyFly J J@host /nonexistent/vrpn_Joyfly.cfg\n".into()).unwrap();
    assert_eq!(j.file, None);
    for (text, kind) in [
        (
            "vrpn_JoyFly J *joy\n".to_string(),
            ConfigErrorKind::MissingArguments,
        ),
        (
            "vrpn_JoyFly J joy x.cfg\n".to_string(),
            ConfigErrorKind::BadName,
        ),
        (
            format!("vrpn_JoyFly J *joy {}\n", bad.display()),
            ConfigErrorKind::BadValue,
        ),
    ] {
        let e = parse(text.clone()).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert!(e.to_string().starts_with("j.cfg:1: "), "{e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_reset_returns_to_the_initial_matrix_and_a_one_millisecond_step() {
    let file = JoyFlyFile::default();
    let mut f = Flight::new(file);
    let t = TimeVal { sec: 5, usec: 0 };
    let (p1, _) = f.step(t, &[0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    // After a reset: 1 ms of x = 0.5 moves x by -0.5 (the translation's sign, as C++).
    assert_eq!(p1[0], -0.5);
    f.reset();
    let (p2, q2) = f.step(t, &[0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert_eq!((p2, q2[3]), (p1, 1.0));
    // A channel out of range moves nothing.
    assert!(f.step(t, &[0.0, 0.6, 0.0, 0.0, 0.0, 0.0, 0.0]).is_none());
}
