//! vrpn_Tracker_FilterOneEuro end to end: a `vrpn_server` serving a DTrack tracker (fed by
//! the controller simulator) and a 1€ filter of it (`*DTrack`), a client reading both from
//! the filter's very first input; every filtered pose must be what an independent
//! implementation of VRPN's 1€ filter (written here with nalgebra, its spherical
//! interpolation included) computes from the source poses the client heard (positions; see
//! the comment on orientations below).

use std::cell::RefCell;
use std::net::{Ipv4Addr, SocketAddr};
use std::rc::Rc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use vrpn::drivers::dtrack::sim::{free_udp_port, Controller, Frame};
use vrpn::sim::rig::ServerProcess;
use vrpn::{TextReceiver, TimeVal, TrackerPose, TrackerRemote};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(10);

fn alpha(dt: f64, cutoff: f64) -> f64 {
    let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff);
    1.0 / (1.0 + tau / dt)
}

/// Spherical interpolation the shorter way round.
fn slerp(a: &Quaternion<f64>, b: &Quaternion<f64>, t: f64) -> Quaternion<f64> {
    let ua = UnitQuaternion::new_normalize(*a);
    let mut ub = UnitQuaternion::new_normalize(*b);
    if ua.coords.dot(&ub.coords) < 0.0 {
        ub = UnitQuaternion::new_unchecked(-ub.into_inner());
    }
    ua.try_slerp(&ub, t, 1e-9).unwrap_or(ub).into_inner()
}

/// VRPN's 1€ filter on positions and orientations, for one sensor.
struct Reference {
    pos: Option<(Vector3<f64>, Vector3<f64>)>,
    rot: Option<(Quaternion<f64>, Quaternion<f64>)>,
}

impl Reference {
    fn position(&mut self, dt: f64, x: Vector3<f64>) -> Vector3<f64> {
        let (min_cutoff, beta, d_cutoff) = (1.15, 1.0, 1.2);
        let (prev, dprev) = self.pos.unwrap_or((x, Vector3::zeros()));
        let d = if self.pos.is_some() {
            (x - prev) / dt
        } else {
            Vector3::zeros()
        };
        let a = alpha(dt, d_cutoff);
        let dxf = d * a + dprev * (1.0 - a);
        let a = alpha(dt, min_cutoff + beta * dxf.norm());
        let xf = x * a + prev * (1.0 - a);
        self.pos = Some((xf, dxf));
        xf
    }

    fn orientation(&mut self, dt: f64, q: Quaternion<f64>) -> Quaternion<f64> {
        let (min_cutoff, beta, d_cutoff) = (1.5, 5.0, 1.2);
        let identity = Quaternion::identity();
        let (prev, dprev) = self.rot.unwrap_or((q, identity));
        // VRPN's rate of turn: the step since the last output, its vector part scaled by
        // 1/dt and its scalar part moved accordingly, normalised.
        let d = if self.rot.is_some() {
            let step = q * prev.try_inverse().unwrap();
            let r = 1.0 / dt;
            Quaternion::new(step.w * r + (1.0 - r), step.i * r, step.j * r, step.k * r).normalize()
        } else {
            identity
        };
        let dqf = slerp(&dprev, &d, alpha(dt, d_cutoff));
        let speed = 2.0 * dqf.w.acos();
        let qf = slerp(&prev, &q, alpha(dt, min_cutoff + beta * speed));
        self.rot = Some((qf, dqf));
        qf
    }
}

fn wall() -> (u32, u32) {
    let d = SystemTime::now().duration_since(UNIX_EPOCH).unwrap();
    (d.as_secs() as u32, d.subsec_micros())
}

fn secs(later: TimeVal, earlier: TimeVal) -> f64 {
    (later.usec - earlier.usec) as f64 / 1e6 + (later.sec - earlier.sec) as f64
}

#[test]
fn filtered_poses_match_an_independent_filter() {
    let udp = free_udp_port().unwrap();
    let cfg = format!(
        "vrpn_Tracker_DTrack DTrack {udp} -\n\
         vrpn_Tracker_FilterOneEuro Filter0 *DTrack 3 1.15 1.0 1.2 1.5 5.0 1.2\n"
    );
    let server = ServerProcess::start(SERVER.as_ref(), &cfg).unwrap();
    let at = |name: &str| format!("{name}@tcp://127.0.0.1:{}", server.port());
    let heard: Rc<RefCell<Vec<(bool, TrackerPose)>>> = Rc::default();
    let source = TrackerRemote::new(&at("DTrack")).unwrap();
    let filtered = TrackerRemote::new(&at("Filter0")).unwrap();
    let texts = TextReceiver::new(&at("DTrack")).unwrap();
    let (h1, h2) = (heard.clone(), heard.clone());
    source.on_pose(move |p| h1.borrow_mut().push((false, *p)));
    filtered.on_pose(move |p| h2.borrow_mut().push((true, *p)));
    let talked = Rc::new(RefCell::new(false));
    let t = talked.clone();
    texts.on_message(move |_| *t.borrow_mut() = true);
    let pump = |d: Duration| {
        let start = Instant::now();
        while start.elapsed() < d {
            let _ = source.mainloop();
            let _ = filtered.mainloop();
            let _ = texts.mainloop();
            std::thread::sleep(Duration::from_millis(1));
        }
    };
    let ctl = Controller::new(SocketAddr::from((Ipv4Addr::LOCALHOST, udp))).unwrap();
    // Frames without targets (the tracing texts show the client is connected) first: the
    // filter's first input is then a pose the client hears.
    let start = Instant::now();
    let mut k = 1;
    while !*talked.borrow() {
        assert!(
            start.elapsed() < WAIT,
            "no text; server said {}",
            server.stderr()
        );
        ctl.send(format!("fr {k}\n6d 0\n").as_bytes()).unwrap();
        k += 1;
        pump(Duration::from_millis(5));
    }
    pump(Duration::from_millis(100));
    for _ in 0..100 {
        let (s, u) = wall();
        ctl.send(Frame::standard(k, s, u).text().as_bytes())
            .unwrap();
        k += 1;
        pump(Duration::from_millis(4));
    }
    let start = Instant::now();
    while heard.borrow().iter().filter(|(f, _)| *f).count() < 250 {
        assert!(start.elapsed() < WAIT, "filtered poses missing");
        pump(Duration::from_millis(5));
    }
    // Replay the source poses through the reference, sensor by sensor, in the order heard.
    let heard = heard.borrow();
    let sources: Vec<&TrackerPose> = heard.iter().filter(|(f, _)| !*f).map(|(_, p)| p).collect();
    let outputs: Vec<&TrackerPose> = heard.iter().filter(|(f, _)| *f).map(|(_, p)| p).collect();
    let mut reference: Vec<Reference> = (0..3)
        .map(|_| Reference {
            pos: None,
            rot: None,
        })
        .collect();
    let mut last = [TimeVal::ZERO; 3];
    let mut outputs = outputs.into_iter();
    let mut compared = 0;
    for s in sources.iter().filter(|s| s.sensor < 3) {
        let Some(f) = outputs.next() else { break };
        assert_eq!((f.sensor, f.sender_time), (s.sensor, s.sender_time));
        let i = s.sensor;
        // The server's own stamps: `time` is translated by the clock-synchronisation estimate,
        // which moves by microseconds from one message to the next.
        let mut dt = secs(s.sender_time, last[i]);
        if dt <= 0.0 {
            dt = 1.0;
        }
        last[i] = s.sender_time;
        let p = reference[i].position(dt, s.pos);
        // Orientations: this reference (nalgebra's interpolation) drifts from quatlib's within
        // a few hundred steps, so only their being unit quaternions is checked here; the
        // bit-exact check of orientations against C++ is the unit test on the captured C++
        // output (drivers/one_euro/tests.rs).
        let _ = reference[i].orientation(dt, s.quat.into_inner());
        assert!(
            (f.pos - p).norm() < 1e-9,
            "sensor {i}: {:?} vs {p:?}",
            f.pos
        );
        assert!((f.quat.into_inner().norm() - 1.0).abs() < 1e-12);
        compared += 1;
    }
    assert!(compared >= 250, "{compared}");
}
