//! Linux input devices through evdev: C++ `vrpn_DevInput` (keyboards, mice and joysticks by
//! their kernel name), `vrpn_Mouse` (C++ reads it through gpm on Linux; here through the
//! first mouse's event node) and `vrpn_Event_Mouse` (a mouse by its event node's path).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_DevInput NAME "DEVICE NAME" keyboard KEYS
//! vrpn_DevInput NAME "DEVICE NAME" relative [IGNORED]
//! vrpn_DevInput NAME "DEVICE NAME" absolute RANGE
//! vrpn_Mouse NAME
//! vrpn_Event_Mouse NAME EVENT_DEVICE
//! ```
//!
//! # What is sent
//!
//! - `vrpn_DevInput`: an Analog and a Button named `NAME`, counts as C++: a keyboard has no
//!   channels and `KEYS` buttons (1-255), button *n* the key with code *n*; a mouse or
//!   joystick has 80 buttons, button *n* the key code 0x110 + *n* (`BTN_LEFT` is 0, a
//!   joystick's `BTN_TRIGGER` 16, a gamepad's `BTN_SOUTH` 32), and channels numbered by axis
//!   code — 63 for `relative`, 15 for `absolute` (C++'s counts). An `EV_REL` event sets its
//!   channel to the motion it reports and always sends the Analog (equal motions are not
//!   lost); on an `absolute` device an `EV_ABS` event sets its channel to value / `RANGE`.
//!   One report per event, as C++.
//! - `vrpn_Mouse`: an Analog with 2 channels (the X and Y motion of the latest event frame,
//!   in counts) and a Button with 3 buttons (left, middle, right), sent at the end of each
//!   frame (`EV_SYN`).
//! - `vrpn_Event_Mouse`: an Analog with 3 channels (the latest `REL_X`, `REL_Y`,
//!   `REL_WHEEL` values) and a Button with 3 buttons (left, right, middle), what changed sent
//!   at the end of each frame.
//!
//! # Which node
//!
//! `vrpn_DevInput` takes the lowest-numbered event node whose name (sysfs `device/name`,
//! what `EVIOCGNAME` answers) is `DEVICE NAME` exactly; `vrpn_Mouse` the lowest-numbered
//! node with relative X and Y and a left button; `vrpn_Event_Mouse` its path (`/dev/…`
//! paths are read inside the server's device tree). All wait for the device to appear and
//! pick it up again after an unplug.
//!
//! # Differences from C++ VRPN
//!
//! * `vrpn_Mouse` reads evdev instead of gpm (no console mouse server needed); its channels
//!   are counts of the latest motion (gpm's are divided by the console's size).
//! * A key's auto-repeat (value 2) is reported as pressed (C++ sends state 2).
//! * `absolute` with no `RANGE` (or 0) passes values unscaled (C++ divides by zero).
//! * `vrpn_Event_Mouse` reads while no client is connected (C++ lets events queue) and
//!   ignores an unknown button instead of dropping the rest of the read.

pub mod config;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
#[cfg(test)]
mod tests;

pub use self::config::DRIVER;

use crate::devices::ServerDevice;
use crate::hid::input_event::{
    InputEvent, ABS_MAX, BTN_LEFT, BTN_MIDDLE, BTN_MOUSE, BTN_RIGHT, EV_ABS, EV_KEY, EV_REL,
    EV_SYN, REL_MAX, REL_WHEEL, REL_X, REL_Y,
};
use crate::hid::{DeviceHub, HidDevice, HidDriver, HidMatch, HidOps, NodeInfo, Select};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, Error};

/// Buttons of a `relative` or `absolute` device (C++ 0x50).
pub const MOUSE_BUTTONS: usize = 0x50;

/// What a `vrpn_DevInput` line reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DevInputKind {
    /// A keyboard with this many buttons (key codes 0…).
    Keyboard(usize),
    /// Relative axes (mouse).
    Relative,
    /// Absolute axes (joystick, tablet) divided by this range.
    Absolute(f64),
}

/// The three evdev drivers' behaviours.
#[derive(Clone, Debug, PartialEq)]
enum Kind {
    DevInput(DevInputKind),
    Mouse { dx: i32, dy: i32, moved: bool },
    EventMouse,
}

/// A driver for one evdev line: see the module documentation.
pub struct EvdevDriver {
    name: String,
    want: HidMatch,
    kind: Kind,
    analog: AnalogServer,
    buttons: ButtonServer,
    /// The frame has changes to report (the mice report at `EV_SYN`).
    pending: bool,
}

impl EvdevDriver {
    /// `vrpn_DevInput NAME "DEVICE" TYPE PARAM`.
    pub fn dev_input(
        name: &str,
        device: &str,
        kind: DevInputKind,
        conn: &Connection,
    ) -> Result<EvdevDriver, Error> {
        let (channels, buttons) = match kind {
            DevInputKind::Keyboard(n) => (0, n),
            DevInputKind::Relative => (usize::from(ABS_MAX), MOUSE_BUTTONS),
            DevInputKind::Absolute(_) => (usize::from(REL_MAX), MOUSE_BUTTONS),
        };
        Ok(EvdevDriver {
            name: name.to_string(),
            want: HidMatch::evdev(Select::Name(device.to_string())),
            kind: Kind::DevInput(kind),
            analog: AnalogServer::new(name, conn, channels)?,
            buttons: ButtonServer::new(name, conn, buttons)?,
            pending: false,
        })
    }

    /// `vrpn_Mouse NAME`.
    pub fn mouse(name: &str, conn: &Connection) -> Result<EvdevDriver, Error> {
        Ok(EvdevDriver {
            name: name.to_string(),
            want: HidMatch::evdev(Select::Mouse),
            kind: Kind::Mouse {
                dx: 0,
                dy: 0,
                moved: false,
            },
            analog: AnalogServer::new(name, conn, 2)?,
            buttons: ButtonServer::new(name, conn, 3)?,
            pending: false,
        })
    }

    /// `vrpn_Event_Mouse NAME PATH`.
    pub fn event_mouse(name: &str, path: &str, conn: &Connection) -> Result<EvdevDriver, Error> {
        Ok(EvdevDriver {
            name: name.to_string(),
            want: HidMatch::evdev(Select::Path(path.to_string())),
            kind: Kind::EventMouse,
            analog: AnalogServer::new(name, conn, 3)?,
            buttons: ButtonServer::new(name, conn, 3)?,
            pending: false,
        })
    }

    fn report(&mut self, at: Now, force_analog: bool) {
        // A failed send is the connection's business (it reports and drops the peer).
        if self.analog.num_channels() > 0 {
            let _ = if force_analog {
                self.analog.report(Some(at.wall)).map(|_| true)
            } else {
                self.analog.report_changes(Some(at.wall))
            };
        }
        self.buttons.set_timestamp(at.wall);
        let _ = self.buttons.report_changes();
    }

    /// Applies one event (see the module documentation for each kind).
    pub fn apply(&mut self, ev: InputEvent, at: Now) {
        match &mut self.kind {
            Kind::DevInput(kind) => {
                let kind = *kind;
                let mut force = false;
                match ev.kind {
                    EV_KEY => {
                        let n = match kind {
                            DevInputKind::Keyboard(_) => Some(usize::from(ev.code)),
                            _ => ev.code.checked_sub(BTN_MOUSE).map(usize::from),
                        };
                        if let Some(n) = n {
                            self.buttons.set_button(n, ev.value != 0);
                        }
                    }
                    // C++ takes relative motion on any kind's channels (a keyboard has none).
                    EV_REL if usize::from(ev.code) < self.analog.num_channels() => {
                        self.analog.set_channel(ev.code.into(), f64::from(ev.value));
                        force = true;
                    }
                    EV_ABS => {
                        if let DevInputKind::Absolute(range) = kind {
                            let range = if range == 0.0 { 1.0 } else { range };
                            self.analog
                                .set_channel(ev.code.into(), (f64::from(ev.value) - 0.0) / range);
                        }
                    }
                    _ => {}
                }
                self.report(at, force);
            }
            Kind::Mouse { dx, dy, moved } => match (ev.kind, ev.code) {
                (EV_REL, REL_X) => {
                    *dx += ev.value;
                    *moved = true;
                }
                (EV_REL, REL_Y) => {
                    *dy += ev.value;
                    *moved = true;
                }
                (EV_KEY, c @ (BTN_LEFT | BTN_MIDDLE | BTN_RIGHT)) => {
                    let b = match c {
                        BTN_LEFT => 0,
                        BTN_MIDDLE => 1,
                        _ => 2,
                    };
                    self.buttons.set_button(b, ev.value != 0);
                    self.pending = true;
                }
                (EV_SYN, _) => {
                    let forced = *moved;
                    if forced {
                        self.analog.set_channel(0, f64::from(*dx));
                        self.analog.set_channel(1, f64::from(*dy));
                    }
                    (*dx, *dy, *moved) = (0, 0, false);
                    if forced || self.pending {
                        self.pending = false;
                        self.report(at, forced);
                    }
                }
                _ => {}
            },
            Kind::EventMouse => match (ev.kind, ev.code) {
                (EV_REL, REL_X | REL_Y | REL_WHEEL) => {
                    let c = match ev.code {
                        REL_X => 0,
                        REL_Y => 1,
                        _ => 2,
                    };
                    self.analog.set_channel(c, f64::from(ev.value));
                    self.pending = true;
                }
                (EV_KEY, c @ (BTN_LEFT | BTN_RIGHT | BTN_MIDDLE))
                    if ev.value == 0 || ev.value == 1 =>
                {
                    let b = match c {
                        BTN_LEFT => 0,
                        BTN_RIGHT => 1,
                        _ => 2,
                    };
                    self.buttons.set_button(b, ev.value == 1);
                    self.pending = true;
                }
                (EV_SYN, _) if self.pending => {
                    self.pending = false;
                    self.report(at, false);
                }
                _ => {}
            },
        }
    }
}

impl HidDriver for EvdevDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        vec![self.want.clone()]
    }

    fn opened(&mut self, _now: Now, _nodes: &[Option<NodeInfo>], _ops: &mut HidOps) {
        self.pending = false;
        if let Kind::Mouse { dx, dy, moved } = &mut self.kind {
            (*dx, *dy, *moved) = (0, 0, false);
        }
    }

    fn report(&mut self, _interface: usize, record: &[u8], at: Now, _ops: &mut HidOps) {
        if let Some(ev) = InputEvent::decode(record) {
            self.apply(ev, at);
        }
    }
}

/// The running device for a line's driver.
pub fn build(driver: EvdevDriver, conn: &Connection, hub: &DeviceHub) -> Box<dyn ServerDevice> {
    Box::new(HidDevice::new(driver, hub, conn))
}

/// The `vrpn_DevInput` line that would serve `node`, by what its capabilities say it is.
pub fn suggest(node: &crate::hid::NodeInfo) -> Option<String> {
    use crate::hid::input_event::{BTN_GAMEPAD, BTN_JOYSTICK};
    let i = node.input()?;
    let name = &i.name;
    if i.ev.has(EV_REL.into()) && i.rel.has(REL_X.into()) && i.key.has(BTN_LEFT.into()) {
        return Some(format!("vrpn_DevInput Mouse0 \"{name}\" relative"));
    }
    if i.ev.has(EV_ABS.into()) && (i.key.has(BTN_JOYSTICK.into()) || i.key.has(BTN_GAMEPAD.into()))
    {
        return Some(format!("vrpn_DevInput Joystick0 \"{name}\" absolute 32767"));
    }
    // A keyboard: the letter keys (KEY_Q 16 … KEY_P 25).
    if i.ev.has(EV_KEY.into()) && (16..=25).all(|k| i.key.has(k)) {
        return Some(format!("vrpn_DevInput Keyboard0 \"{name}\" keyboard 255"));
    }
    None
}
