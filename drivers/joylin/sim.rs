//! A simulated joystick: the kernel end of a `/dev/input/jsN` device, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! When plugged in (at creation, and after [`JoystickSim::plugged`]) it sends the initial
//! state as the kernel does after an open: one event per button, then one per axis, each
//! flagged [`JS_EVENT_INIT`](super::event::JS_EVENT_INIT). While [`JoystickSim::running`],
//! it then sends one live event every [`SimConfig::period`]: event `k` (counted over the
//! simulator's life) moves an axis to a new value or, every fourth, toggles a button
//! ([`JoystickSim::live_event`]). Every event sent can be logged with the time it left
//! ([`JoystickSim::sent`]), from which a test computes what a client must receive without
//! asking the driver.
//!
//! Faults: [`JoystickSim::inject`] puts bytes on the line, [`JoystickSim::mute`] makes it
//! silent. It ignores what is written to it (a joystick device is read-only).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::event::{JsEvent, Kind};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim joylin PATH`: a joystick with 6 axes and 10 buttons.
pub static SIMULATOR: Simulator = Simulator {
    name: "joylin",
    about: "Linux joystick (js_event records): 6 axes, 10 buttons",
    baud: 0,
    line: "vrpn_Joylin Joy0 {PATH}",
    make: |_| Box::new(JoystickSim::new(SimConfig::new(6, 10))),
};

/// How the simulated joystick is built and behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Axes, 1..=255.
    pub axes: u8,
    /// Buttons, 1..=255.
    pub buttons: u8,
    /// Time between live events.
    pub period: Duration,
    /// Log every event sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// `axes` axes and `buttons` buttons, an event every 5 ms, no log.
    pub fn new(axes: u8, buttons: u8) -> SimConfig {
        SimConfig {
            axes: axes.max(1),
            buttons: buttons.max(1),
            period: Duration::from_millis(5),
            keep_log: false,
        }
    }
}

/// An event put on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentEvent {
    /// When it left.
    pub at: Instant,
    /// The event.
    pub event: JsEvent,
}

/// The simulated joystick. See the module documentation.
pub struct JoystickSim {
    cfg: SimConfig,
    axes: Vec<i16>,
    buttons: Vec<bool>,
    count: u64,
    zero: Option<Instant>,
    next_event: Option<Instant>,
    init_pending: bool,
    out: VecDeque<(Instant, u8)>,
    /// Live events are sent while true.
    pub running: bool,
    /// Sends nothing while true (events still happen, and are lost).
    pub mute: bool,
    sent: Vec<SentEvent>,
}

impl JoystickSim {
    /// A joystick as `cfg` says, all axes centred and buttons released, running, plugged in.
    pub fn new(cfg: SimConfig) -> JoystickSim {
        JoystickSim {
            axes: vec![0; usize::from(cfg.axes)],
            buttons: vec![false; usize::from(cfg.buttons)],
            cfg,
            count: 0,
            zero: None,
            next_event: None,
            init_pending: true,
            out: VecDeque::new(),
            running: true,
            mute: false,
            sent: Vec::new(),
        }
    }

    /// Events sent (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentEvent] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// The current axis values.
    pub fn axes(&self) -> &[i16] {
        &self.axes
    }

    /// The current button states.
    pub fn buttons(&self) -> &[bool] {
        &self.buttons
    }

    /// Sets axis `i` (the next initial state carries it; nothing is sent now).
    pub fn set_axis(&mut self, i: usize, v: i16) {
        self.axes[i] = v;
    }

    /// Sets button `i` (the next initial state carries it; nothing is sent now).
    pub fn set_button(&mut self, i: usize, pressed: bool) {
        self.buttons[i] = pressed;
    }

    /// Leaves out the initial state after the next plug (a stand-in stream that sends live
    /// events only).
    pub fn skip_initial_state(&mut self) {
        self.init_pending = false;
    }

    /// The device was opened again: the initial state goes out at the next transmit.
    pub fn plugged(&mut self) {
        self.init_pending = true;
    }

    /// Puts `bytes` on the line at `now` (line noise).
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.out.extend(bytes.iter().map(|&b| (now, b)));
    }

    /// The number and value of live event `k` for a stick with `axes` axes and `buttons`
    /// buttons: every fourth event a button (its new state is the opposite of its old one),
    /// the others an axis, with values that differ from event to event.
    pub fn live_event(k: u64, axes: u8, buttons: u8) -> (Kind, u8) {
        if k % 4 == 3 {
            (Kind::Button, ((k / 4) % u64::from(buttons)) as u8)
        } else {
            (Kind::Axis, ((k - k / 4) % u64::from(axes)) as u8)
        }
    }

    /// The value live event `k` gives an axis.
    pub fn axis_value(k: u64) -> i16 {
        (((k * 7_919 + 1_234) % 65_535) as i32 - 32_767) as i16
    }

    fn put(&mut self, ev: JsEvent, at: Instant) {
        if self.mute {
            return;
        }
        self.out.extend(ev.encode().into_iter().map(|b| (at, b)));
        if self.cfg.keep_log {
            self.sent.push(SentEvent { at, event: ev });
        }
    }

    fn time_ms(&self, at: Instant) -> u32 {
        self.zero
            .map_or(0, |z| at.saturating_duration_since(z).as_millis() as u32)
    }

    fn init_burst(&mut self, at: Instant) {
        let time_ms = self.time_ms(at);
        let buttons = self.buttons.clone();
        for (i, &b) in buttons.iter().enumerate() {
            self.put(
                JsEvent {
                    time_ms,
                    value: i16::from(b),
                    kind: Kind::Button,
                    init: true,
                    number: i as u8,
                },
                at,
            );
        }
        let axes = self.axes.clone();
        for (i, &v) in axes.iter().enumerate() {
            self.put(
                JsEvent {
                    time_ms,
                    value: v,
                    kind: Kind::Axis,
                    init: true,
                    number: i as u8,
                },
                at,
            );
        }
    }

    fn live(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        let (kind, number) = JoystickSim::live_event(k, self.cfg.axes, self.cfg.buttons);
        let value = match kind {
            Kind::Axis => {
                let v = JoystickSim::axis_value(k);
                self.axes[usize::from(number)] = v;
                v
            }
            Kind::Button => {
                let b = &mut self.buttons[usize::from(number)];
                *b = !*b;
                i16::from(*b)
            }
        };
        let ev = JsEvent {
            time_ms: self.time_ms(at),
            value,
            kind,
            init: false,
            number,
        };
        self.put(ev, at);
    }
}

impl DeviceModel for JoystickSim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let zero = *self.zero.get_or_insert(now.mono);
        if std::mem::take(&mut self.init_pending) {
            self.init_burst(now.mono);
        }
        if !self.running {
            self.next_event = None;
        } else if self.next_event.is_none() {
            self.next_event = Some(now.mono.max(zero) + self.cfg.period);
        }
        while let Some(t) = self.next_event.filter(|&t| t <= now.mono) {
            self.live(t);
            self.next_event = Some(t + self.cfg.period);
        }
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        [self.out.front().map(|&(t, _)| t), self.next_event]
            .into_iter()
            .flatten()
            .min()
    }
}
