//! The glove buttons against C++ VRPN 07.38's own output, and the configuration line.

use super::{pressed, Button5dtServer, BUTTONS};
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::fixture_records;

/// See the header of the file.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_button_5dt_server.txt");

const THRESHOLDS: [f64; BUTTONS] = [
    2048.0, 1000.0, 3000.0, 2500.0, 1500.0, 2048.5, 100.0, 4000.0, 2000.0, 2100.0, 1800.0, 2600.0,
    900.0, 3500.0, 0.0, 4095.0,
];

#[test]
fn same_changes_as_cxx_for_the_same_input() {
    // The client joined while the glove was streaming: the state before the first report it
    // heard is unknown, so comparisons start with the second report.
    let mut state: Option<[bool; BUTTONS]> = None;
    let mut expected: Vec<(f64, f64)> = Vec::new();
    let mut compared = 0;
    for (tag, v) in fixture_records(CXX_CAPTURE) {
        match tag {
            "IN" => {
                assert!(expected.is_empty(), "C++ did not send {expected:?}");
                let n = v[2] as usize;
                let now = pressed(&v[3..3 + n], &THRESHOLDS);
                if let Some(before) = state {
                    for i in (0..BUTTONS).rev() {
                        if now[i] != before[i] {
                            expected.push((i as f64, f64::from(u8::from(now[i]))));
                        }
                    }
                }
                state = Some(now);
            }
            "BTN" => {
                if compared == 0 && expected.is_empty() {
                    continue; // a change of the first report
                }
                let want = expected.pop().expect("a change C++ sent");
                assert_eq!((v[2], v[3]), want);
                compared += 1;
            }
            _ => panic!("unknown record {tag}"),
        }
    }
    assert!(compared >= 80, "{compared}");
}

fn parse(text: &str) -> Result<Button5dtServer, crate::config::ConfigError> {
    let cfg = format!("{text}\n");
    let entries = crate::server::config::parse_str(&cfg, "b.cfg")?;
    Ok(entries[0].spec::<Button5dtServer>().unwrap().clone())
}

#[test]
fn configuration_line_of_the_cpp_sample() {
    let b = parse(
        "vrpn_Button_5DT_Server glove_5dt_button glove_5dt16 1794 2171 2110 2610 1707 2673 \
         2459 1493 3029 2301 1936 3007 2302 1635 0 0",
    )
    .unwrap();
    assert_eq!(b.source, DeviceRef::Local("glove_5dt16".into()));
    assert_eq!(b.thresholds[0], 1794.0);
    assert_eq!(b.thresholds[13], 1635.0);
    let t = " 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15.5 16";
    let b = parse(&format!("vrpn_Button_5DT_Server B *G{t}")).unwrap();
    assert_eq!(b.source, DeviceRef::Local("G".into()));
    assert_eq!(b.thresholds[14], 15.5);
    let b = parse(&format!("vrpn_Button_5DT_Server B G@host{t}")).unwrap();
    assert_eq!(b.source, DeviceRef::Remote("G@host".into()));
    for (line, kind) in [
        (
            "vrpn_Button_5DT_Server B G 1 2 3".to_string(),
            ConfigErrorKind::MissingArguments,
        ),
        (
            format!("vrpn_Button_5DT_Server B G{t} 17"),
            ConfigErrorKind::BadValue,
        ),
        (
            format!("vrpn_Button_5DT_Server B G{}", t.replace("7", "x")),
            ConfigErrorKind::BadNumber,
        ),
        (
            format!("vrpn_Button_5DT_Server B NULL{t}"),
            ConfigErrorKind::BadName,
        ),
    ] {
        let e = parse(&line).unwrap_err();
        assert_eq!(e.kind(), kind, "{line}: {e}");
        assert!(e.to_string().starts_with("b.cfg:1: "), "{e}");
    }
}

#[test]
fn a_button_is_pressed_strictly_above_its_threshold() {
    let mut ch = [0.0; 17];
    ch[0] = 2048.0;
    ch[5] = 2049.0;
    ch[14] = 0.5;
    let p = pressed(&ch, &THRESHOLDS);
    assert!(!p[0] && p[5] && p[14] && !p[15]);
    // A short report: missing channels are 0.
    assert_eq!(pressed(&[], &THRESHOLDS), [false; BUTTONS]);
}
