//! Client side, text messages: a device's texts (warnings, errors, notes such as "cannot open
//! the serial port") as callbacks, like C++ `vrpn_Text_Receiver`.

use std::ffi::{c_char, c_void};

use super::client::{callback, connection_state, mainloop, open, Callbacks, Remote};
use super::handle::{self, Header, Object};
use super::types::VrpnTimeVal;
use super::{count, status, VrpnStatus};
use crate::devices::base::RemoteCore;
use crate::devices::text::TextSeverity;
use crate::{TextMessage, TextReceiver};

/// Capacity of `VrpnTextMessage::text`: the longest VRPN text (1023 bytes) and its NUL.
pub const VRPN_TEXT_CAPACITY: usize = 1024;

/// A text message from a device.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct VrpnTextMessage {
    /// Time the sender stamped on the message (translated to the local clock when clock
    /// synchronisation is in effect).
    pub time: VrpnTimeVal,
    /// 0 normal, 1 warning, 2 error (C++ `vrpn_TEXT_NORMAL` …); other values as sent.
    pub severity: u32,
    /// The level the sender gave (free-form).
    pub level: u32,
    /// The text, UTF-8, NUL-terminated.
    pub text: [c_char; VRPN_TEXT_CAPACITY],
}

impl From<&TextMessage> for VrpnTextMessage {
    fn from(m: &TextMessage) -> Self {
        let mut text = [0 as c_char; VRPN_TEXT_CAPACITY];
        for (d, &b) in text.iter_mut().zip(m.text().as_bytes()) {
            *d = b as c_char;
        }
        VrpnTextMessage {
            time: m.time.into(),
            severity: match m.severity {
                TextSeverity::Normal => 0,
                TextSeverity::Warning => 1,
                TextSeverity::Error => 2,
                TextSeverity::Other(c) => c,
            },
            level: m.level,
            text,
        }
    }
}

/// Receives text messages; `message` is valid during the call only.
pub type VrpnTextMessageCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, message: *const VrpnTextMessage)>;

/// A text receiver (C++ `vrpn_Text_Receiver`).
pub struct VrpnText {
    header: Header,
    remote: TextReceiver,
    callbacks: Callbacks,
}

impl Object for VrpnText {
    const TAG: u32 = 0x7672_0005;
    const NAME: &'static str = "VrpnText";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnText {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Receives the text messages of device `name` ("Tracker0@host", see `vrpn_tracker_open`);
/// NULL on failure. (Without a callback, warnings and errors still go to the default printer:
/// see `vrpn_set_default_printer`.)
#[no_mangle]
pub extern "C" fn vrpn_text_open(name: *const c_char) -> *mut VrpnText {
    open(name, |n| {
        Ok(VrpnText {
            header: Header::new::<VrpnText>(),
            remote: TextReceiver::new(n)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees a text receiver (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_text_free(text: *mut VrpnText) -> VrpnStatus {
    handle::free(text)
}

/// Services the receiver's connection without blocking; runs callbacks.
#[no_mangle]
pub extern "C" fn vrpn_text_mainloop(text: *mut VrpnText) -> VrpnStatus {
    mainloop(text)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_text_connection_state(text: *const VrpnText) -> i32 {
    connection_state(text)
}

/// Calls `callback(userdata, message)` for every text message from the device.
#[no_mangle]
pub extern "C" fn vrpn_text_on_message(
    text: *mut VrpnText,
    callback: VrpnTextMessageCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(text, |t| {
        let cb = self::callback(callback, userdata)?;
        let id = t
            .remote
            .on_message(move |m| cb.call(VrpnTextMessage::from(m)));
        t.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id `vrpn_text_on_message` gave.
#[no_mangle]
pub extern "C" fn vrpn_text_remove_callback(text: *mut VrpnText, id: u64) -> VrpnStatus {
    status(handle::with(text, |t| {
        t.remote.remove_callback(t.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Number of messages received so far (saturated at INT32_MAX), or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_text_received(text: *const VrpnText) -> i32 {
    count(handle::with(text, |t| {
        Ok(usize::try_from(t.remote.received()).unwrap_or(usize::MAX))
    }))
}
