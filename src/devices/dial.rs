//! Dial: incremental rotation of each dial, in revolutions.
//! [`DialRemote`] is the client half, [`DialServer`] the server half, [`DialExample`] the
//! C++ `vrpn_Dial_Example_Server`.

use std::ops::Deref;
use std::rc::Rc;
use std::time::Instant;

use super::base::{self, BaseIds, RemoteCore};
use super::text::TextSeverity;
use super::{Cadence, ServerDevice};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, TypeId};
use crate::error::Error;
use crate::time::{Now, TimeVal};
use crate::wire::class;
use crate::wire::payload::dial as codec;

pub use codec::MAX_DIALS;

/// Ids of the dial types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct DialIds {
    /// `vrpn_Dial update`.
    pub update: TypeId,
}

impl DialIds {
    /// Registers the dial type.
    pub fn register(conn: &Connection) -> Result<DialIds, Error> {
        Ok(DialIds {
            update: conn.register_type(codec::UPDATE)?,
        })
    }
}

/// One dial moved (C++ `vrpn_DIALCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DialUpdate {
    /// Time the server stamped on the report.
    pub time: TimeVal,
    /// Dial index.
    pub dial: i32,
    /// Revolutions since the previous report.
    pub change: f64,
}

#[derive(Default)]
struct RemoteShared {
    update: CallbackList<DialUpdate>,
    bad: std::cell::Cell<u64>,
}

/// Client half of a dial device.
pub struct DialRemote {
    core: RemoteCore,
    shared: Rc<RemoteShared>,
}

impl Deref for DialRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl DialRemote {
    /// Opens `Device@location` (sharing the connection with other devices at that location).
    pub fn new(name: &str) -> Result<DialRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<DialRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, DialIds::register)?;
        let shared = Rc::new(RemoteShared::default());
        let s = shared.clone();
        core.handle(ids.update, move |m| {
            match codec::Update::decode(m.payload) {
                Ok(u) => s.update.call(&DialUpdate {
                    time: m.time,
                    dial: u.dial,
                    change: u.change,
                }),
                Err(_) => s.bad.set(s.bad.get() + 1),
            }
        });
        Ok(DialRemote { core, shared })
    }

    /// Calls `f` for every dial update.
    pub fn on_update(&self, f: impl FnMut(&DialUpdate) + 'static) -> HandlerId {
        self.shared.update.add(f)
    }

    /// Removes a callback.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.update.remove(id)
    }

    /// Updates that could not be decoded and were ignored.
    pub fn bad_messages(&self) -> u64 {
        self.shared.bad.get()
    }
}

/// Server half of a dial device: accumulate rotation per dial, then report.
pub struct DialServer {
    conn: Connection,
    ids: DialIds,
    base: BaseIds,
    num: usize,
    dials: [f64; MAX_DIALS],
    timestamp: TimeVal,
}

impl DialServer {
    /// Registers `device` with `dials` dials (clamped to 128).
    pub fn new(device: &str, conn: &Connection, dials: usize) -> Result<DialServer, Error> {
        let (base, ids) = base::register_server(conn, device, DialIds::register)?;
        Ok(DialServer {
            conn: conn.clone(),
            ids,
            base,
            num: dials.min(MAX_DIALS),
            dials: [0.0; MAX_DIALS],
            timestamp: TimeVal::ZERO,
        })
    }

    /// Number of dials.
    pub fn num_dials(&self) -> usize {
        self.num
    }

    /// Sets the time stamped on later reports.
    pub fn set_timestamp(&mut self, t: TimeVal) {
        self.timestamp = t;
    }

    /// Sets dial `i`'s accumulated rotation (revolutions).
    pub fn set_dial(&mut self, i: usize, revolutions: f64) {
        if i < self.num {
            self.dials[i] = revolutions;
        }
    }

    /// Adds to dial `i`'s accumulated rotation.
    pub fn add_rotation(&mut self, i: usize, revolutions: f64) {
        if i < self.num {
            self.dials[i] += revolutions;
        }
    }

    fn send(&mut self, i: usize) {
        let mut buf = [0u8; codec::Update::LEN];
        codec::Update {
            change: self.dials[i],
            dial: i as i32,
        }
        .encode(&mut buf);
        let _ = self.conn.pack_message(
            self.timestamp,
            self.ids.update,
            self.base.sender,
            &buf,
            class::RELIABLE,
        );
        self.dials[i] = 0.0;
    }

    /// Sends one update per dial with nonzero rotation, then zeroes them.
    pub fn report_changes(&mut self) {
        for i in 0..self.num {
            if self.dials[i] != 0.0 {
                self.send(i);
            }
        }
    }

    /// Sends one update per dial, zeros included, then zeroes them.
    pub fn report(&mut self) {
        for i in 0..self.num {
            self.send(i);
        }
    }

    /// Sends a text message from this device.
    pub fn send_text(&self, severity: TextSeverity, level: u32, text: &str) -> Result<(), Error> {
        base::send_text(&self.conn, self.base.sender, severity, level, text)
    }
}

/// `vrpn_Dial_Example NAME DIALS SPIN_RATE UPDATE_RATE`: every dial turns `SPIN_RATE`
/// revolutions per second, reported `UPDATE_RATE` times a second (`SPIN_RATE/UPDATE_RATE` each).
pub struct DialExample {
    server: DialServer,
    name: String,
    step: f64,
    cadence: Cadence,
}

impl DialExample {
    /// An example dial server.
    pub fn new(
        device: &str,
        conn: &Connection,
        dials: usize,
        spin_rate: f64,
        update_rate: f64,
    ) -> Result<DialExample, Error> {
        let ok = update_rate > 0.0 && update_rate.is_finite();
        Ok(DialExample {
            server: DialServer::new(device, conn, dials)?,
            name: device.to_string(),
            step: if ok { spin_rate / update_rate } else { 0.0 },
            cadence: Cadence::per_second(update_rate),
        })
    }
}

impl ServerDevice for DialExample {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        if !self.cadence.due(now.mono) {
            return;
        }
        self.server.set_timestamp(now.wall);
        for i in 0..self.server.num_dials() {
            self.server.set_dial(i, self.step);
        }
        self.server.report_changes();
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}
