//! What most HID drivers share: the state a report decodes into (channels, buttons, dial
//! turns), the Analog/Button/Dial servers it goes out through, and a [`HidDriver`] that runs
//! any [`PadDecoder`] — decode a report, report what changed, stamped with the report's read
//! time.
//!
//! Reports go out in C++'s order: the Analog's `vrpn_Analog Channel` if a channel changed
//! (LOW_LATENCY), one `vrpn_Button Change` per changed button (RELIABLE), one `vrpn_Dial
//! update` per dial that turned (RELIABLE; the turn is then spent).
//!
//! Several C++ drivers also send their whole Analog again every 1/30 s whether or not it
//! changed; a decoder that says so ([`PadDecoder::repeats_analog`]) gets the same here, stamped
//! with the pass that sends it, while the device is open.

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use crate::connection::ConnectionEvent;
use crate::devices::text::TextSeverity;
use crate::driver::text::with_text;
use crate::hid::{HidDriver, HidMatch, HidOps, NodeInfo};
use crate::time::{Now, TimeVal};
use crate::{AnalogServer, ButtonServer, Connection, DialServer, Error};

/// Channels a pad state holds.
pub const MAX_CHANNELS: usize = 128;
/// Buttons a pad state holds.
pub const MAX_BUTTONS: usize = 256;
/// Dials a pad state holds.
pub const MAX_DIALS: usize = 4;
/// C++'s repeat period for drivers that send their Analog at 30 Hz.
pub const REPEAT_PERIOD: Duration = Duration::from_micros(33_333);

/// What a report decodes into.
#[derive(Clone, Debug)]
pub struct PadState {
    /// Analog channel values.
    pub channel: [f64; MAX_CHANNELS],
    /// Button states.
    pub button: [bool; MAX_BUTTONS],
    /// Dial turns (revolutions) not reported yet.
    pub dial: [f64; MAX_DIALS],
}

impl Default for PadState {
    fn default() -> Self {
        PadState {
            channel: [0.0; MAX_CHANNELS],
            button: [false; MAX_BUTTONS],
            dial: [0.0; MAX_DIALS],
        }
    }
}

/// The VRPN interfaces of a device, all named alike.
pub struct Pad {
    analog: Option<AnalogServer>,
    buttons: Option<ButtonServer>,
    dials: Option<DialServer>,
    /// The decoded state.
    pub state: PadState,
}

impl Pad {
    /// Registers the interfaces a device has (`None`: the C++ class has no such base).
    pub fn new(
        name: &str,
        conn: &Connection,
        channels: Option<usize>,
        buttons: Option<usize>,
        dials: Option<usize>,
    ) -> Result<Pad, Error> {
        Ok(Pad {
            analog: channels
                .map(|n| AnalogServer::new(name, conn, n))
                .transpose()?,
            buttons: buttons
                .map(|n| ButtonServer::new(name, conn, n))
                .transpose()?,
            dials: dials.map(|n| DialServer::new(name, conn, n)).transpose()?,
            state: PadState::default(),
        })
    }

    /// Sets the channel and button counts (a device that learns them from its descriptor).
    pub fn resize(&mut self, channels: usize, buttons: usize) {
        if let Some(a) = &mut self.analog {
            a.set_num_channels(channels.min(MAX_CHANNELS));
        }
        if let Some(b) = &self.buttons {
            b.set_num_buttons(buttons.min(MAX_BUTTONS));
        }
    }

    /// The Analog.
    pub fn analog(&self) -> Option<&AnalogServer> {
        self.analog.as_ref()
    }

    /// The Button.
    pub fn buttons(&self) -> Option<&ButtonServer> {
        self.buttons.as_ref()
    }

    /// The Dial.
    pub fn dials(&self) -> Option<&DialServer> {
        self.dials.as_ref()
    }

    fn copy_in(&mut self) {
        if let Some(a) = &mut self.analog {
            let n = a.num_channels();
            a.channels_mut()
                .copy_from_slice(&self.state.channel[..n.min(MAX_CHANNELS)]);
        }
        if let Some(b) = &self.buttons {
            for i in 0..b.num_buttons().min(MAX_BUTTONS) {
                b.set_button(i, self.state.button[i]);
            }
        }
    }

    /// Reports what changed, stamped `at` (a failed send is the connection's business: it
    /// reports and drops the peer).
    pub fn report_changes(&mut self, at: TimeVal) {
        self.copy_in();
        if let Some(a) = &mut self.analog {
            if a.num_channels() > 0 {
                let _ = a.report_changes(Some(at));
            }
        }
        self.report_buttons_and_dials(at);
    }

    /// Reports every channel whether or not it changed, then the buttons and dials that did.
    pub fn report_all(&mut self, at: TimeVal) {
        self.copy_in();
        if let Some(a) = &mut self.analog {
            if a.num_channels() > 0 {
                let _ = a.report(Some(at));
            }
        }
        self.report_buttons_and_dials(at);
    }

    fn report_buttons_and_dials(&mut self, at: TimeVal) {
        if let Some(b) = &self.buttons {
            b.set_timestamp(at);
            let _ = b.report_changes();
        }
        if let Some(d) = &mut self.dials {
            for i in 0..d.num_dials().min(MAX_DIALS) {
                d.set_dial(i, self.state.dial[i]);
                self.state.dial[i] = 0.0;
            }
            d.set_timestamp(at);
            let _ = d.report_changes();
        }
    }

    /// Sends a text from the device (formatted without allocating).
    pub fn say(&self, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
        with_text(args, |text| {
            let _ = if let Some(a) = &self.analog {
                a.send_text(severity, 0, text)
            } else if let Some(b) = &self.buttons {
                b.send_text(severity, 0, text)
            } else if let Some(d) = &self.dials {
                d.send_text(severity, 0, text)
            } else {
                Ok(())
            };
        });
    }
}

/// Why a report was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Skip {
    /// A length the device does not send.
    Length(usize),
    /// A report type (first byte) the driver does not know.
    Kind(u8),
    /// A report whose check bits are wrong.
    Corrupt,
    /// Nothing to report (the driver keeps it to itself).
    Quiet,
}

/// A device's report format: see the module documentation.
pub trait PadDecoder {
    /// Send the whole Analog every 1/30 s, as the C++ driver does.
    fn repeats_analog(&self) -> bool {
        false
    }

    /// Decodes one report into `state`.
    fn decode(&mut self, report: &[u8], state: &mut PadState) -> Result<(), Skip>;

    /// The device opened: forget what the last one said (dial positions).
    fn opened(&mut self, _state: &mut PadState, _ops: &mut HidOps) {}

    /// A text to send when the device opens (C++ greets some devices by what they are).
    fn greeting(&self, _node: Option<&NodeInfo>) -> Option<String> {
        None
    }

    /// Whether any client is connected changed (C++ X-keys turn their LEDs green or red).
    fn clients(&mut self, _any: bool, _ops: &mut HidOps) {}

    /// The server is stopping (C++ X-keys turn their LEDs off).
    fn shutdown(&mut self, _ops: &mut HidOps) {}
}

/// A [`PadDecoder`] as a [`HidDriver`].
pub struct PadDriver<T: PadDecoder> {
    name: String,
    wants: Vec<HidMatch>,
    /// The device's interfaces and state.
    pub pad: Pad,
    /// The report format.
    pub decoder: T,
    next_repeat: Option<Instant>,
    open: bool,
    /// Whether a client is connected, as the connection last said, and whether the decoder
    /// has heard it.
    clients: Rc<Cell<(bool, bool)>>,
    conn: Connection,
    last_now: Option<Instant>,
    skipped: u64,
    last_skip_text: Option<Instant>,
}

impl<T: PadDecoder> PadDriver<T> {
    /// A driver for `name`, on the node `wants` finds, reporting through `pad`.
    pub fn new(
        name: &str,
        conn: &Connection,
        wants: HidMatch,
        pad: Pad,
        decoder: T,
    ) -> PadDriver<T> {
        let clients = Rc::new(Cell::new((false, true)));
        let c = clients.clone();
        conn.on_event(ConnectionEvent::GotConnection, move || c.set((true, false)));
        let c = clients.clone();
        conn.on_event(ConnectionEvent::DroppedLastConnection, move || {
            c.set((false, false))
        });
        PadDriver {
            name: name.to_string(),
            wants: vec![wants],
            pad,
            decoder,
            next_repeat: None,
            open: false,
            clients,
            conn: conn.clone(),
            last_now: None,
            skipped: 0,
            last_skip_text: None,
        }
    }

    /// Reports skipped so far.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    fn note_skip(&mut self, skip: Skip, at: Now) {
        self.skipped += 1;
        // At most one text a second: a device sending garbage must not flood the clients.
        if self
            .last_skip_text
            .is_some_and(|t| at.mono < t + Duration::from_secs(1))
        {
            return;
        }
        self.last_skip_text = Some(at.mono);
        let name = &self.name;
        match skip {
            Skip::Length(n) => self.pad.say(
                TextSeverity::Warning,
                format_args!("{name}: ignored a report of unexpected length {n}"),
            ),
            Skip::Kind(k) => self.pad.say(
                TextSeverity::Warning,
                format_args!("{name}: ignored a report of unknown type {k}"),
            ),
            Skip::Corrupt => self.pad.say(
                TextSeverity::Warning,
                format_args!("{name}: ignored a corrupted report"),
            ),
            Skip::Quiet => {}
        }
    }
}

impl<T: PadDecoder> HidDriver for PadDriver<T> {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        self.wants.clone()
    }

    fn opened(&mut self, now: Now, nodes: &[Option<NodeInfo>], ops: &mut HidOps) {
        self.open = true;
        if let Some(text) = self
            .decoder
            .greeting(nodes.first().and_then(Option::as_ref))
        {
            self.pad.say(TextSeverity::Normal, format_args!("{text}"));
        }
        self.last_now = Some(now.mono);
        self.decoder.opened(&mut self.pad.state, ops);
        let any = self.conn.connected_peers() > 0;
        self.clients.set((any, true));
        self.decoder.clients(any, ops);
        self.next_repeat = self
            .decoder
            .repeats_analog()
            .then(|| now.mono + REPEAT_PERIOD);
    }

    fn report(&mut self, _interface: usize, report: &[u8], at: Now, _ops: &mut HidOps) {
        self.last_now = Some(at.mono);
        match self.decoder.decode(report, &mut self.pad.state) {
            Ok(()) => self.pad.report_changes(at.wall),
            Err(Skip::Quiet) => {}
            Err(skip) => self.note_skip(skip, at),
        }
    }

    fn poll(&mut self, now: Now, ops: &mut HidOps) {
        self.last_now = Some(now.mono);
        let (any, heard) = self.clients.get();
        if !heard {
            self.clients.set((any, true));
            self.decoder.clients(any, ops);
        }
        if let Some(t) = self.next_repeat {
            if now.mono >= t {
                self.pad.report_all(now.wall);
                // From now: after a stall, no burst of catch-up reports.
                self.next_repeat = Some(now.mono + REPEAT_PERIOD);
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        if !self.open {
            return None;
        }
        let (_, heard) = self.clients.get();
        let clients = (!heard).then_some(self.last_now).flatten();
        [self.next_repeat, clients].into_iter().flatten().min()
    }

    fn closed(&mut self, _now: Now) {
        self.open = false;
        self.next_repeat = None;
    }

    fn shutdown(&mut self, ops: &mut HidOps) {
        if self.open {
            self.decoder.shutdown(ops);
        }
    }
}

/// A little-endian `i16` at `at`.
pub fn le_i16(b: &[u8], at: usize) -> i16 {
    i16::from_le_bytes([b[at], b[at + 1]])
}

/// A little-endian `u16` at `at`.
pub fn le_u16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

/// A big-endian `i16` at `at` (VRPN's own byte order, which C++ `vrpn_unbuffer` reads).
pub fn be_i16(b: &[u8], at: usize) -> i16 {
    i16::from_be_bytes([b[at], b[at + 1]])
}

/// C++'s hat-to-angle table of the game-controller drivers: the angle (degrees clockwise from
/// up) of the hat's direction buttons, −1 when none is pressed.
pub fn dpad_angle(up: bool, right: bool, down: bool, left: bool) -> f64 {
    let x = i32::from(right) - i32::from(left);
    let y = i32::from(up) - i32::from(down);
    const ANGLES: [f64; 9] = [225.0, 270.0, 315.0, 180.0, -1.0, 0.0, 135.0, 90.0, 45.0];
    ANGLES[((x + 1) * 3 + (y + 1)) as usize]
}

/// C++'s axis normalisation of the game-controller drivers: `value` centred on half its
/// `bits`-bit range, zero inside three quarters of `deadzone` (integer arithmetic, as C++),
/// divided by half the range, times `scale`, clamped to −1…1. Computed in single precision
/// where C++ does.
pub fn normalize_axis(value: u32, deadzone: i32, scale: f64, bits: u32) -> f64 {
    let half = (1u32 << (bits - 1)) as f32;
    let mut channel = f64::from(value as f32 - half);
    if channel.abs() < f64::from(deadzone * 3 / 4) {
        channel = 0.0;
    } else {
        channel /= f64::from(half);
    }
    (channel * scale).clamp(-1.0, 1.0)
}

/// The simpler normalisation of the Contour, Griffin and Futaba drivers: centred on 128,
/// zero inside `deadzone`, divided by 128, times `scale`, clamped.
pub fn normalize_byte_axis(value: u32, deadzone: i32, scale: f64) -> f64 {
    let mut channel = f64::from(value as f32 - 128.0f32);
    if channel.abs() < f64::from(deadzone) {
        channel = 0.0;
    } else {
        channel /= 128.0;
    }
    (channel * scale).clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hat_angles_follow_the_cpp_table() {
        assert_eq!(dpad_angle(false, false, false, false), -1.0);
        assert_eq!(dpad_angle(true, false, false, false), 0.0);
        assert_eq!(dpad_angle(true, true, false, false), 45.0);
        assert_eq!(dpad_angle(false, true, false, false), 90.0);
        assert_eq!(dpad_angle(false, true, true, false), 135.0);
        assert_eq!(dpad_angle(false, false, true, false), 180.0);
        assert_eq!(dpad_angle(false, false, true, true), 225.0);
        assert_eq!(dpad_angle(false, false, false, true), 270.0);
        assert_eq!(dpad_angle(true, false, false, true), 315.0);
    }

    #[test]
    fn axes_centre_clamp_and_keep_their_dead_zone() {
        assert_eq!(normalize_axis(128, 8, 1.0, 8), 0.0);
        // |value − 128| = 5 < 8·3/4 = 6: inside the dead zone.
        assert_eq!(normalize_axis(133, 8, 1.0, 8), 0.0);
        assert_eq!(normalize_axis(134, 8, 1.0, 8), 6.0 / 128.0);
        assert_eq!(normalize_axis(0, 8, 1.0, 8), -1.0);
        assert_eq!(normalize_axis(255, 8, 1.0, 8), 127.0 / 128.0);
        assert_eq!(normalize_axis(0xffff, 7849, 1.0, 16), 32767.0 / 32768.0);
        assert_eq!(normalize_axis(0, 7849, 2.0, 16), -1.0);
        assert_eq!(normalize_byte_axis(128 + 4, 5, 1.0), 0.0);
        let scale = f64::from(1.0f32 / 0.70f32);
        assert_eq!(normalize_byte_axis(200, 5, scale), 72.0 / 128.0 * scale);
        assert_eq!(normalize_byte_axis(255, 5, scale), 1.0);
    }
}
