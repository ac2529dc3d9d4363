//! vrpn_Tracker_DeadReckoning_Rotation end to end: a `vrpn_server` serving a spinning tracker
//! (which reports poses and angular velocities) and a predictor of it (`*Spin`), a client
//! reading both; every prediction must be what nalgebra computes independently (the source's
//! rotation per interval raised to the power prediction/interval, applied to the pose), and
//! every velocity is passed through unchanged.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::nalgebra::UnitQuaternion;
use vrpn::sim::rig::ServerProcess;
use vrpn::{TimeVal, TrackerPose, TrackerRemote, TrackerVelocity};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const WAIT: Duration = Duration::from_secs(20);

#[derive(Default)]
struct Heard {
    source_poses: Vec<TrackerPose>,
    source_velocities: Vec<TrackerVelocity>,
    predictions: Vec<TrackerPose>,
    passed_velocities: Vec<TrackerVelocity>,
}

#[test]
fn predictions_match_an_independent_computation() {
    let cfg = "vrpn_Tracker_Spin Spin 2 60.0 0.0 1.0 0.5 0.3\n\
               vrpn_Tracker_DeadReckoning_Rotation DR *Spin 2 0.5\n";
    let server = ServerProcess::start(SERVER.as_ref(), cfg).unwrap();
    let at = |name: &str| format!("{name}@tcp://127.0.0.1:{}", server.port());
    let heard: Rc<RefCell<Heard>> = Rc::default();
    let source = TrackerRemote::new(&at("Spin")).unwrap();
    let predictor = TrackerRemote::new(&at("DR")).unwrap();
    let h = heard.clone();
    source.on_pose(move |p| h.borrow_mut().source_poses.push(*p));
    let h = heard.clone();
    source.on_velocity(move |v| h.borrow_mut().source_velocities.push(*v));
    let h = heard.clone();
    predictor.on_pose(move |p| h.borrow_mut().predictions.push(*p));
    let h = heard.clone();
    predictor.on_velocity(move |v| h.borrow_mut().passed_velocities.push(*v));
    let start = Instant::now();
    while heard.borrow().predictions.len() < 200 {
        assert!(
            start.elapsed() < WAIT,
            "{} predictions; server said {}",
            heard.borrow().predictions.len(),
            server.stderr()
        );
        let _ = source.mainloop();
        let _ = predictor.mainloop();
        std::thread::sleep(Duration::from_millis(2));
    }
    let heard = heard.borrow();
    let velocity = heard.source_velocities[0];
    // The spinning tracker's rate is constant: one velocity for every prediction.
    assert!(heard
        .source_velocities
        .iter()
        .all(|v| v.vel_quat == velocity.vel_quat && v.vel_quat_dt == velocity.vel_quat_dt));
    let prediction = 0.5f32 as f64;
    let rate = velocity.vel_quat.powf(prediction / velocity.vel_quat_dt);
    let ahead = |t: TimeVal| {
        let usec = t.usec + 500_000;
        TimeVal {
            sec: t.sec + usec / 1_000_000,
            usec: usec % 1_000_000,
        }
    };
    let mut compared = 0;
    for p in &heard.predictions {
        // The pose it was predicted from: same sensor, 0.5 s earlier.
        let Some(s) = heard
            .source_poses
            .iter()
            .find(|s| s.sensor == p.sensor && ahead(s.sender_time) == p.sender_time)
        else {
            continue;
        };
        let want: UnitQuaternion<f64> = rate * s.quat;
        assert!(
            p.quat.angle_to(&want) < 1e-9,
            "sensor {}: {:?} vs {:?}",
            p.sensor,
            p.quat,
            want
        );
        assert_eq!(p.pos, s.pos);
        compared += 1;
    }
    assert!(compared >= 150, "{compared} of {}", heard.predictions.len());
    // Velocities pass through unchanged, same time stamp (the server's: `time` is translated
    // by the clock-synchronisation estimate, which moves from one message to the next).
    assert!(heard.passed_velocities.len() >= 50);
    for v in &heard.passed_velocities {
        let s = heard
            .source_velocities
            .iter()
            .find(|s| s.sensor == v.sensor && s.sender_time == v.sender_time)
            .expect("a velocity the source sent");
        assert_eq!(
            (v.vel, v.vel_quat, v.vel_quat_dt),
            (s.vel, s.vel_quat, s.vel_quat_dt)
        );
    }
}
