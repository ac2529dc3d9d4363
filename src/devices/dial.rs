//! Dial: incremental rotation of each dial, in revolutions.
//! [`DialRemote`] is the client half, [`DialServer`] the server half, [`DialExample`] the
//! C++ `vrpn_Dial_Example_Server`.

use std::ops::Deref;
use std::rc::Rc;
use std::time::Instant;

use super::base::{self, BaseIds, RemoteCore};
use super::latest::{Latest, Stamp};
use super::text::TextSeverity;
use super::{Cadence, ServerDevice};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderId, TypeId};
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
    /// Time the server stamped on the report, translated to the local clock when clock
    /// synchronisation is in effect.
    pub time: TimeVal,
    /// The time exactly as the server stamped it.
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock of the `mainloop()` pass that read it).
    pub arrival: TimeVal,
    /// Which update of this dial it is: 1 for the first this remote received, then 2, ...
    pub seq: u64,
    /// Dial index.
    pub dial: usize,
    /// Revolutions since the previous report.
    pub change: f64,
}

/// What a remote keeps of a dial: its last update and the rotation not yet taken.
#[derive(Clone, Copy)]
struct DialState {
    last: DialUpdate,
    untaken: f64,
}

struct RemoteShared {
    update: CallbackList<DialUpdate>,
    dials: Latest<DialState>,
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
        let shared = Rc::new(RemoteShared {
            update: CallbackList::default(),
            dials: Latest::with_capacity(8),
            bad: std::cell::Cell::new(0),
        });
        let s = shared.clone();
        core.handle(ids.update, move |m| {
            match codec::Update::decode(m.payload) {
                Ok(u) if u.dial >= 0 => {
                    let (st, dial) = (Stamp::of(m), u.dial as usize);
                    let untaken = s.dials.get(dial).map_or(0.0, |d| d.untaken);
                    let state = s.dials.store(dial, |seq| DialState {
                        last: DialUpdate {
                            time: m.time,
                            sender_time: st.sender_time,
                            arrival: st.arrival,
                            seq,
                            dial,
                            change: u.change,
                        },
                        untaken: untaken + u.change,
                    });
                    s.update.call(&state.last);
                }
                _ => s.bad.set(s.bad.get() + 1),
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

    /// The last update of `dial`, if any arrived.
    pub fn last_update(&self, dial: usize) -> Option<DialUpdate> {
        self.shared.dials.get(dial).map(|d| d.last)
    }

    /// Revolutions `dial` turned since the last `take_rotation(dial)` (the sum of the
    /// updates in between; 0.0 when none came): what a frame loop applies once per frame.
    pub fn take_rotation(&self, dial: usize) -> f64 {
        self.shared.dials.take(dial).map_or(0.0, |d| {
            self.shared.dials.store_quiet(dial, |s| s.untaken = 0.0);
            d.untaken
        })
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

    fn send(&mut self, i: usize) -> Result<(), Error> {
        let mut buf = [0u8; codec::Update::LEN];
        codec::Update {
            change: self.dials[i],
            dial: i as i32,
        }
        .encode(&mut buf);
        self.dials[i] = 0.0;
        self.conn.pack_message(
            self.timestamp,
            self.ids.update,
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }

    /// Sends one update per dial with nonzero rotation, then zeroes them.
    pub fn report_changes(&mut self) -> Result<(), Error> {
        for i in 0..self.num {
            if self.dials[i] != 0.0 {
                self.send(i)?;
            }
        }
        Ok(())
    }

    /// Sends one update per dial, zeros included, then zeroes them.
    pub fn report(&mut self) -> Result<(), Error> {
        for i in 0..self.num {
            self.send(i)?;
        }
        Ok(())
    }

    /// This device's sender id on its connection.
    pub fn sender(&self) -> SenderId {
        self.base.sender
    }

    /// The connection this server reports on.
    pub fn connection(&self) -> &Connection {
        &self.conn
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
        let _ = self.server.report_changes();
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}
