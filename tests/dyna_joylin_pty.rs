//! The joystick driver end to end: a simulator on a pseudo-terminal, a `vrpn_server` child
//! running the driver from its vrpn.cfg line, and a client over a real socket on 127.0.0.1.
//! Values are checked against the simulator's own log (over TCP only, so no datagram can be
//! lost on a busy machine); damage and an unplugged device are survived. (The DynaSight's
//! end-to-end test is `tests/driver_dyna.rs`.)

mod common;
#[path = "common/pty_sim.rs"]
mod pty_sim;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use pty_sim::Simulated;
use vrpn::drivers::joylin::event::Kind;
use vrpn::drivers::joylin::sim::{JoystickSim, SimConfig as JoySimConfig};
use vrpn::{AnalogRemote, ButtonRemote, Now, TextReceiver, TimeVal, TrackerPose, TrackerRemote};

/// Runs `pump` until `done` or `max`; returns whether `done` held.
fn pump_until(pump: &dyn Fn(), max: Duration, done: &dyn Fn() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < max {
        pump();
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    done()
}

/// Collects a device's text messages.
fn texts(device: &str) -> (TextReceiver, Rc<RefCell<Vec<String>>>) {
    let r = TextReceiver::new(device).unwrap();
    let t: Rc<RefCell<Vec<String>>> = Rc::default();
    let t2 = t.clone();
    r.on_message(move |m| t2.borrow_mut().push(m.text().to_string()));
    (r, t)
}

/// Index of `got` as a contiguous run inside `sent`, if it is one.
fn run_in<T: PartialEq>(got: &[T], sent: &[T]) -> Option<usize> {
    (0..=sent.len().checked_sub(got.len())?).find(|&i| sent[i..i + got.len()] == *got)
}

/// What a client must receive for the live events logged: the channels after each axis event
/// and each button change, from the simulator's log alone.
fn joystick_reference(sim: &JoystickSim, axes: usize) -> (Vec<Vec<f64>>, Vec<(i32, i32)>) {
    let mut chan = vec![0.0; axes];
    let mut pressed = vec![0; 256];
    let (mut a, mut c) = (Vec::new(), Vec::new());
    for e in sim.sent() {
        let (n, v) = (usize::from(e.event.number), e.event.value);
        match e.event.kind {
            Kind::Axis => chan[n] = f64::from(v) / 32767.0,
            Kind::Button if pressed[n] != i32::from(v) => {
                pressed[n] = i32::from(v);
                if !e.event.init {
                    c.push((n as i32, pressed[n]));
                }
            }
            Kind::Button => {}
        }
        if !e.event.init && e.event.kind == Kind::Axis {
            a.push(chan.clone());
        }
    }
    (a, c)
}

#[test]
fn joystick_through_vrpn_server_to_a_client_and_analogfly() {
    let mut cfg = JoySimConfig::new(6, 10);
    cfg.keep_log = true;
    let mut model = JoystickSim::new(cfg);
    model.running = false;
    model.set_axis(0, 16_383);
    model.set_axis(1, -8_191);
    let sim = Simulated::start(model, "joylin");
    let t0 = Now::read();
    let server = common::start_server(
        &format!(
            "vrpn_Joylin Joy0 {}\n\
             vrpn_Tracker_AnalogFly Flyer0 60.0 absolute\n\
             X *Joy0 0 0.0 0.0 1.0 1.0\n\
             Y *Joy0 1 0.0 0.0 2.0 1.0\n\
             Z NULL 0 0.0 0.0 1.0 1.0\n\
             RX NULL 0 0.0 0.0 1.0 1.0\n\
             RY NULL 0 0.0 0.0 1.0 1.0\n\
             RZ NULL 0 0.0 0.0 1.0 1.0\n\
             RESET NULL 0\n\
             CLUTCH NULL 0\n\
             \n",
            sim.path.display()
        ),
        0,
    );
    let at = format!("Joy0@tcp://127.0.0.1:{}", server.port);
    let analog = AnalogRemote::new(&at).unwrap();
    let buttons = ButtonRemote::new(&at).unwrap();
    let flyer = TrackerRemote::new(&format!("Flyer0@tcp://127.0.0.1:{}", server.port)).unwrap();
    let (_texts_rx, texts) = texts(&at);
    type Channels = (TimeVal, Vec<f64>);
    let reports: Rc<RefCell<Vec<Channels>>> = Rc::default();
    let changes: Rc<RefCell<Vec<(i32, i32)>>> = Rc::default();
    let flights: Rc<RefCell<Vec<TrackerPose>>> = Rc::default();
    let (r, c, f) = (reports.clone(), changes.clone(), flights.clone());
    analog.on_report(move |m| {
        let n = m.num_channel;
        r.borrow_mut().push((m.time, m.channel[..n].to_vec()));
    });
    buttons.on_change(move |m| c.borrow_mut().push((m.button as i32, m.state.raw())));
    flyer.on_pose(move |p| f.borrow_mut().push(*p));
    let pump = || {
        analog.mainloop().unwrap();
        flyer.mainloop().unwrap();
    };
    let why = || format!("server said: {}", server.stderr.lock().unwrap());

    // AnalogFly flies the tracker from the joystick's initial state (absolute mode: x is
    // channel 0, y is twice channel 1).
    let want = [16_383.0 / 32767.0, 2.0 * -8_191.0 / 32767.0, 0.0];
    assert!(
        pump_until(&pump, Duration::from_secs(10), &|| {
            flights
                .borrow()
                .last()
                .is_some_and(|p| [p.pos.x, p.pos.y, p.pos.z] == want)
        }),
        "{:?}; {}",
        flights.borrow().last(),
        why()
    );
    assert_eq!(buttons.num_buttons(), 10);
    let flown = flights
        .borrow()
        .iter()
        .find(|p| p.pos.x != 0.0)
        .map(|p| p.time);
    let first = flown.unwrap().seconds_since(t0.wall);
    eprintln!(
        "Joylin: vrpn_server start to the first AnalogFly pose from the stick {:.0} ms",
        first * 1e3
    );

    // Live events: every axis move and button change arrives, in order.
    sim.lock().model.running = true;
    let enough = || reports.borrow().len() >= 150 && changes.borrow().len() >= 50;
    assert!(
        pump_until(&pump, Duration::from_secs(10), &enough),
        "{}",
        why()
    );
    {
        let d = sim.lock();
        let (want_a, want_c) = joystick_reference(&d.model, 6);
        let got: Vec<Vec<f64>> = reports.borrow().iter().map(|r| r.1.clone()).collect();
        // The first report (the initial state) came before any live event.
        let live = &got[1..];
        assert!(
            run_in(live, &want_a).is_some(),
            "analog reports out of order"
        );
        assert!(
            run_in(&changes.borrow(), &want_c).is_some(),
            "button changes"
        );
        // Stamped with the time the event reached the server: in order, and recent.
        let times: Vec<TimeVal> = reports.borrow().iter().map(|r| r.0).collect();
        assert!(times.windows(2).all(|w| w[0] <= w[1]));
        assert!(Now::read().wall.seconds_since(*times.last().unwrap()) < 1.0);
    }

    // Unplugged and plugged back: C++'s error text, then the device is reopened and events
    // flow again from its initial state.
    sim.lock().unplug();
    assert!(
        pump_until(&pump, Duration::from_secs(3), &|| {
            texts
                .borrow()
                .iter()
                .any(|t| t == "Error reading from joystick")
        }),
        "{:?}; {}",
        texts.borrow(),
        why()
    );
    {
        let mut d = sim.lock();
        d.plug().unwrap();
        d.model.plugged();
    }
    let n = reports.borrow().len();
    let more = || reports.borrow().len() >= n + 100;
    assert!(
        pump_until(&pump, Duration::from_secs(5), &more),
        "{}",
        why()
    );
    // AnalogFly follows: its latest pose is the latest channels.
    let last = reports.borrow().last().unwrap().1.clone();
    let follows = || {
        flights
            .borrow()
            .last()
            .is_some_and(|p| (p.pos.x - last[0]).abs() < 1.0)
    };
    assert!(pump_until(&pump, Duration::from_secs(2), &follows));
}
