//! HID and evdev devices report without allocating: a server with a SpaceMouse, a game
//! controller (with C++'s 30 Hz repeat), an Oculus inertial unit (several samples per report),
//! the generic driver on a real descriptor and a `vrpn_DevInput` mouse, all on simulators
//! behind a fake device tree, streaming through a real socket to a client's remotes. A
//! counting global allocator covers every pass of the server and the client.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::Cell;
use std::io::Write;
use std::rc::Rc;
use std::time::{Duration, Instant};

use counting_alloc::{COUNT, ENABLED};
use vrpn::drivers::{gamepads, hid_generic, hmd, spacemouse};
use vrpn::hid::fake::FakeTree;
use vrpn::hid::DeviceHub;
use vrpn::net::Reactor;
use vrpn::ServerDevice;
use vrpn::{AnalogRemote, ButtonRemote, Connection, Limits, Now};

struct Loop {
    reactor: Reactor,
    server: Connection,
    client: Connection,
    devices: Vec<Box<dyn ServerDevice>>,
    /// Count allocations inside passes (the simulators between them allocate freely).
    counting: bool,
}

impl Loop {
    fn pass(&mut self) {
        ENABLED.with(|e| e.set(self.counting));
        self.pass_inner();
        ENABLED.with(|e| e.set(false));
    }

    fn pass_inner(&mut self) {
        let now = Now::read();
        for d in &mut self.devices {
            d.mainloop(now);
        }
        self.server.mainloop().unwrap();
        self.client.mainloop().unwrap();
        let deadline = self.devices.iter().filter_map(|d| d.next_deadline()).min();
        self.reactor
            .wait(deadline, Duration::from_millis(1))
            .unwrap();
    }

    fn until(&mut self, what: &str, mut done: impl FnMut() -> bool) {
        let start = Instant::now();
        while !done() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            self.pass();
        }
    }
}

#[test]
fn hid_and_evdev_devices_stream_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let fake = FakeTree::new();
    let reactor = Reactor::new().unwrap();
    let server = Connection::server_in(
        &reactor,
        Some(std::net::Ipv4Addr::LOCALHOST),
        0,
        Limits::default(),
    )
    .unwrap();
    let port = server.local_port().unwrap();
    let client =
        Connection::client_in(&reactor, "127.0.0.1", port, false, Limits::default()).unwrap();
    let hub = DeviceHub::new(fake.tree(), Some(&reactor));
    let nav = spacemouse::model("vrpn_3DConnexion_Navigator").unwrap();
    let xbox = gamepads::model("vrpn_Microsoft_Controller_Raw_Xbox_360").unwrap();
    let dk1 = hmd::model("vrpn_Oculus_DK1").unwrap();
    let mut devices: Vec<Box<dyn ServerDevice>> = vec![
        spacemouse::build(nav, "Nav", &server, &hub).unwrap(),
        gamepads::build(xbox, "Pad", None, &server, &hub).unwrap(),
        hmd::build(dk1, "Rift", &server, &hub).unwrap(),
        Box::new(vrpn::hid::HidDevice::new(
            hid_generic::GenericDriver::new(
                "Gen",
                vrpn::hid::HidMatch::product(0x046d, 0xc629),
                &server,
            )
            .unwrap(),
            &hub,
            &server,
        )),
    ];
    devices.push(vrpn::drivers::evdev::build(
        vrpn::drivers::evdev::EvdevDriver::dev_input(
            "Mouse",
            "Test Mouse",
            vrpn::drivers::evdev::DevInputKind::Relative,
            &server,
        )
        .unwrap(),
        &server,
        &hub,
    ));
    let mut l = Loop {
        reactor,
        server,
        client,
        devices,
        counting: false,
    };
    // Remotes counting what arrives (their callbacks allocate nothing).
    let counts: Vec<Rc<Cell<u64>>> = (0..6).map(|_| Rc::default()).collect();
    let mut keep = Vec::new();
    for (i, name) in ["Nav", "Pad", "Rift", "Gen", "Mouse"]
        .into_iter()
        .enumerate()
    {
        let ar = AnalogRemote::on_connection(name, &l.client).unwrap();
        let c = counts[i].clone();
        ar.on_report(move |_| c.set(c.get() + 1));
        keep.push(ar);
    }
    let br = ButtonRemote::on_connection("Nav", &l.client).unwrap();
    let c = counts[5].clone();
    br.on_change(move |_| c.set(c.get() + 1));
    let client = l.client.clone();
    l.until("client connected", || client.connected());
    // Plug everything in.
    let plug = |n: u32, v: u16, p: u16, name: &str| {
        fake.add_hidraw(n, v, p, 0, name, "");
        fake.listen_hidraw(n).unwrap()
    };
    let nodes = [
        plug(1, nav.vendor, nav.product, "SpaceNavigator"),
        plug(2, xbox.vendor, xbox.product, "Xbox 360"),
        plug(3, dk1.vendor, dk1.product, "Rift DK1"),
        plug(4, 0x046d, 0xc629, "SpacePilot Pro"),
    ];
    fake.set_report_descriptor(4, &hid_generic::sim::spacenavigator());
    fake.add_input(5, "Test Mouse", 1, 2, "7", "70000 0 0 0 0", "103", "");
    let fifo = fake.fifo_input(5).unwrap();
    l.pass();
    for n in 1..=4 {
        fake.uevent("add", "hidraw", &format!("hidraw{n}")).unwrap();
    }
    fake.uevent("add", "input", "input/event5").unwrap();
    let mut ends = Vec::new();
    for node in &nodes {
        let mut end = None;
        l.until("device opened", || {
            end = node.accept().unwrap();
            end.is_some()
        });
        ends.push(end.unwrap());
    }
    let mut mouse = None;
    l.until("event node opened", || {
        use std::os::unix::fs::OpenOptionsExt;
        mouse = std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(nix::libc::O_NONBLOCK)
            .open(&fifo)
            .ok();
        mouse.is_some()
    });
    let mut mouse = mouse.unwrap();
    // One round of reports from every device, values changing each time.
    let mut round = |l: &mut Loop, k: i16| {
        ends[0]
            .send_report(&spacemouse::sim::translation(k, -k, 3))
            .unwrap();
        ends[0]
            .send_report(&spacemouse::sim::buttons(nav, (k & 3) as u32))
            .unwrap();
        ends[1]
            .send_report(&gamepads::sim::xbox_360(
                [0x8000 + 300 * k as u16; 2],
                [0x8000; 2],
                0x80,
                0,
                0,
                0,
            ))
            .unwrap();
        ends[2]
            .send_report(&hmd::sim::type_1(
                k as u16,
                2500,
                &[
                    ([k.into(), 2, 3], [4, 5, 6]),
                    ([k.into(), 3, 3], [4, 5, 6]),
                    ([k.into(), 4, 3], [4, 5, 6]),
                ],
                [1, 2, 3],
                62,
            ))
            .unwrap();
        let mut r = vec![1u8];
        r.extend_from_slice(&k.to_le_bytes());
        r.extend_from_slice(&[0; 4]);
        ends[3].send_report(&r).unwrap();
        let ev = |kind, code, value| {
            vrpn::hid::input_event::InputEvent { kind, code, value }.encode(0, 0)
        };
        let mut m = Vec::new();
        m.extend_from_slice(&ev(2, 0, k.into()));
        m.extend_from_slice(&ev(0, 0, 0));
        mouse.write_all(&m).unwrap();
        let before = counts[4].get();
        let mouse_count = counts[4].clone();
        l.until("a round arrives", || mouse_count.get() > before);
        for _ in 0..3 {
            l.pass();
        }
    };
    for k in 1..20 {
        round(&mut l, k);
    }
    let before: Vec<u64> = counts.iter().map(|c| c.get()).collect();
    COUNT.with(|c| c.set(0));
    l.counting = true;
    for k in 20..120 {
        round(&mut l, k);
    }
    l.counting = false;
    let allocations = COUNT.with(Cell::get);
    let got: Vec<u64> = counts
        .iter()
        .zip(&before)
        .map(|(c, b)| c.get() - b)
        .collect();
    // 100 rounds: the SpaceMouse's translation, the pad's sticks, three IMU samples each, the
    // generic axis, the mouse motion, the SpaceMouse's buttons.
    assert!(got[0] >= 100 && got[1] >= 100 && got[2] >= 300, "{got:?}");
    assert!(got[3] >= 100 && got[4] >= 100 && got[5] >= 50, "{got:?}");
    assert_eq!(allocations, 0, "allocations while streaming {got:?}");
    drop(keep);
}
