//! An in-process rig for HID driver tests: a fake device tree, a server connection on a real
//! socket (127.0.0.1, an OS-chosen port) whose devices run on the tree's hub, and a client
//! connection to it. Simulators plug devices in (sysfs entry, node socket, uevent), the
//! server opens them, and the client's remotes receive what the drivers report.

use std::time::{Duration, Instant};

use super::fake::FakeTree;
use super::fake::{DeviceEnd, NodeListener};
use super::DeviceHub;
use crate::devices::ServerDevice;
use crate::net::Reactor;
use crate::time::Now;
use crate::{Connection, Limits};

/// See the module documentation.
pub(crate) struct Rig {
    pub fake: FakeTree,
    pub reactor: Reactor,
    pub server: Connection,
    pub hub: DeviceHub,
    pub devices: Vec<Box<dyn ServerDevice>>,
    pub client: Connection,
}

impl Rig {
    pub fn new() -> Rig {
        crate::devices::base::set_print_threshold(crate::TextSeverity::Other(u32::MAX));
        let fake = FakeTree::new();
        let reactor = Reactor::new().unwrap();
        let server = Connection::server_in(
            &reactor,
            Some(std::net::Ipv4Addr::LOCALHOST),
            0,
            Limits::default(),
        )
        .unwrap();
        let hub = DeviceHub::new(fake.tree(), Some(&reactor));
        let port = server.local_port().unwrap();
        let client =
            Connection::client_in(&reactor, "127.0.0.1", port, false, Limits::default()).unwrap();
        Rig {
            fake,
            reactor,
            server,
            hub,
            devices: Vec::new(),
            client,
        }
    }

    /// One loop pass: the devices, both connections, then a short wait.
    pub fn pass(&mut self) {
        let now = Now::read();
        for d in &mut self.devices {
            d.mainloop(now);
        }
        self.server.mainloop().unwrap();
        self.client.mainloop().unwrap();
        let deadline = self
            .devices
            .iter()
            .filter_map(|d| d.next_deadline())
            .chain(self.server.poll_timeout())
            .chain(self.client.poll_timeout())
            .min();
        self.reactor
            .wait(deadline, Duration::from_millis(2))
            .unwrap();
    }

    /// Runs passes until `done` holds; fails with `what` after 10 s.
    pub fn until(&mut self, what: &str, mut done: impl FnMut(&mut Rig) -> bool) {
        let start = Instant::now();
        while !done(self) {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            self.pass();
        }
    }

    /// Runs passes for `d`.
    #[allow(dead_code)]
    pub fn run_for(&mut self, d: Duration) {
        let start = Instant::now();
        while start.elapsed() < d {
            self.pass();
        }
    }

    /// The client has completed its handshake.
    pub fn connect(&mut self) {
        self.until("the client connects", |r| r.client.connected());
    }

    /// Plugs in hidraw node `n`: sysfs entry, the simulator's socket, the uevent.
    pub fn plug(
        &mut self,
        n: u32,
        vendor: u16,
        product: u16,
        interface: i32,
        name: &str,
    ) -> NodeListener {
        self.fake
            .add_hidraw(n, vendor, product, interface, name, "");
        let l = self.fake.listen_hidraw(n).unwrap();
        // The watcher exists once a device has run a pass.
        self.pass();
        self.fake
            .uevent("add", "hidraw", &format!("hidraw{n}"))
            .unwrap();
        l
    }

    /// Waits for the server to open the simulator's node.
    pub fn accept(&mut self, l: &NodeListener) -> DeviceEnd {
        let mut end = None;
        self.until("the server opens the device", |_| {
            end = l.accept().unwrap();
            end.is_some()
        });
        end.unwrap()
    }

    /// Unplugs hidraw node `n` (the simulator drops its end separately).
    pub fn unplug(&mut self, n: u32) {
        self.fake.remove_hidraw(n);
        self.fake
            .uevent("remove", "hidraw", &format!("hidraw{n}"))
            .unwrap();
    }
}
