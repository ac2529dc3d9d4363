//! Layered devices report without allocating: each of vrpn_Tracker_FilterOneEuro,
//! vrpn_Tracker_DeadReckoning_Rotation (over a tracker), vrpn_Tracker_GameTrak,
//! vrpn_Button_5DT_Server, vrpn_JoyFly, vrpn_IMU_Magnetometer and vrpn_IMU_SimpleCombiner
//! (over an analog) reads a source of the same server (`*Src`) and of another server
//! (`Src@127.0.0.1:PORT`), fed 300 changing reports, a client's remote listening over TCP to
//! what it sends; and vrpn_Poser_Analog, driving an Analog_Output of the same server
//! (`*Stage`) and of another (`Stage@127.0.0.1:PORT`) from a client's pose requests. A
//! counting global allocator covers every pass of the servers, the device and the client
//! once each has sent and heard its first reports.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
#[path = "common/layered_rig.rs"]
mod layered_rig;

use std::cell::Cell;
use std::rc::Rc;

use counting_alloc::{count, counter_works};
use layered_rig::Layered;
use vrpn::config::DeviceRef;
use vrpn::devices::analog_output::AnalogOutputServer;
use vrpn::devices::poser::PoserRemote;
use vrpn::drivers::button_5dt_server::{Button5dtDevice, Button5dtServer};
use vrpn::drivers::dead_reckoning::{DeadReckoning, DeadReckoningDevice};
use vrpn::drivers::gametrak::{GameTrak, GameTrakDevice};
use vrpn::drivers::imu_magnetometer::{Magnetometer, MagnetometerDevice};
use vrpn::drivers::imu_simple_combiner::{CombinerDevice, SimpleCombiner};
use vrpn::drivers::joyfly::{JoyFly, JoyFlyDevice, JoyFlyFile};
use vrpn::drivers::one_euro::filter::Params;
use vrpn::drivers::one_euro::{FilterOneEuro, OneEuroDevice};
use vrpn::drivers::poser_analog::{Axis, PoserAnalog, PoserAnalogDevice};
use vrpn::layered::imu::AxisParams;
use vrpn::ServerDevice;
use vrpn::{
    AnalogRemote, AnalogServer, ButtonRemote, Connection, TimeVal, TrackerRemote, TrackerServer,
};

/// What feeds the layered device.
enum Upstream {
    Analog(Box<AnalogServer>),
    Tracker(TrackerServer),
}

impl Upstream {
    /// Report `k`: every channel, position and rotation changes; channels cross 0 every
    /// report (the 5DT buttons' thresholds) and stay within ±0.5 (JoyFly's range), but for
    /// channel 11, an accelerometer's near gravity.
    fn send(&mut self, k: u32) {
        let f = f64::from(k % 97);
        let time = TimeVal::from_micros(1_700_000_000_000_000 + i64::from(k) * 10_000);
        match self {
            Upstream::Analog(a) => {
                for (i, c) in a.channels_mut().iter_mut().enumerate() {
                    let base = if (k + i as u32) % 2 == 0 { -0.3 } else { 0.3 };
                    *c = base + 0.001 * f;
                }
                a.channels_mut()[11] = -9.7 - 0.001 * f;
                a.report(Some(time)).unwrap();
            }
            Upstream::Tracker(t) => {
                let half = 0.01 * f;
                let q = [half.sin(), 0.0, 0.0, half.cos()];
                t.report_pose(0, time, [0.01 * f, 0.2, -0.1], q).unwrap();
                let v = [0.0, (0.001 * f).sin(), 0.0, (0.001 * f).cos()];
                t.report_velocity(0, time, [0.1, 0.0, 0.0], v, 0.01)
                    .unwrap();
            }
        }
    }
}

/// What the client listens to.
#[derive(Clone, Copy)]
enum Output {
    Tracker,
    Analog,
    Button,
}

/// A remote of the right kind on `client` counting what it hears; returned to stay alive.
fn listen(output: Output, client: &Connection, heard: &Rc<Cell<u64>>) -> Box<dyn std::any::Any> {
    let h = heard.clone();
    let bump = move || h.set(h.get() + 1);
    match output {
        Output::Tracker => {
            let r = TrackerRemote::on_connection("Out", client).unwrap();
            r.on_pose(move |_| bump());
            Box::new(r)
        }
        Output::Analog => {
            let r = AnalogRemote::on_connection("Out", client).unwrap();
            r.on_report(move |_| bump());
            Box::new(r)
        }
        Output::Button => {
            let r = ButtonRemote::on_connection("Out", client).unwrap();
            r.on_change(move |_| bump());
            Box::new(r)
        }
    }
}

/// Streams 300 reports of `Src` through the device `build` makes (named `Out`, reading
/// `source`) and checks that no pass allocates and that the client heard at least `least`
/// reports meanwhile.
fn stream(
    local: bool,
    tracker_source: bool,
    output: Output,
    least: u64,
    build: impl FnOnce(DeviceRef, &Connection) -> Box<dyn ServerDevice>,
) {
    let rig = Layered::new(local);
    let mut upstream = if tracker_source {
        Upstream::Tracker(TrackerServer::new("Src", &rig.upstream, 1).unwrap())
    } else {
        Upstream::Analog(Box::new(
            AnalogServer::new("Src", &rig.upstream, 16).unwrap(),
        ))
    };
    let mut device = build(rig.source("Src"), &rig.server);
    let client = rig.client();
    let heard = Rc::new(Cell::new(0u64));
    let _remote = listen(output, &client, &heard);

    let mut k = 0u32;
    let mut send = || {
        k += 1;
        upstream.send(k);
    };
    let device = &mut *device;
    rig.warm_up(
        device,
        &client,
        &mut send,
        || heard.get() >= 20,
        "nothing heard",
    );
    let before = heard.get();
    rig.stream(device, &client, 300, &mut send, || {
        heard.get() >= before + least
    });
    assert!(
        heard.get() >= before + least,
        "heard {before} → {}",
        heard.get()
    );
    assert_eq!(count(), 0, "allocations while streaming");
    counter_works();
}

/// vrpn_Poser_Analog: 300 pose requests from a client, each driving three channels of the
/// Analog_Output `Stage` and answered with a tracker report.
fn poser(local: bool) {
    let rig = Layered::new(local);
    let stage = AnalogOutputServer::new("Stage", &rig.upstream, 3).unwrap();
    let requests = Rc::new(Cell::new(0u64));
    let r = requests.clone();
    stage.on_request(move |_| r.set(r.get() + 1));
    let target = rig.source("Stage");
    let axis = |i: u32| Axis {
        device: (i < 3).then(|| target.clone()),
        channel: (i < 3).then_some(i),
        offset: 0.0,
        scale: 2.0,
        min: -10.0,
        max: 10.0,
    };
    let cfg = PoserAnalog {
        name: "Out".into(),
        tracker_reports: true,
        axes: (0..6).map(axis).collect(),
    };
    let mut device = PoserAnalogDevice::new(&cfg, &rig.server).unwrap();
    let client = rig.client();
    let poser = PoserRemote::on_connection("Out", &client).unwrap();
    let heard = Rc::new(Cell::new(0u64));
    let _remote = listen(Output::Tracker, &client, &heard);
    let mut k = 0u32;
    let mut send = || {
        k += 1;
        let f = f64::from(k % 97);
        let half = 0.01 * f;
        let time = TimeVal::from_micros(1_700_000_000_000_000 + i64::from(k) * 10_000);
        // Refused (not connected) until the client's connection is up.
        let _ = poser.request_pose(
            time,
            [0.01 * f, -0.02 * f, 0.5],
            [0.0, half.sin(), 0.0, half.cos()],
        );
    };
    rig.warm_up(
        &mut device,
        &client,
        &mut send,
        || heard.get() >= 20 && requests.get() >= 60,
        "nothing heard",
    );
    let (poses, changes) = (heard.get(), requests.get());
    rig.stream(&mut device, &client, 300, &mut send, || {
        heard.get() >= poses + 250 && requests.get() >= changes + 750
    });
    assert!(
        heard.get() >= poses + 250,
        "poses {poses} → {}",
        heard.get()
    );
    assert!(
        requests.get() >= changes + 750,
        "channel changes {changes} → {}",
        requests.get()
    );
    assert_eq!(count(), 0, "allocations while streaming");
    counter_works();
}

#[test]
fn poser_analog_drives_without_allocating() {
    poser(true);
    poser(false);
}

fn one_euro(local: bool) {
    stream(local, true, Output::Tracker, 250, |source, conn| {
        let p = Params {
            min_cutoff: 1.0,
            beta: 0.5,
            derivative_cutoff: 1.0,
        };
        let cfg = FilterOneEuro {
            name: "Out".into(),
            source,
            sensors: 1,
            position: p,
            orientation: p,
        };
        Box::new(OneEuroDevice::new(&cfg, conn).unwrap())
    });
}

fn dead_reckoning(local: bool) {
    stream(local, true, Output::Tracker, 250, |source, conn| {
        let cfg = DeadReckoning {
            name: "Out".into(),
            source,
            sensors: 1,
            prediction: 0.05,
        };
        Box::new(DeadReckoningDevice::new(&cfg, conn).unwrap())
    });
}

fn gametrak(local: bool) {
    stream(local, false, Output::Tracker, 250, |source, conn| {
        let cfg = GameTrak {
            name: "Out".into(),
            source,
            mapping: [0, 1, 2, 3, 4, 5],
        };
        Box::new(GameTrakDevice::new(&cfg, conn).unwrap())
    });
}

fn button_5dt(local: bool) {
    stream(local, false, Output::Button, 250, |source, conn| {
        let cfg = Button5dtServer {
            name: "Out".into(),
            source,
            thresholds: [0.0; 16],
        };
        Box::new(Button5dtDevice::new(&cfg, conn).unwrap())
    });
}

fn joyfly(local: bool) {
    stream(local, false, Output::Tracker, 250, |source, conn| {
        let cfg = JoyFly {
            name: "Out".into(),
            source,
            file_name: "joyfly.cfg".into(),
            file: Some(JoyFlyFile::default()),
        };
        Box::new(JoyFlyDevice::new(&cfg, conn).unwrap())
    });
}

fn axes(source: &DeviceRef, first: u32) -> AxisParams {
    AxisParams {
        source: source.clone(),
        channels: [first, first + 1, first + 2],
        offsets: [0.0; 3],
        scales: [1.0; 3],
    }
}

fn magnetometer(local: bool) {
    // Reports at its rate (1000 a second), whatever the input.
    stream(local, false, Output::Analog, 100, |source, conn| {
        let cfg = Magnetometer {
            name: "Out".into(),
            update_rate: 1000.0,
            axes: axes(&source, 0),
        };
        Box::new(MagnetometerDevice::new(&cfg, conn).unwrap())
    });
}

fn simple_combiner(local: bool) {
    stream(local, false, Output::Tracker, 100, |source, conn| {
        let cfg = SimpleCombiner {
            name: "Out".into(),
            update_rate: 1000.0,
            accel: axes(&source, 10),
            rotation: axes(&source, 13),
            magnetometer: Some(source.clone()),
        };
        Box::new(CombinerDevice::new(&cfg, conn).unwrap())
    });
}

#[test]
fn one_euro_reports_without_allocating() {
    one_euro(true);
    one_euro(false);
}

#[test]
fn dead_reckoning_reports_without_allocating() {
    dead_reckoning(true);
    dead_reckoning(false);
}

#[test]
fn gametrak_reports_without_allocating() {
    gametrak(true);
    gametrak(false);
}

#[test]
fn button_5dt_server_reports_without_allocating() {
    button_5dt(true);
    button_5dt(false);
}

#[test]
fn joyfly_reports_without_allocating() {
    joyfly(true);
    joyfly(false);
}

#[test]
fn imu_magnetometer_reports_without_allocating() {
    magnetometer(true);
    magnetometer(false);
}

#[test]
fn imu_simple_combiner_reports_without_allocating() {
    simple_combiner(true);
    simple_combiner(false);
}
