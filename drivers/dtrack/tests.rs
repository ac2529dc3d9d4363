//! The DTrack parser, the report conversion and the configuration line, against frames
//! written by the simulator and values computed independently.

use super::config::{DTrack, Source};
use super::frame::{parse, Malformed, Targets};
use super::report::{report_time, FixedNumbering, Reporter};
use super::sim::{Frame, Rotation};
use crate::config::ConfigErrorKind;
use crate::time::TimeVal;

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// Same rotation: q and −q.
fn same_quat(a: &[f64; 4], b: &[f64; 4]) -> bool {
    close(a, b, 2e-5) || close(a, &b.map(|v| -v), 2e-5)
}

#[test]
fn standard_frames_give_the_simulators_values() {
    let mut targets = Targets::default();
    let mut reporter = Reporter::new(None, true, 0.0);
    let arrived = TimeVal::new(1_700_000_000, 0);
    for k in 1..60 {
        let f = Frame::standard(k, 1_700_000_000, 1000 * k);
        let h = parse(f.text().as_bytes(), &mut targets).unwrap();
        assert_eq!(h.frame, Some(k));
        let out = reporter.frame(&h, &targets, arrived);
        // ts2 within 0.1 s of the arrival: the controller's time is the report's.
        assert_eq!(
            out.time,
            TimeVal {
                sec: 1_700_000_000,
                usec: 1000 * k as i64
            }
        );
        let want = f.expected_poses(true);
        assert_eq!(out.poses.len(), want.len(), "frame {k}");
        for (p, (sensor, pos, quat)) in out.poses.iter().zip(&want) {
            assert_eq!(p.sensor, *sensor, "frame {k}");
            assert!(
                close(&p.pos, pos, 1e-6),
                "frame {k}: {:?} vs {pos:?}",
                p.pos
            );
            assert!(
                same_quat(&p.quat, quat),
                "frame {k}: {:?} vs {quat:?}",
                p.quat
            );
        }
        let stick = &f.sticks[0];
        assert_eq!(out.num_buttons, 8);
        for i in 0..8 {
            assert_eq!(
                out.buttons[i],
                stick.buttons >> i & 1 == 1,
                "frame {k} button {i}"
            );
        }
        assert_eq!(out.num_channels, 2);
        let j0 = format!("{:.2}", stick.joystick[0]).parse::<f32>().unwrap() as f64;
        assert_eq!(out.channels[..2], [j0, 0.25]);
    }
}

#[test]
fn report_time_as_cpp() {
    let arrived = TimeVal::new(1_700_000_100, 500_000);
    let h = |ts: f64, ts2: (u32, u32, u32)| super::frame::Header {
        frame: None,
        timestamp: ts,
        ts2,
        has_bodycal: false,
    };
    // No stamp: the arrival.
    assert_eq!(report_time(&h(-1.0, (0, 0, 0)), arrived), arrived);
    // ts2 far from the arrival (clocks apart): arrival less the latency.
    assert_eq!(
        report_time(&h(-1.0, (5, 0, 2000)), arrived),
        TimeVal {
            sec: 1_700_000_100,
            usec: 498_000
        }
    );
    assert_eq!(
        report_time(&h(-1.0, (5, 0, 600_000)), arrived),
        TimeVal {
            sec: 1_700_000_099,
            usec: 900_000
        }
    );
    // ts: seconds since midnight placed in the arrival's day (1_700_000_100 is 22:15:00 UTC).
    let day = 1_700_000_100 - 1_700_000_100 % 86400;
    assert_eq!(
        report_time(&h(80100.25, (0, 0, 0)), arrived),
        TimeVal {
            sec: day + 80100,
            usec: 250_000
        }
    );
    // Just after midnight by the controller's clock, still before by ours: the next day.
    assert_eq!(
        report_time(&h(10.5, (0, 0, 0)), TimeVal::new(day + 86390, 0)),
        TimeVal {
            sec: day + 86400 + 10,
            usec: 500_000
        }
    );
}

#[test]
fn old_flystick_format_swaps_buttons_and_ramps_the_hat() {
    let mut targets = Targets::default();
    // Hat right (0x80) and button 1 (0x02): VRPN's button 3 is the controller's 1.
    let rot = "1 0 0 0 1 0 0 0 1";
    let text = |bits: u32, ts: f64| {
        format!("fr 1\nts {ts}\n6dcal 1\n6df 1 [0 1.0 {bits}][0 0 0][{rot}]\n")
    };
    let mut reporter = Reporter::new(None, false, 0.5);
    let t0 = TimeVal::new(1_000_000, 0);
    let mut run = |bits: u32, ts: f64, targets: &mut Targets| {
        let h = parse(text(bits, ts).as_bytes(), targets).unwrap();
        let out = reporter.frame(&h, targets, t0);
        (
            out.buttons[..8].to_vec(),
            out.channels[..2].to_vec(),
            out.poses.len(),
        )
    };
    let (b, c, poses) = run(0x00, 100.0, &mut targets);
    // 6dcal 1 less one old-format Flystick: no standard body; the Flystick is sensor 0.
    assert_eq!(poses, 1);
    assert_eq!(b, vec![false; 8]);
    assert_eq!(c, vec![0.0, 0.0]);
    let (b, c, _) = run(0x82, 100.1, &mut targets);
    assert_eq!(b, [false, false, false, true, false, false, false, true]);
    // The hat jumps to 1; the driver ramps at 1/0.5 s: 0.1 s later, 0.2.
    assert!((c[0] - 0.2).abs() < 1e-5, "{c:?}");
    let (_, c, _) = run(0x80, 100.3, &mut targets);
    assert!((c[0] - 0.6).abs() < 1e-5, "{c:?}");
    let (_, c, _) = run(0x80, 100.6, &mut targets);
    assert_eq!(c[0], 1.0);
    let (_, c, _) = run(0x00, 100.7, &mut targets);
    assert_eq!(c[0], 0.0);
}

#[test]
fn damaged_datagrams_are_refused_whole() {
    let good = Frame::standard(4, 1, 0).text();
    let mut targets = Targets::default();
    parse(good.as_bytes(), &mut targets).unwrap();
    let kept = targets.clone();
    let cases: &[(&str, Malformed)] = &[
        ("fr x\n", Malformed::Frame),
        ("ts2 1 2\n", Malformed::Timestamp),
        ("6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0]\n", Malformed::Bodies),
        ("6d 1 [0 1.0][1 2 3]\n", Malformed::Bodies),
        (
            "6d 1 [999 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\n",
            Malformed::TooMany,
        ),
        (
            "6d 1 [-1 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\n",
            Malformed::Bodies,
        ),
        (
            "6df2 1 2 [0 1 2 2][0 0 0][1 0 0 0 1 0 0 0 1][1 0 0]\n",
            Malformed::Flysticks,
        ),
        (
            "6df2 1 1 [0 1 17 2][0 0 0][1 0 0 0 1 0 0 0 1][1 0 0]\n",
            Malformed::Flysticks,
        ),
        (
            "6df 1 [1 1 0][0 0 0][1 0 0 0 1 0 0 0 1]\n",
            Malformed::Flysticks,
        ),
        ("3d 2 [1 1.0][0 0 0]\n", Malformed::Markers),
        ("6dcal x\n", Malformed::Calibrated),
        // Without the blank the identifier is another one: skipped, as in C++.
        ("6dcal\n6d 1 [0 1][0 0 0]\n", Malformed::Bodies),
        ("", Malformed::Empty),
        ("\x01\x02 garbage [[[ 6d 1 [", Malformed::NoDTrackLine),
    ];
    for (text, want) in cases {
        let mut t = kept.clone();
        assert_eq!(parse(text.as_bytes(), &mut t), Err(*want), "{text:?}");
    }
    // Truncated anywhere: refused or (cut between lines) a shorter good frame; never a panic.
    for cut in 0..good.len() {
        let mut t = kept.clone();
        let _ = parse(&good.as_bytes()[..cut], &mut t);
    }
    // Unknown lines are skipped; a NUL ends the datagram as in C.
    let mut t = kept.clone();
    let h = parse(b"xyz 1 2 3\nfr 9\n\0fr 10\n", &mut t).unwrap();
    assert_eq!(h.frame, Some(9));
}

#[test]
fn bodies_not_in_a_frame_stay_as_cpp_keeps_them() {
    let mut targets = Targets::default();
    let m = "[1 0 0 0 1 0 0 0 1]";
    parse(
        format!("6d 2 [0 1][1 2 3]{m} [3 1][4 5 6]{m}\n").as_bytes(),
        &mut targets,
    )
    .unwrap();
    assert_eq!(targets.bodies.len(), 4);
    assert_eq!(targets.bodies[1].quality, -1.0);
    // A frame without a 6d line keeps the bodies (C++ reports them again).
    parse(b"fr 2\n", &mut targets).unwrap();
    assert_eq!(targets.bodies[3].loc, [4.0, 5.0, 6.0]);
    assert_eq!(targets.bodies[3].quality, 1.0);
}

#[test]
fn fixed_numbering_as_cpp() {
    // 2 bodies, 2 Flysticks renumbered 2 1 0 3: the Flysticks' button blocks are their ids
    // less the bodies renumbered below them: 0 → 0 (body 2 and 1 not below 0), 3 → 1.
    let f = FixedNumbering::new(2, 2, Some(&[2, 1, 0, 3]));
    assert_eq!(f.sensor, vec![2, 1, 0, 3]);
    assert_eq!(f.flystick_block, vec![0, 1]);
    let f = FixedNumbering::new(2, 1, None);
    assert_eq!(f.sensor, vec![0, 1, 2]);
    assert_eq!(f.flystick_block, vec![0]);
    // Through a frame: body 0 → sensor 2, body 1 → 1, Flystick 0 → 0.
    let mut targets = Targets::default();
    let m = "[1 0 0 0 1 0 0 0 1]";
    let text =
        format!("6d 2 [0 1][1 0 0]{m} [1 1][2 0 0]{m}\n6df2 1 1 [0 1 8 2][3 0 0]{m}[5 0.5 -0.5]\n");
    let h = parse(text.as_bytes(), &mut targets).unwrap();
    let mut r = Reporter::new(
        Some(FixedNumbering::new(2, 2, Some(&[2, 1, 0, 3]))),
        false,
        0.0,
    );
    let out = r.frame(&h, &targets, TimeVal::new(5, 0));
    let sensors: Vec<(usize, f64)> = out.poses.iter().map(|p| (p.sensor, p.pos[0])).collect();
    assert_eq!(sensors, vec![(2, 0.001), (1, 0.002), (0, 0.003)]);
    assert_eq!(out.num_buttons, 16);
    assert_eq!(&out.buttons[..3], &[true, false, true]);
    assert_eq!(&out.channels[..2], &[0.5, -0.5]);
}

#[test]
fn rotation_matrix_to_quaternion() {
    let r = Rotation {
        axis: [0.0, 0.6, 0.8],
        angle: 2.5,
    };
    let mut targets = Targets::default();
    let text = format!("6d 1 [0 1][0 0 0][{}]\n", r.dtrack_text());
    let h = parse(text.as_bytes(), &mut targets).unwrap();
    let mut rep = Reporter::new(None, false, 0.0);
    let out = rep.frame(&h, &targets, TimeVal::new(1, 0));
    assert!(
        same_quat(&out.poses[0].quat, &r.quat()),
        "{:?}",
        out.poses[0].quat
    );
}

fn parse_line(text: &str) -> Result<DTrack, crate::config::ConfigError> {
    let cfg = format!("vrpn_Tracker_DTrack {text}\n");
    let entries = crate::server::config::parse_str(&cfg, "dtrack.cfg")?;
    Ok(entries[0].spec::<DTrack>().unwrap().clone())
}

#[test]
fn configuration_lines_of_the_cpp_sample() {
    let d = parse_line("DTrack 5000").unwrap();
    assert_eq!(d.source, Source::Port(5000));
    assert!(!d.markers && !d.tracing && d.fixed.is_none());
    let d = parse_line("DTrack 225.1.1.1:5000").unwrap();
    assert_eq!(d.source, Source::Multicast([225, 1, 1, 1].into(), 5000));
    let d = parse_line("DTrack atc-302401001:5000:fw").unwrap();
    assert_eq!(d.source, Source::Firewall("atc-302401001".into(), 5000));
    let d = parse_line("DTrack 5000 3d -").unwrap();
    assert!(d.markers && d.tracing);
    let d = parse_line("DTrack 5000 0.5").unwrap();
    assert_eq!(d.time_to_reach_joy, 0.5);
    let d = parse_line("DTrack 5000 0.5 2 2 2 1 0 3 3d -").unwrap();
    assert_eq!(
        d.fixed,
        Some(FixedNumbering::new(2, 2, Some(&[2, 1, 0, 3])))
    );
    assert!(d.markers && d.tracing);
    let d = parse_line("DTrack 5000 0.5 2 2").unwrap();
    assert_eq!(d.fixed, Some(FixedNumbering::new(2, 2, None)));
}

#[test]
fn bad_configuration_lines_name_file_line_and_problem() {
    let cases = [
        ("DTrack", ConfigErrorKind::MissingArguments),
        ("DTrack 0", ConfigErrorKind::OutOfRange),
        ("DTrack 70000", ConfigErrorKind::OutOfRange),
        ("DTrack 10.0.0.1:5000", ConfigErrorKind::BadValue),
        ("DTrack 225.1.1.1:5000:fw", ConfigErrorKind::BadValue),
        ("DTrack host:5000:xx", ConfigErrorKind::BadValue),
        ("DTrack 5000 0.5 2", ConfigErrorKind::MissingArguments),
        ("DTrack 5000 0.5 2 2 1 0", ConfigErrorKind::MissingArguments),
        ("DTrack 5000 fast", ConfigErrorKind::BadNumber),
    ];
    for (text, kind) in cases {
        let e = parse_line(text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        let shown = e.to_string();
        assert!(
            shown.starts_with("dtrack.cfg:1: vrpn_Tracker_DTrack"),
            "{shown}"
        );
    }
}

/// The frames and C++ VRPN 07.38's poses for them, captured by hand (see the fixture's
/// header): every pose must be the same to the last bit.
#[test]
fn same_poses_as_cxx_for_the_same_frames() {
    let capture = include_str!("../../tests/fixtures/cxx_dtrack_one_euro.txt");
    let mut want = capture.lines().filter_map(|l| l.strip_prefix("DTrack "));
    let mut targets = Targets::default();
    let mut reporter = Reporter::new(None, true, 0.0);
    let mut compared = 0;
    for frame in capture.lines().filter_map(|l| l.strip_prefix("FRAME ")) {
        let text = frame.replace('|', "\r\n");
        let h = parse(text.as_bytes(), &mut targets).unwrap();
        let (sec, usec, _) = h.ts2;
        // Received within 0.1 s of the controller's stamp: the report time is the stamp.
        let arrived = TimeVal::new(sec as i64, usec as i64 + 2000);
        let out = reporter.frame(&h, &targets, arrived);
        for p in &out.poses {
            let line = want.next().expect("as many poses as C++ sent");
            let v: Vec<&str> = line.split_whitespace().collect();
            let f = |i: usize| v[i].parse::<f64>().unwrap();
            assert_eq!(
                (out.time.sec, out.time.usec, p.sensor),
                (f(0) as i64, f(1) as i64, f(2) as usize)
            );
            assert_eq!(p.pos, [f(3), f(4), f(5)], "{line}");
            assert_eq!(p.quat, [f(6), f(7), f(8), f(9)], "{line}");
            compared += 1;
        }
    }
    assert!(want.next().is_none());
    assert!(compared > 400, "{compared}");
}
