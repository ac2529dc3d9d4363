//! The analog poser against C++ VRPN 07.38's own output, and its configuration lines.

use super::{axis_value, clamp_position, PoserAnalog};
use crate::config::{ConfigErrorKind, DeviceRef};
use crate::layered::fixture_records;

/// See the header of the file.
const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_poser_analog.txt");

fn parse(text: &str) -> Result<PoserAnalog, crate::config::ConfigError> {
    let entries = crate::server::config::parse_str(text, "p.cfg")?;
    Ok(entries[0].spec::<PoserAnalog>().unwrap().clone())
}

const CAPTURED: &str = "vrpn_Poser_Analog PA 1\n\
    X AO@127.0.0.1:1 0 0.5 2.0 -1 1.5\n\
    Y AO@127.0.0.1:1 2 -0.25 -3.0 -2 2\n\
    Z AO@127.0.0.1:1 1 0.0 0.1 0 100\n\
    RX NULL 0 0.0 1.0 -10 10\n\
    RY NULL 0 0.0 1.0 -10 10\n\
    RZ NULL 0 0.0 1.0 -10 10\n";

#[test]
fn same_numbers_as_cxx_for_the_same_input() {
    let cfg = parse(CAPTURED).unwrap();
    // Two streams, each in order: what AO received, and what PA's tracker sent.
    let mut ao_want: Vec<Vec<f64>> = Vec::new();
    let mut tracker_want: Vec<(&str, Vec<f64>)> = Vec::new();
    let mut ao_got = Vec::new();
    let mut tracker_got = Vec::new();
    let mut channels = [0.0; 3];
    for (tag, v) in fixture_records(CXX_CAPTURE) {
        match tag {
            "IN" => {
                let p = clamp_position([v[2], v[3], v[4]], &cfg.min(), &cfg.max());
                for (axis, coordinate) in cfg.axes.iter().zip(p) {
                    channels[axis.channel.unwrap() as usize] = axis_value(axis, coordinate);
                    ao_want.push(channels.to_vec());
                }
                let mut out = vec![0.0];
                out.extend_from_slice(&p);
                out.extend_from_slice(&v[5..9]);
                tracker_want.push(("OUT", out));
            }
            "INVEL" => {
                let vel = clamp_position([v[0], v[1], v[2]], &[-1.0; 3], &[1.0; 3]);
                let mut out = vec![0.0];
                out.extend_from_slice(&vel);
                out.extend_from_slice(&v[3..7]);
                out.push(1.0);
                tracker_want.push(("VEL", out));
            }
            "AO" => ao_got.push(v),
            // The pose's time is C++'s clock: not compared.
            "OUT" => tracker_got.push(("OUT", [&v[..1], &v[3..]].concat())),
            "VEL" => tracker_got.push(("VEL", v)),
            _ => panic!("unknown record {tag}"),
        }
    }
    assert_eq!(ao_got.len(), 180);
    assert_eq!(ao_got, ao_want);
    assert_eq!(tracker_got.len(), 66);
    assert_eq!(tracker_got, tracker_want);
}

#[test]
fn configuration_lines_of_the_cpp_sample() {
    let p = parse(
        "vrpn_Poser_Analog\tPoser0\t1\n\
         X\t*MCLXYZOUT\t0\t0.0\t0.1\t0\t100\n\
         Y\t*MCLXYZOUT\t1\t0.0\t0.1\t0\t100\n\
         Z\t*MCLXYZOUT\t2\t0.0\t0.1\t0\t100\n\
         RX\tNULL\t0\t0.0\t1.0\t-10\t10\n\
         RY\tNULL\t0\t0.0\t1.0\t-10\t10\n\
         RZ\tNULL\t0\t0.0\t1.0\t-10\t10\n",
    )
    .unwrap();
    assert!(p.tracker_reports);
    assert_eq!(p.axes[2].device, Some(DeviceRef::Local("MCLXYZOUT".into())));
    assert_eq!(p.axes[2].channel, Some(2));
    // Single precision, as C++ reads it.
    assert_eq!(p.axes[0].scale, f64::from(0.1f32));
    assert_eq!((p.axes[3].device.clone(), p.axes[3].channel), (None, None));
    assert_eq!(p.max(), [100.0; 3]);
    let base = CAPTURED.replace("AO@127.0.0.1:1", "*AO");
    for (text, kind, line) in [
        (
            "vrpn_Poser_Analog P\n".to_string(),
            ConfigErrorKind::MissingArguments,
            1,
        ),
        (
            base.replace("Y *AO", "Z *AO"),
            ConfigErrorKind::BadBlockLine,
            3,
        ),
        (
            base.replace("RZ NULL 0 0.0 1.0 -10 10\n", ""),
            ConfigErrorKind::UnclosedBlock,
            1,
        ),
        (base.replace("-2 2", "-2"), ConfigErrorKind::BadBlockLine, 3),
        (
            base.replace("*AO 1 0.0", "*AO 128 0.0"),
            ConfigErrorKind::OutOfRange,
            4,
        ),
        (
            base.replace("0.1 0 100", "x 0 100"),
            ConfigErrorKind::BadNumber,
            4,
        ),
        (base.replace("*AO 0", "AO 0"), ConfigErrorKind::BadName, 2),
    ] {
        let e = parse(&text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert_eq!(e.line(), Some(line), "{text}: {e}");
    }
}
