//! Float seconds at the edges: tiny rates, huge periods, times beyond any clock. None of them
//! may panic; configuration files get an error naming the line, the library saturates or
//! refuses as documented in `vrpn::time`.

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use vrpn::devices::ServerDevice;
use vrpn::{Connection, Now};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// Runs `vrpn_server -f CONFIG 0` on `config`; returns its exit code and stderr, or `None`
/// when it was still running after 5 s (then it is killed).
fn server_on(config: &str) -> (Option<i32>, String) {
    let dir = std::env::temp_dir().join(format!("vrpn-extreme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{:x}.cfg", fxhash(config)));
    std::fs::File::create(&path)
        .unwrap()
        .write_all(config.as_bytes())
        .unwrap();
    let mut child = Command::new(SERVER)
        .args(["-f", path.to_str().unwrap(), "0"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > Duration::from_secs(5) {
            child.kill().unwrap();
            child.wait().unwrap();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    let _ = std::fs::remove_file(&path);
    (code, err)
}

fn fxhash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

#[test]
fn tiny_rates_and_huge_periods_are_config_errors_naming_the_line() {
    // (configuration, line of the bad entry, field named)
    let cases: [(&str, usize, &str); 9] = [
        ("vrpn_Tracker_NULL T 1 1e-20\n", 1, "rate"),
        ("vrpn_Tracker_Spin S 1 5e-20 0 0 1 0.5\n", 1, "rate"),
        ("vrpn_Button_Example B 2 1e-20\n", 1, "rate"),
        ("vrpn_Analog_Example A 2 1e-20\n", 1, "rate"),
        ("vrpn_Dial_Example D 2 1.0 1e-20\n", 1, "update_rate"),
        ("vrpn_Text_Example X 1e30 hello\n", 1, "period_seconds"),
        ("vrpn_Tracker_NULL T 1 1e-45\n", 1, "rate"),
        (
            "vrpn_Analog_Example A 2 10\nvrpn_Tracker_AnalogFly F 1e-20 absolute\nX *A 0 0 0 1 1\n\n",
            2,
            "update_rate",
        ),
        (
            "vrpn_Button_Example B 2 10\nvrpn_Tracker_ButtonFly F 1e-20\nabsolute *B 0 0 0 0 0 0 0\nend\n",
            2,
            "update_rate",
        ),
    ];
    for (config, keyword_line, field) in cases {
        let (code, err) = server_on(config);
        assert_eq!(code, Some(1), "{config:?}: {err}");
        assert!(!err.contains("panicked"), "{config:?}: {err}");
        assert!(
            err.contains(&format!(".cfg:{keyword_line}: ")) && err.contains(field),
            "{config:?}: the error names the line and the field: {err}"
        );
    }
}

/// The library's own constructors take any float: a rate below one per `MAX_PERIOD` or a
/// period beyond it means "never", with no panic in construction or scheduling.
#[test]
fn the_library_schedules_any_float_without_panicking() {
    let conn = Connection::new_loopback();
    let now = Now::read();
    let mut devices: Vec<Box<dyn ServerDevice>> = Vec::new();
    for (i, rate) in [1e-20, 5e-20, 1e-300, f64::MIN_POSITIVE, -1.0, f64::NAN]
        .into_iter()
        .enumerate()
    {
        devices.push(Box::new(
            vrpn::devices::tracker::TrackerNull::new(&format!("T{i}"), &conn, 1, rate).unwrap(),
        ));
        devices.push(Box::new(
            vrpn::devices::button::ButtonExample::new(&format!("B{i}"), &conn, 1, rate).unwrap(),
        ));
        devices.push(Box::new(
            vrpn::devices::analog::AnalogExample::new(&format!("A{i}"), &conn, 1, rate).unwrap(),
        ));
        devices.push(Box::new(
            vrpn::devices::dial::DialExample::new(&format!("D{i}"), &conn, 1, 1.0, rate).unwrap(),
        ));
    }
    for (i, period) in [1e30, 1e10, f64::INFINITY, f64::NAN, 0.0]
        .into_iter()
        .enumerate()
    {
        devices.push(Box::new(
            vrpn::devices::text_device::TextExample::new(&format!("X{i}"), &conn, period, "hi")
                .unwrap(),
        ));
    }
    for d in devices.iter_mut() {
        d.mainloop(now);
        d.mainloop(now.plus(Duration::from_secs(1)));
        assert_eq!(d.next_deadline(), None, "{} never reports", d.name());
    }
    // The fly trackers take their rate from a configuration built in code.
    let analog = vrpn::devices::analog::AnalogExample::new("FlyIn", &conn, 2, 10.0).unwrap();
    let mut fly_cfg = vrpn::server::config::parse_str(
        "vrpn_Tracker_AnalogFly F 10 absolute\nX *FlyIn 0 0 0 1 1\n\n",
        "inline.cfg",
    )
    .unwrap()[0]
        .spec::<vrpn::layered::config::AnalogFly>()
        .unwrap()
        .clone();
    fly_cfg.update_rate = 1e-30;
    let mut fly = vrpn::layered::TrackerAnalogFly::new(&fly_cfg, &conn).unwrap();
    let _ = &analog;
    fly.mainloop(now);
    fly.mainloop(now.plus(Duration::from_secs(1)));
    let _ = fly.next_deadline();
    let mut bfly_cfg = vrpn::server::config::parse_str(
        "vrpn_Tracker_ButtonFly G 10\nabsolute *FlyB 0 0 0 0 0 0 0\nend\n",
        "inline.cfg",
    )
    .unwrap()[0]
        .spec::<vrpn::layered::config::ButtonFly>()
        .unwrap()
        .clone();
    bfly_cfg.update_rate = 1e-30;
    let _buttons = vrpn::devices::button::ButtonExample::new("FlyB", &conn, 1, 10.0).unwrap();
    let mut bfly = vrpn::layered::TrackerButtonFly::new(&bfly_cfg, &conn).unwrap();
    bfly.mainloop(now);
    bfly.mainloop(now.plus(Duration::from_secs(1)));
    let _ = bfly.next_deadline();
}

fn golden(name: &str) -> String {
    format!(
        "{}/tests/fixtures/golden/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// A replay of a 3.4 s golden log with a pose counter.
fn replay() -> (
    Connection,
    vrpn::TrackerRemote,
    std::rc::Rc<std::cell::Cell<u32>>,
) {
    let conn = Connection::replay_file(&golden("tracker_udp_lob.out.vrpn")).unwrap();
    let tracker = vrpn::TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let n = std::rc::Rc::new(std::cell::Cell::new(0u32));
    let c = n.clone();
    tracker.on_pose(move |_| c.set(c.get() + 1));
    conn.replay().unwrap().set_rate(0.0);
    (conn, tracker, n)
}

#[test]
fn replay_positions_beyond_any_time_saturate() {
    let (conn, _tracker, n) = replay();
    let r = conn.replay().unwrap();
    let length = r.length_secs();
    let limit = vrpn::time::MAX_MICROS as f64 * 1e-6;
    for far in [1e14, 1e300, f64::INFINITY] {
        r.reset();
        assert!(
            !r.jump_to_time(far),
            "seek({far}) is past the end of the log"
        );
        let position = r.elapsed();
        assert!(
            position > length && position <= limit,
            "seek({far}): position {position}"
        );
        assert_eq!(n.get(), 0, "a seek delivers nothing");
    }
    // A NaN target is refused and moves nothing.
    r.reset();
    assert!(r.jump_to_time(1.0));
    assert!(!r.jump_to_time(f64::NAN));
    assert!((r.elapsed() - 1.0).abs() < 1e-6, "{}", r.elapsed());
    r.play_to_time(f64::NAN);
    assert_eq!(n.get(), 0);
    // A far play-to plays everything (the same as one just past the end).
    for far in [1e14, 1e300, f64::INFINITY] {
        r.reset();
        n.set(0);
        r.play_to_time(far);
        assert_eq!(n.get(), 410, "play_to({far})");
        assert!(r.eof());
    }
    // Far before the start: from the beginning.
    for early in [-1e14, -1e300, f64::NEG_INFINITY] {
        r.reset();
        n.set(0);
        assert!(r.jump_to_time(early), "seek({early})");
        r.play_to_time(length + 1.0);
        assert_eq!(n.get(), 410, "after seek({early})");
    }
}

#[test]
fn a_report_stamped_beyond_the_header_range_saturates_instead_of_wrapping() {
    let server = Connection::server(Some(std::net::Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let tracker = vrpn::TrackerServer::new("Tracker0", &server, 1).unwrap();
    let remote = vrpn::TrackerRemote::new(&format!("Tracker0@tcp://127.0.0.1:{port}")).unwrap();
    let times = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let t = times.clone();
    remote.on_pose(move |p| t.borrow_mut().push((p.sender_time.sec, p.sender_time.usec)));
    let start = Instant::now();
    while !remote.connection().connected() || server.connected_peers() == 0 {
        assert!(start.elapsed() < Duration::from_secs(10), "no connection");
        server.mainloop().unwrap();
        remote.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    let far = vrpn::TimeVal::from_secs_f64(1e300);
    assert_eq!(far, vrpn::TimeVal::MAX);
    for time in [
        far,
        vrpn::TimeVal::new(-5, 0),
        vrpn::TimeVal::new(1 << 32, 1),
    ] {
        tracker
            .report_pose(0, time, [0.0; 3], [0.0, 0.0, 0.0, 1.0])
            .unwrap();
    }
    while times.borrow().len() < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "{:?}",
            times.borrow()
        );
        server.mainloop().unwrap();
        remote.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    // The header's seconds are unsigned 32-bit: the nearest end of that range, never the low
    // 32 bits of the value (which for 2^62 µs would read as some day in 2005).
    assert_eq!(
        *times.borrow(),
        [
            (i64::from(u32::MAX), vrpn::TimeVal::MAX.usec),
            (0, 0),
            (i64::from(u32::MAX), 1)
        ]
    );
}
