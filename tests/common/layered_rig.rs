//! The zero-allocation harness for layered devices (a device that reads another device,
//! `Src`, of its own server or of another server): two in-process servers and a TCP client
//! on one reactor, passes of all of them with the counting allocator on or off, and the
//! warm-up and counted phases every such test runs. A test crate that includes this file
//! also includes `counting_alloc.rs` as `mod counting_alloc`.
#![allow(dead_code)]

use std::net::Ipv4Addr;
use std::time::{Duration, Instant};

use vrpn::config::DeviceRef;
use vrpn::net::Reactor;
use vrpn::ServerDevice;
use vrpn::{Connection, Limits, Now};

use super::counting_alloc::{reset_count, set_counting};

/// The device's server, the server of what it reads and the client's connection.
pub struct Layered {
    pub reactor: Reactor,
    /// The layered device's server, which the client connects to.
    pub server: Connection,
    /// The server of what the device reads: `server` itself when local.
    pub upstream: Connection,
    /// Whether the device reads a device of its own server.
    pub local: bool,
}

impl Layered {
    /// Keeps the devices' texts off the test output and starts the servers on 127.0.0.1.
    pub fn new(local: bool) -> Layered {
        vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
        let reactor = Reactor::new().unwrap();
        let server =
            Connection::server_in(&reactor, Some(Ipv4Addr::LOCALHOST), 0, Limits::default())
                .unwrap();
        let upstream = if local {
            server.clone()
        } else {
            Connection::server_in(&reactor, Some(Ipv4Addr::LOCALHOST), 0, Limits::default())
                .unwrap()
        };
        Layered {
            reactor,
            server,
            upstream,
            local,
        }
    }

    /// How the device names `name` of the upstream server: `*name` locally,
    /// `name@127.0.0.1:PORT` otherwise.
    pub fn source(&self, name: &str) -> DeviceRef {
        if self.local {
            DeviceRef::Local(name.into())
        } else {
            DeviceRef::Remote(format!(
                "{name}@127.0.0.1:{}",
                self.upstream.local_port().unwrap()
            ))
        }
    }

    /// A TCP client of the device's server.
    pub fn client(&self) -> Connection {
        Connection::client_in(
            &self.reactor,
            "127.0.0.1",
            self.server.local_port().unwrap(),
            false,
            Limits::default(),
        )
        .unwrap()
    }

    /// One pass of the upstream server, the device, its server and the client, counted or
    /// not; then a wait for the sockets or the device's deadline (1 ms at most).
    pub fn pass(&self, device: &mut dyn ServerDevice, client: &Connection, counting: bool) {
        set_counting(counting);
        if !self.local {
            let _ = self.upstream.mainloop();
        }
        device.mainloop(Now::read());
        let _ = self.server.mainloop();
        let _ = client.mainloop();
        set_counting(false);
        self.reactor
            .wait(device.next_deadline(), Duration::from_millis(1))
            .unwrap();
    }

    /// Warm-up, nothing counted: `send` and five passes until `warm` (connections up, first
    /// reports heard), failing with `cold` after 20 s.
    pub fn warm_up(
        &self,
        device: &mut dyn ServerDevice,
        client: &Connection,
        mut send: impl FnMut(),
        warm: impl Fn() -> bool,
        cold: &str,
    ) {
        let start = Instant::now();
        while !warm() {
            assert!(start.elapsed() < Duration::from_secs(20), "{cold}");
            send();
            for _ in 0..5 {
                self.pass(device, client, false);
            }
        }
    }

    /// The counted part, from a count of zero: `rounds` times `send` and three passes, then
    /// passes until `done` (10 s at most). The caller checks `done` and the count.
    pub fn stream(
        &self,
        device: &mut dyn ServerDevice,
        client: &Connection,
        rounds: u32,
        mut send: impl FnMut(),
        done: impl Fn() -> bool,
    ) {
        reset_count();
        for _ in 0..rounds {
            set_counting(true);
            send();
            set_counting(false);
            for _ in 0..3 {
                self.pass(device, client, true);
            }
        }
        let start = Instant::now();
        while !done() && start.elapsed() < Duration::from_secs(10) {
            self.pass(device, client, true);
        }
    }
}
