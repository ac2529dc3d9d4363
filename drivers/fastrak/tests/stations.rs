//! Station devices: IS-900 wands and styluses, the Fastrak stylus, InterSense entries.

use super::*;

/// Expected button Change messages of `device` for the records of `station` in `log`.
fn expected_changes(
    device: &'static str,
    log: &[SentRecord],
    station: u8,
    count: usize,
    bits: impl Fn(u64) -> u8,
    time: impl Fn(&SentRecord) -> TimeVal,
) -> Vec<Seen> {
    let mut last = 0u8;
    let mut out = Vec::new();
    for r in log.iter().filter(|r| r.station == station) {
        let now = bits(r.seq);
        for i in 0..count {
            let (was, is) = (last >> i & 1, now >> i & 1);
            if was != is {
                out.push(Seen::Button(device, i as i32, i32::from(is), time(r)));
            }
        }
        last = now;
    }
    out
}

#[test]
fn is900_wand_and_stylus_report_under_their_own_names_with_tracker_time() {
    let mut sim = SimConfig::new(115_200);
    sim.stations = 4;
    let mut rig = rig(IS900, &["Wand0", "Stylus0"], sim, 12);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(2));
    let d = &rig.line.device;
    assert_eq!(d.output_list(1), [2, 11, 21, 22, 23, 0]);
    assert_eq!(d.output_list(2), [2, 11, 21, 0]);
    assert_eq!(d.output_list(3), [2, 11, 21, 22, 0]);
    assert_eq!(d.output_list(4), [2, 11, 21, 0]);
    assert!(d.commands.iter().any(|c| c == "MT"));
    let zero = rig
        .line
        .driver
        .protocol()
        .clock_zero()
        .expect("IS900time zeroes the clock");
    // The tracker clock was zeroed when MZ reached it; the host estimate adds the 7 bytes'
    // transmission (0.6 ms at 115200 baud).
    let mz = rig.wall_at(d.clock_zero().unwrap());
    assert!(
        (zero.seconds_since(mz) - 0.000_608).abs() < 1e-6,
        "{zero} vs {mz}"
    );

    let log = rig.binary_log();
    let time_of = |r: &SentRecord| {
        TimeVal::from_micros(zero.as_micros() + is900_offset(r.device_ms).as_micros())
    };
    let seen = rig.seen.borrow().clone();
    let poses: Vec<TrackerPose> = rig.poses();
    assert!(poses.len() > 400);
    for (p, r) in poses.iter().zip(&log) {
        assert_eq!(actual(p), expected_pose(r, time_of(r)));
        // The tracker stamps the sample, which it then sends: a little before the arrival
        // (less than one cycle of four records on the line).
        let early = rig.arrival(r).seconds_since(p.time);
        assert!((0.0..0.015).contains(&early), "{early}");
    }
    let n = poses.len();
    let delivered = &log[..n];
    let wand: Vec<Seen> = seen
        .iter()
        .filter(|s| matches!(s, Seen::Button("Wand0", ..)))
        .cloned()
        .collect();
    assert_eq!(
        wand,
        expected_changes("Wand0", delivered, 1, 6, |s| sim::buttons(1, s), time_of)
    );
    assert!(wand.len() > 20);
    let stylus: Vec<Seen> = seen
        .iter()
        .filter(|s| matches!(s, Seen::Button("Stylus0", ..)))
        .cloned()
        .collect();
    assert_eq!(
        stylus,
        expected_changes("Stylus0", delivered, 3, 2, |s| sim::buttons(3, s), time_of)
    );
    assert!(!stylus.is_empty());
    let unit = WandClip {
        min: -1.0,
        low_zero: 0.0,
        high_zero: 0.0,
        max: 1.0,
    };
    let analog: Vec<Seen> = seen
        .iter()
        .filter(|s| matches!(s, Seen::Analog(..)))
        .cloned()
        .collect();
    let mut want = Vec::new();
    let mut last = [0.0, 0.0];
    for r in delivered.iter().filter(|r| r.station == 1) {
        let j = sim::joystick(1, r.seq);
        let v = [
            clip(joystick_raw(j[0]), &unit),
            clip(joystick_raw(j[1]), &unit),
        ];
        if v != last {
            want.push(Seen::Analog("Wand0", v, time_of(r)));
            last = v;
        }
    }
    assert_eq!(analog, want);
    // Per record: button changes, then the joystick, then the pose (as C++ orders them).
    let mut wand_record_ends = 0;
    for w in seen.windows(2) {
        if let [Seen::Analog(..), next] = w {
            assert!(matches!(next, Seen::Pose(p) if p.sensor == 0), "{next:?}");
            wand_record_ends += 1;
        }
        if let [Seen::Button("Wand0", ..), next] = w {
            assert!(matches!(next, Seen::Button("Wand0", ..) | Seen::Analog(..)));
        }
    }
    assert_eq!(wand_record_ends, analog.len());
}

#[test]
fn fastrak_stylus_switches_to_the_fastrak_button_format() {
    let text = "vrpn_Tracker_Fastrak Tracker0 /dev/ttyS0 115200 /\nFTStylus Stylus0 1\n";
    let mut rig = rig(text, &["Stylus0"], SimConfig::new(115_200), 13);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(1));
    let d = &rig.line.device;
    assert_eq!(d.output_list(1), [2, 11, 0]);
    assert_eq!(d.output_list(2), [2, 11, 16, 0]);
    let e = d.commands.iter().position(|c| c == "e1,0").unwrap();
    let o4 = d.commands.iter().position(|c| c == "O4,2,11,0").unwrap();
    let x = d.commands.iter().position(|c| c.starts_with('x')).unwrap();
    assert!(o4 < e && e < x, "e1,0 follows the output lists");
    let n = assert_exact_stream(&rig);
    let log = rig.binary_log();
    let changes: Vec<Seen> = rig
        .seen
        .borrow()
        .iter()
        .filter(|s| matches!(s, Seen::Button(..)))
        .cloned()
        .collect();
    let want = expected_changes(
        "Stylus0",
        &log[..n],
        2,
        1,
        |s| u8::from(sim::stylus(2, s)),
        |r| rig.arrival(r),
    );
    assert_eq!(changes, want);
    assert!(changes.len() > 10);
}

#[test]
fn status_letters_and_a_54_byte_status_are_accepted() {
    let mut sim = SimConfig::new(57_600);
    sim.status_len = 54;
    sim.status_byte = b'B';
    sim.stations = 1;
    let mut rig = rig("vrpn_Tracker_Fastrak F /dev/ttyS0 57600\n", &[], sim, 14);
    rig.start_up();
    rig.line.run_for(Duration::from_millis(500));
    assert!(assert_exact_stream(&rig) > 20);
    assert!(!rig.has_text(TextSeverity::Normal, "characters for status"));
}

#[test]
fn intersense_entry_runs_eight_stations_over_the_fastrak_protocol() {
    let text = "vrpn_Tracker_InterSense IS0 COM1 IS900time ResetAtStartup /\n\
                Wand Wand6 6 -1.0 -0.1 0.1 1.0 -0.5 0.0 0.0 0.5\n";
    let cfg: config::InterSense = parse_one(text);
    let mut sim = SimConfig::new(115_200);
    sim.stations = 8;
    sim.cycle = Duration::from_millis(30);
    let mut rig = rig_with(
        |conn| {
            let p = FastrakProtocol::from_intersense(&cfg, "/dev/ttyUSB3", 115_200, conn);
            Lifecycle::new(&cfg.name, p.unwrap(), conn)
        },
        &["Wand6"],
        sim,
        15,
    );
    assert_eq!(rig.line.driver.protocol().port(), "/dev/ttyUSB3");
    assert_eq!(rig.line.driver.protocol().tracker().num_sensors(), 8);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(1));
    assert_eq!(rig.line.device.output_list(7), [2, 11, 21, 22, 23, 0]);
    assert_eq!(rig.line.device.output_list(8), [2, 11, 21, 0]);
    let zero = rig.line.driver.protocol().clock_zero().unwrap();
    let log = rig.binary_log();
    let poses = rig.poses();
    assert!(poses.len() > 200);
    for (p, r) in poses.iter().zip(&log) {
        let t = TimeVal::from_micros(zero.as_micros() + is900_offset(r.device_ms).as_micros());
        assert_eq!(actual(p), expected_pose(r, t));
    }
    let sensors: std::collections::BTreeSet<i32> = poses.iter().map(|p| p.sensor as i32).collect();
    assert_eq!(sensors.len(), 8);
    let clips = [
        WandClip {
            min: -1.0,
            low_zero: -0.1,
            high_zero: 0.1,
            max: 1.0,
        },
        WandClip {
            min: -0.5,
            low_zero: 0.0,
            high_zero: 0.0,
            max: 0.5,
        },
    ];
    let last_wand = log[..poses.len()].iter().rfind(|r| r.station == 7).unwrap();
    let j = sim::joystick(7, last_wand.seq);
    let want = [
        clip(joystick_raw(j[0]), &clips[0]),
        clip(joystick_raw(j[1]), &clips[1]),
    ];
    let got = rig
        .seen
        .borrow()
        .iter()
        .rev()
        .find_map(|s| match s {
            Seen::Analog("Wand6", v, _) => Some(*v),
            _ => None,
        })
        .unwrap();
    assert_eq!(got, want);
}

#[test]
fn station_devices_must_be_on_existing_stations() {
    let cfg = config::Fastrak {
        name: "F".into(),
        port: "/dev/null".into(),
        baud: 9600,
        is900_timestamps: false,
        reset_commands: vec![],
        stations: vec![config::StationDevice::Stylus {
            name: "S".into(),
            sensor: 4,
        }],
    };
    let conn = Connection::new_loopback();
    assert!(FastrakProtocol::new(&cfg, &conn).is_err());
}

#[test]
fn in_process_delivery_needs_no_mainloop() {
    // The rig relies on reports reaching the remotes inside the driver's calls.
    let mut rig = rig(PLAIN, &[], SimConfig::new(19200), 16);
    rig.start_up();
    let n = rig.pose_count();
    rig.line.run_for(Duration::from_millis(200));
    assert!(rig.pose_count() > n);
    rig.conn.mainloop().unwrap();
}

#[test]
fn reset_commands_then_station_devices_with_is900_time() {
    // `IS900time\` is both the option and the start of the reset commands; the last reset
    // line ends in `/` to start the station devices.
    let text = "vrpn_Tracker_Fastrak Isense900 /dev/ttyS0 115200 IS900time\\\n\
                MCc/\n\
                Stylus Pen 3\n";
    let cfg = fastrak_cfg(text);
    assert!(cfg.is900_timestamps);
    let mut rig = rig(text, &["Pen"], SimConfig::new(115_200), 17);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(1));
    let d = &rig.line.device;
    assert!(d.commands.iter().any(|c| c == "MCc"));
    assert_eq!(d.output_list(4), [2, 11, 21, 22, 0]);
    let zero = rig.line.driver.protocol().clock_zero().unwrap();
    let time_of = |r: &SentRecord| {
        TimeVal::from_micros(zero.as_micros() + is900_offset(r.device_ms).as_micros())
    };
    let poses = rig.poses();
    let log = rig.binary_log();
    for (p, r) in poses.iter().zip(&log) {
        assert_eq!(actual(p), expected_pose(r, time_of(r)));
    }
    let changes: Vec<Seen> = rig
        .seen
        .borrow()
        .iter()
        .filter(|s| matches!(s, Seen::Button(..)))
        .cloned()
        .collect();
    let want = expected_changes(
        "Pen",
        &log[..poses.len()],
        4,
        2,
        |s| sim::buttons(4, s),
        time_of,
    );
    assert_eq!(changes, want);
    assert!(!changes.is_empty());
}

#[test]
fn a_wand_beside_a_fastrak_stylus_uses_the_stylus_button_format() {
    // As in C++, one FTStylus line switches every station's buttons to the Fastrak format.
    let text = "vrpn_Tracker_Fastrak T /dev/ttyS0 115200 /\n\
                Wand W 0 -1 0 0 1 -1 0 0 1 /\n\
                FTStylus S 1\n";
    let mut rig = rig(text, &["W", "S"], SimConfig::new(115_200), 18);
    rig.start_up();
    rig.line.run_for(Duration::from_secs(1));
    assert_eq!(rig.line.device.output_list(1), [2, 11, 16, 23, 0]);
    assert_eq!(rig.line.device.output_list(2), [2, 11, 16, 0]);
    let n = assert_exact_stream(&rig);
    let log = rig.binary_log();
    let wand: Vec<Seen> = rig
        .seen
        .borrow()
        .iter()
        .filter(|s| matches!(s, Seen::Button("W", ..)))
        .cloned()
        .collect();
    let want = expected_changes(
        "W",
        &log[..n],
        1,
        1,
        |s| u8::from(sim::stylus(1, s)),
        |r| rig.arrival(r),
    );
    assert_eq!(wand, want);
    assert!(!wand.is_empty());
    assert!(rig
        .seen
        .borrow()
        .iter()
        .any(|s| matches!(s, Seen::Analog("W", ..))));
}

#[test]
fn is900_times_that_are_not_times_are_counted_and_stamped_with_the_arrival() {
    let mut sim = SimConfig::new(115_200);
    sim.stations = 2;
    let mut rig = rig(
        "vrpn_Tracker_Fastrak T /dev/ttyS1 115200 IS900time\n",
        &[],
        sim,
        21,
    );
    rig.start_up();
    rig.line.run_for(Duration::from_millis(200));
    let zero = rig.line.driver.protocol().clock_zero().unwrap();
    let hostile = [
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        3.4e38,
        -3.4e38,
        -5.0,
        super::super::MAX_DEVICE_MS * 2.0,
    ];
    rig.line.device.hostile_times.extend(hostile);
    rig.line.run_for(Duration::from_millis(500));
    let log = rig.binary_log();
    let poses = rig.poses();
    assert!(poses.len() > 60);
    let mut bad = 0;
    for (p, r) in poses.iter().zip(&log) {
        let ms = r.device_ms;
        let want = if ms.is_finite() && (0.0..=super::super::MAX_DEVICE_MS).contains(&ms) {
            TimeVal::from_micros(zero.as_micros() + is900_offset(ms).as_micros())
        } else {
            bad += 1;
            rig.arrival(r)
        };
        assert_eq!(actual(p), expected_pose(r, want), "device time {ms}");
    }
    assert_eq!(bad, hostile.len(), "every hostile time was delivered");
    assert_eq!(rig.line.driver.protocol().bad_times(), hostile.len() as u64);
    assert!(rig.has_text(TextSeverity::Warning, "is not a time since the reset"));
    // The stream goes on: no reset, no lost record.
    assert_eq!(rig.line.driver.stats().resets, 1);
}
