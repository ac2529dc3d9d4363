//! Button: edges (`Change`), the full state vector (`States`), mode requests
//! (`Admin`) and toggle alerts. [`ButtonRemote`] is the client half, [`ButtonServer`] the
//! server half (C++ `vrpn_Button_Filter` semantics), [`ButtonExample`] the example server.

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;
use std::time::Instant;

use super::base::{self, BaseIds, RemoteCore};
use super::latest::{Index, Latest, Stamp};
use super::text::TextSeverity;
use super::{Cadence, ServerDevice};
use crate::connection::{Connection, ConnectionEvent};
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::time::{Now, TimeVal};
use crate::wire::class;
use crate::wire::payload::button as codec;

pub use codec::{ALL_ID, MAX_BUTTONS, MOMENTARY, OFF, ON, TOGGLE_OFF, TOGGLE_ON};

/// Ids of the button types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct ButtonIds {
    /// `vrpn_Button Change`.
    pub change: TypeId,
    /// `vrpn_Button States`.
    pub states: TypeId,
    /// `vrpn_Button Admin`.
    pub admin: TypeId,
}

impl ButtonIds {
    /// Registers the three button types in C++ order.
    pub fn register(conn: &Connection) -> Result<ButtonIds, Error> {
        Ok(ButtonIds {
            change: conn.register_type(codec::CHANGE)?,
            states: conn.register_type(codec::STATES)?,
            admin: conn.register_type(codec::ADMIN)?,
        })
    }
}

/// Whether a button is down. On the wire a state is an integer: 0 is released, anything
/// else pressed (C++ sends 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ButtonState {
    /// Up ([`OFF`]).
    #[default]
    Released,
    /// Down ([`ON`]).
    Pressed,
}

impl ButtonState {
    /// The state of a wire value (nonzero is pressed).
    pub fn from_raw(raw: i32) -> ButtonState {
        if raw == OFF {
            ButtonState::Released
        } else {
            ButtonState::Pressed
        }
    }

    /// The wire value: [`OFF`] or [`ON`].
    pub fn raw(self) -> i32 {
        match self {
            ButtonState::Released => OFF,
            ButtonState::Pressed => ON,
        }
    }

    /// True for [`Pressed`](Self::Pressed).
    pub fn is_pressed(self) -> bool {
        self == ButtonState::Pressed
    }
}

impl From<bool> for ButtonState {
    fn from(pressed: bool) -> Self {
        if pressed {
            ButtonState::Pressed
        } else {
            ButtonState::Released
        }
    }
}

/// One button changed (C++ `vrpn_BUTTONCB`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ButtonChange {
    /// Time the server stamped on the report, translated to the local clock when clock
    /// synchronisation is in effect.
    pub time: TimeVal,
    /// The time exactly as the server stamped it.
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock of the `mainloop()` pass that read it).
    pub arrival: TimeVal,
    /// Which change of this button it is: 1 for the first this remote received, then 2, ...
    pub seq: u64,
    /// Button index.
    pub button: usize,
    /// New state.
    pub state: ButtonState,
}

/// The state of every button (C++ `vrpn_BUTTONSTATESCB`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ButtonStates {
    /// Time the server stamped on the report (translated as [`ButtonChange::time`]).
    pub time: TimeVal,
    /// The time exactly as the server stamped it.
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock).
    pub arrival: TimeVal,
    /// Number of buttons.
    pub num_buttons: usize,
    /// States of buttons `0..num_buttons`; the rest is released.
    pub states: [ButtonState; MAX_BUTTONS],
}

impl ButtonStates {
    /// The states of buttons `0..num_buttons`.
    pub fn as_slice(&self) -> &[ButtonState] {
        &self.states[..self.num_buttons.min(MAX_BUTTONS)]
    }
}

struct RemoteShared {
    change: CallbackList<ButtonChange>,
    states_cb: CallbackList<ButtonStates>,
    /// Latest state of every button (from Change and States).
    states: RefCell<[ButtonState; MAX_BUTTONS]>,
    /// The latest change of each button, with its count.
    changes: Latest<ButtonChange>,
    /// Presses (changes to pressed) not yet taken, per button.
    presses: RefCell<[u32; MAX_BUTTONS]>,
    num_buttons: Cell<usize>,
    got_states: Cell<bool>,
    bad_messages: Cell<u64>,
}

/// Client half of a button device: callbacks and the latest state of every button.
pub struct ButtonRemote {
    core: RemoteCore,
    ids: ButtonIds,
    shared: Rc<RemoteShared>,
}

impl Deref for ButtonRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl ButtonRemote {
    /// Opens `Device@location` (sharing the connection with other devices at that location).
    pub fn new(name: &str) -> Result<ButtonRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<ButtonRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, ButtonIds::register)?;
        let shared = Rc::new(RemoteShared {
            change: CallbackList::default(),
            states_cb: CallbackList::default(),
            states: RefCell::new([ButtonState::Released; MAX_BUTTONS]),
            changes: Latest::with_capacity(MAX_BUTTONS),
            presses: RefCell::new([0; MAX_BUTTONS]),
            num_buttons: Cell::new(MAX_BUTTONS),
            got_states: Cell::new(false),
            bad_messages: Cell::new(0),
        });
        let s = shared.clone();
        core.handle(ids.change, move |m| {
            match codec::Change::decode(m.payload) {
                Ok(c) if (0..MAX_BUTTONS as i32).contains(&c.button) => {
                    let (st, button) = (Stamp::of(m), c.button as usize);
                    let state = ButtonState::from_raw(c.state);
                    s.states.borrow_mut()[button] = state;
                    if state == ButtonState::Pressed {
                        let mut p = s.presses.borrow_mut();
                        p[button] = p[button].saturating_add(1);
                    }
                    let change = s.changes.store(button, |seq| ButtonChange {
                        time: m.time,
                        sender_time: st.sender_time,
                        arrival: st.arrival,
                        seq,
                        button,
                        state,
                    });
                    s.change.call(&change);
                }
                _ => s.bad_messages.set(s.bad_messages.get() + 1),
            }
        });
        let s = shared.clone();
        core.handle(ids.states, move |m| {
            match codec::States::decode(m.payload) {
                Ok(st) => {
                    s.num_buttons.set(st.count);
                    s.got_states.set(true);
                    let mut states = [ButtonState::Released; MAX_BUTTONS];
                    for (to, &raw) in states.iter_mut().zip(st.as_slice()) {
                        *to = ButtonState::from_raw(raw);
                    }
                    s.states.borrow_mut()[..st.count].copy_from_slice(&states[..st.count]);
                    let stamp = Stamp::of(m);
                    s.states_cb.call(&ButtonStates {
                        time: m.time,
                        sender_time: stamp.sender_time,
                        arrival: stamp.arrival,
                        num_buttons: st.count,
                        states,
                    });
                }
                Err(_) => s.bad_messages.set(s.bad_messages.get() + 1),
            }
        });
        Ok(ButtonRemote { core, ids, shared })
    }

    /// Calls `f` for every Change report.
    pub fn on_change(&self, f: impl FnMut(&ButtonChange) + 'static) -> HandlerId {
        self.shared.change.add(f)
    }

    /// Calls `f` for every States report.
    pub fn on_states(&self, f: impl FnMut(&ButtonStates) + 'static) -> HandlerId {
        self.shared.states_cb.add(f)
    }

    /// Removes a callback added with [`on_change`](Self::on_change) or
    /// [`on_states`](Self::on_states).
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.change.remove(id) || self.shared.states_cb.remove(id)
    }

    /// Latest state of button `i` (released until a report says otherwise).
    pub fn state(&self, i: usize) -> ButtonState {
        self.shared
            .states
            .borrow()
            .get(i)
            .copied()
            .unwrap_or_default()
    }

    /// True when button `i` is pressed now.
    pub fn pressed(&self, i: usize) -> bool {
        self.state(i).is_pressed()
    }

    /// How many times button `i` went down since the last `take_presses(i)`: a frame loop
    /// sees a click even when press and release both arrived between two frames.
    pub fn take_presses(&self, i: usize) -> u32 {
        self.shared
            .presses
            .borrow_mut()
            .get_mut(i)
            .map_or(0, std::mem::take)
    }

    /// The latest change of button `i`, if any arrived.
    pub fn last_change(&self, i: usize) -> Option<ButtonChange> {
        self.shared.changes.get(i)
    }

    /// The latest change of button `i` if it arrived since the last `take_change(i)`.
    pub fn take_change(&self, i: usize) -> Option<ButtonChange> {
        self.shared.changes.take(i)
    }

    /// Number of buttons: 256 until a States report gives the real count (as C++).
    pub fn num_buttons(&self) -> usize {
        self.shared.num_buttons.get()
    }

    /// True once a States report arrived.
    pub fn got_states(&self) -> bool {
        self.shared.got_states.get()
    }

    /// Reports that could not be decoded and were ignored.
    pub fn bad_messages(&self) -> u64 {
        self.shared.bad_messages.get()
    }

    fn admin(&self, button: i32, mode: i32) -> Result<(), Error> {
        let mut buf = [0u8; codec::Admin::LEN];
        codec::Admin { button, mode }.encode(&mut buf);
        self.send(self.ids.admin, &buf)
    }

    /// The wire's number of `button`, or an error (and a text, as C++) when it is outside
    /// the device's count.
    fn check(&self, button: impl Index, what: &str) -> Result<i32, Error> {
        match button.to_index() {
            Some(i) if i < self.num_buttons() => Ok(i as i32),
            i => {
                let shown = i.map_or("negative".to_string(), |i| i.to_string());
                let text = format!(
                    "vrpn_Button::{what}() buttons id {shown} is greater than the number of buttons({})",
                    self.num_buttons()
                );
                let _ = self.send_text(TextSeverity::Error, 0, &text);
                Err(Error::Unsupported(
                    "button index outside the device's count",
                ))
            }
        }
    }

    /// Asks the server to make button `i` momentary.
    pub fn set_momentary(&self, button: impl Index) -> Result<(), Error> {
        let button = self.check(button, "set_momentary")?;
        self.admin(button, MOMENTARY)
    }

    /// Asks the server to make button `i` a toggle, initially on (`true`) or off.
    pub fn set_toggle(&self, button: impl Index, on: bool) -> Result<(), Error> {
        let button = self.check(button, "set_toggle")?;
        self.admin(button, if on { TOGGLE_ON } else { TOGGLE_OFF })
    }

    /// Asks the server to make every button momentary.
    pub fn set_all_momentary(&self) -> Result<(), Error> {
        self.admin(ALL_ID, MOMENTARY)
    }

    /// Asks the server to make every button a toggle.
    pub fn set_all_toggle(&self, on: bool) -> Result<(), Error> {
        self.admin(ALL_ID, if on { TOGGLE_ON } else { TOGGLE_OFF })
    }
}

struct ServerState {
    num: usize,
    buttons: [i32; MAX_BUTTONS],
    last: [i32; MAX_BUTTONS],
    modes: [i32; MAX_BUTTONS],
    timestamp: TimeVal,
    alerts: bool,
}

#[derive(Clone, Copy)]
struct ServerIds {
    ids: ButtonIds,
    base: BaseIds,
    alert: TypeId,
}

fn send_states(conn: &Connection, ids: &ServerIds, st: &RefCell<ServerState>) -> Result<(), Error> {
    let mut buf = [0u8; 4 + 4 * MAX_BUTTONS];
    let (len, time) = {
        let s = st.borrow();
        let msg = codec::States {
            count: s.num,
            states: s.buttons,
        };
        (msg.encode(&mut buf), s.timestamp)
    };
    conn.pack_message(
        time,
        ids.ids.states,
        ids.base.sender,
        &buf[..len],
        class::RELIABLE,
    )
}

fn send_alert(conn: &Connection, ids: &ServerIds, time: TimeVal, button: i32, event: i32) {
    let mut buf = [0u8; codec::Alert::LEN];
    codec::Alert { button, event }.encode(&mut buf);
    let _ = conn.pack_message(time, ids.alert, ids.base.sender, &buf, class::RELIABLE);
}

/// Server half of a button device (C++ `vrpn_Button_Filter` / `vrpn_Button_Server`).
///
/// Set physical states with [`set_button`](Self::set_button), then call
/// [`report_changes`](Self::report_changes). Admin requests (from any sender on the
/// connection, as C++), States on every new connection and on every ping from this device's
/// sender are handled by the server itself.
pub struct ButtonServer {
    conn: Connection,
    ids: ServerIds,
    state: Rc<RefCell<ServerState>>,
}

impl ButtonServer {
    /// Registers `device` with `buttons` buttons (clamped to 256).
    pub fn new(device: &str, conn: &Connection, buttons: usize) -> Result<ButtonServer, Error> {
        let (base, bids) = base::register_server(conn, device, ButtonIds::register)?;
        let sender = base.sender;
        let alert = conn.register_type(codec::ALERT)?;
        let ids = ServerIds {
            ids: bids,
            base,
            alert,
        };
        let state = Rc::new(RefCell::new(ServerState {
            num: buttons.min(MAX_BUTTONS),
            buttons: [0; MAX_BUTTONS],
            last: [0; MAX_BUTTONS],
            modes: [MOMENTARY; MAX_BUTTONS],
            timestamp: TimeVal::ZERO,
            alerts: false,
        }));

        // States on each ping from our own sender (the pong goes out from serve_pings).
        let (weak, st) = (conn.downgrade(), state.clone());
        conn.register_handler(base.ping, SenderFilter::Only(sender), move |_| {
            if let Some(c) = weak.upgrade() {
                let _ = send_states(&c, &ids, &st);
            }
        });
        // States on every new connection.
        let (weak, st) = (conn.downgrade(), state.clone());
        conn.on_event(ConnectionEvent::GotConnection, move || {
            if let Some(c) = weak.upgrade() {
                let _ = send_states(&c, &ids, &st);
            }
        });
        // Admin from any sender, as C++.
        let (weak, st) = (conn.downgrade(), state.clone());
        conn.register_handler(bids.admin, SenderFilter::Any, move |m| {
            let Some(c) = weak.upgrade() else { return };
            let Ok(a) = codec::Admin::decode(m.payload) else {
                return;
            };
            apply_admin(&c, &ids, &st, a.button, a.mode);
        });
        Ok(ButtonServer {
            conn: conn.clone(),
            ids,
            state,
        })
    }

    /// Number of buttons.
    pub fn num_buttons(&self) -> usize {
        self.state.borrow().num
    }

    /// Sets the number of buttons (clamped to 256), for a device that learns its count as it
    /// runs (the Linux joystick). Buttons added start released.
    pub fn set_num_buttons(&self, n: usize) {
        self.state.borrow_mut().num = n.min(MAX_BUTTONS);
    }

    /// Sets the physical state of button `i` (nonzero is pressed). Out-of-range is ignored.
    pub fn set_button(&self, i: usize, pressed: bool) {
        let mut s = self.state.borrow_mut();
        if i < s.num {
            s.buttons[i] = i32::from(pressed);
        }
    }

    /// The physical state of button `i`.
    pub fn button(&self, i: usize) -> ButtonState {
        ButtonState::from_raw(self.state.borrow().buttons.get(i).copied().unwrap_or(0))
    }

    /// The mode of button `i` ([`MOMENTARY`], [`TOGGLE_OFF`] or [`TOGGLE_ON`]).
    pub fn mode(&self, i: usize) -> i32 {
        self.state
            .borrow()
            .modes
            .get(i)
            .copied()
            .unwrap_or(MOMENTARY)
    }

    /// Sets the time stamped on later reports.
    pub fn set_timestamp(&self, t: TimeVal) {
        self.state.borrow_mut().timestamp = t;
    }

    /// The device's current timestamp.
    pub fn timestamp(&self) -> TimeVal {
        self.state.borrow().timestamp
    }

    /// Enables or disables Alert messages (off by default, as C++).
    pub fn set_alerts(&self, on: bool) {
        self.state.borrow_mut().alerts = on;
    }

    /// Applies a mode change locally, exactly as an Admin request would.
    pub fn set_mode(&self, button: i32, mode: i32) {
        apply_admin(&self.conn, &self.ids, &self.state, button, mode);
    }

    /// Sends one Change per changed button (toggle semantics per mode), in index order.
    ///
    /// Never fails on a server; an error is what the connection refused (see
    /// [`Connection::pack_message`]).
    pub fn report_changes(&self) -> Result<(), Error> {
        self.send_changes(true)
    }

    /// Sends one Change per button whose physical state changed, in index order, ignoring
    /// toggle modes: what C++ drivers that call the plain `vrpn_Button::report_changes` send
    /// (the Magellan and the CerealBox), although clients may still set modes.
    pub fn report_changes_unfiltered(&self) -> Result<(), Error> {
        self.send_changes(false)
    }

    fn send_changes(&self, filtered: bool) -> Result<(), Error> {
        // (button, state, alert event or 0); built first so no borrow is held while sending.
        let mut out = [(0i32, 0i32, 0i32); MAX_BUTTONS];
        let mut n = 0;
        let (time, alerts) = {
            let mut s = self.state.borrow_mut();
            for i in 0..s.num {
                let (now, last) = (s.buttons[i], s.last[i]);
                let mode = if filtered { s.modes[i] } else { MOMENTARY };
                match mode {
                    TOGGLE_ON if now != 0 && last == 0 => {
                        s.modes[i] = TOGGLE_OFF;
                        out[n] = (i as i32, 0, TOGGLE_OFF);
                        n += 1;
                    }
                    TOGGLE_OFF if now != 0 && last == 0 => {
                        s.modes[i] = TOGGLE_ON;
                        out[n] = (i as i32, 1, TOGGLE_ON);
                        n += 1;
                    }
                    TOGGLE_ON | TOGGLE_OFF => {}
                    _ if now != last => {
                        out[n] = (i as i32, now, 0);
                        n += 1;
                    }
                    _ => {}
                }
                s.last[i] = now;
            }
            (s.timestamp, s.alerts)
        };
        for &(button, state, event) in &out[..n] {
            if alerts && event != 0 {
                send_alert(&self.conn, &self.ids, time, button, event);
            }
            let mut buf = [0u8; codec::Change::LEN];
            codec::Change { button, state }.encode(&mut buf);
            self.conn.pack_message(
                time,
                self.ids.ids.change,
                self.ids.base.sender,
                &buf,
                class::RELIABLE,
            )?;
        }
        Ok(())
    }

    /// Sends the States message now.
    pub fn report_states(&self) -> Result<(), Error> {
        send_states(&self.conn, &self.ids, &self.state)
    }

    /// This device's sender id on its connection.
    pub fn sender(&self) -> SenderId {
        self.ids.base.sender
    }

    /// Sends a text message from this device.
    pub fn send_text(&self, severity: TextSeverity, level: u32, text: &str) -> Result<(), Error> {
        base::send_text(&self.conn, self.ids.base.sender, severity, level, text)
    }

    /// The connection this server reports on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }
}

fn apply_admin(
    conn: &Connection,
    ids: &ServerIds,
    st: &RefCell<ServerState>,
    button: i32,
    mode: i32,
) {
    let mut alerts_out = [(0i32, 0i32); MAX_BUTTONS];
    let mut n = 0;
    let (time, alerts, err) = {
        let mut s = st.borrow_mut();
        let num = s.num;
        let mut err = None;
        if button == ALL_ID {
            for i in 0..num {
                if mode == MOMENTARY && s.modes[i] != MOMENTARY {
                    s.modes[i] = MOMENTARY;
                    alerts_out[n] = (i as i32, TOGGLE_OFF);
                    n += 1;
                } else if mode != MOMENTARY && s.modes[i] == MOMENTARY {
                    s.modes[i] = if mode == TOGGLE_ON {
                        TOGGLE_ON
                    } else {
                        TOGGLE_OFF
                    };
                    alerts_out[n] = (i as i32, mode);
                    n += 1;
                }
            }
        } else if button < 0 || button as usize >= num {
            let what = if mode == MOMENTARY {
                "set_momentary"
            } else {
                "set_toggle"
            };
            err = Some((what, button, num));
        } else {
            let i = button as usize;
            if mode == MOMENTARY {
                s.modes[i] = MOMENTARY;
                alerts_out[n] = (button, TOGGLE_OFF);
            } else {
                let m = if mode == TOGGLE_ON {
                    TOGGLE_ON
                } else {
                    TOGGLE_OFF
                };
                s.modes[i] = m;
                alerts_out[n] = (button, m);
            }
            n += 1;
        }
        (s.timestamp, s.alerts, err)
    };
    if let Some((what, b, num)) = err {
        let text = format!(
            "vrpn_Button::{what}() buttons id {b} is greater than the number of buttons({num})"
        );
        let _ = base::send_text(conn, ids.base.sender, TextSeverity::Error, 0, &text);
        return;
    }
    if alerts {
        for &(b, e) in &alerts_out[..n] {
            send_alert(conn, ids, time, b, e);
        }
    }
}

/// `vrpn_Button_Example NAME BUTTONS RATE`: every button flips together, `RATE` times a second;
/// the first flip (all on) happens on the first mainloop.
pub struct ButtonExample {
    server: ButtonServer,
    name: String,
    cadence: Cadence,
}

impl ButtonExample {
    /// An example button server.
    pub fn new(
        device: &str,
        conn: &Connection,
        buttons: usize,
        rate: f64,
    ) -> Result<ButtonExample, Error> {
        Ok(ButtonExample {
            server: ButtonServer::new(device, conn, buttons)?,
            name: device.to_string(),
            cadence: Cadence::per_second(rate),
        })
    }

    /// The underlying button server.
    pub fn server(&self) -> &ButtonServer {
        &self.server
    }

    /// Flips every button and reports, stamped now (one cycle of the example).
    pub fn flip(&self) {
        self.flip_at(self.server.connection().now().wall);
    }

    /// Flips every button and reports, stamped `time`.
    pub fn flip_at(&self, time: TimeVal) {
        self.server.set_timestamp(time);
        {
            let mut s = self.server.state.borrow_mut();
            for i in 0..s.num {
                s.buttons[i] = i32::from(s.last[i] == 0);
            }
        }
        let _ = self.server.report_changes();
    }
}

impl ServerDevice for ButtonExample {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        if self.cadence.due(now.mono) {
            self.flip_at(now.wall);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}
