//! Function generator (`vrpn_FunctionGenerator`): a remote sets the function each channel
//! generates (none, or a script for the server's interpreter), the sample rate, and starts
//! and stops generation; the server answers each request. [`FunctionGeneratorRemote`] is
//! the client half; [`FunctionGeneratorServer`] runs a program's [`FunctionGeneratorHandler`],
//! which does the generating (this crate has no waveform or audio back end).

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;

use super::base::{self, BaseIds, RemoteCore};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::function_generator::{
    self as codec, ChannelMessage, ChannelNumber, Description, ErrorReport, Flag, Function,
    SampleRate, MAX_CHANNELS,
};

/// Ids of the thirteen function generator types, in C++ registration order.
#[derive(Clone, Copy, Debug)]
pub struct FunctionGeneratorIds(pub [TypeId; 13]);

impl FunctionGeneratorIds {
    /// Registers the types in C++ order.
    pub fn register(conn: &Connection) -> Result<FunctionGeneratorIds, Error> {
        let mut ids = [TypeId(0); 13];
        for (slot, name) in ids.iter_mut().zip(codec::TYPE_NAMES) {
            *slot = conn.register_type(name)?;
        }
        Ok(FunctionGeneratorIds(ids))
    }
    fn channel(&self) -> TypeId {
        self.0[0]
    }
    fn channel_request(&self) -> TypeId {
        self.0[1]
    }
    fn all_channel_request(&self) -> TypeId {
        self.0[2]
    }
    fn sample_rate(&self) -> TypeId {
        self.0[3]
    }
    fn start(&self) -> TypeId {
        self.0[4]
    }
    fn stop(&self) -> TypeId {
        self.0[5]
    }
    fn interpreter_request(&self) -> TypeId {
        self.0[6]
    }
    fn channel_reply(&self) -> TypeId {
        self.0[7]
    }
    fn start_reply(&self) -> TypeId {
        self.0[8]
    }
    fn stop_reply(&self) -> TypeId {
        self.0[9]
    }
    fn sample_rate_reply(&self) -> TypeId {
        self.0[10]
    }
    fn interpreter_reply(&self) -> TypeId {
        self.0[11]
    }
    fn error(&self) -> TypeId {
        self.0[12]
    }
}

/// The function a channel generates.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum ChannelFunction {
    /// Zeros (C++ `vrpn_FunctionGenerator_function_NULL`).
    #[default]
    Null,
    /// A script for the server's interpreter.
    Script(String),
}

impl ChannelFunction {
    fn wire(&self) -> Function<'_> {
        match self {
            ChannelFunction::Null => Function::Null,
            ChannelFunction::Script(s) => Function::Script(s.as_bytes()),
        }
    }

    fn from_wire(f: &Function<'_>) -> ChannelFunction {
        match f {
            Function::Null => ChannelFunction::Null,
            Function::Script(s) => ChannelFunction::Script(String::from_utf8_lossy(s).into_owned()),
        }
    }
}

/// What went wrong in a server (C++ `FGError`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GeneratorError {
    /// No error (0).
    None,
    /// The interpreter could not run the script (1).
    Interpreter,
    /// Samples were not generated in time (2).
    TakingTooLong,
    /// A wrong number of values was generated (3).
    InvalidResultQuantity,
    /// Values out of range were generated (4).
    InvalidResultRange,
    /// Any other code a peer sent.
    Other(i32),
}

impl GeneratorError {
    /// The wire code.
    pub fn code(self) -> i32 {
        match self {
            GeneratorError::None => 0,
            GeneratorError::Interpreter => 1,
            GeneratorError::TakingTooLong => 2,
            GeneratorError::InvalidResultQuantity => 3,
            GeneratorError::InvalidResultRange => 4,
            GeneratorError::Other(c) => c,
        }
    }

    /// From the wire code.
    pub fn from_code(c: i32) -> GeneratorError {
        match c {
            0 => GeneratorError::None,
            1 => GeneratorError::Interpreter,
            2 => GeneratorError::TakingTooLong,
            3 => GeneratorError::InvalidResultQuantity,
            4 => GeneratorError::InvalidResultRange,
            c => GeneratorError::Other(c),
        }
    }
}

/// A channel's function as the server reported it.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelReply {
    /// The server's time stamp.
    pub time: TimeVal,
    /// The channel.
    pub channel: u32,
    /// Its function.
    pub function: ChannelFunction,
}

/// A reply carrying one value: whether generation started or stopped, the sample rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reply<T> {
    /// The server's time stamp.
    pub time: TimeVal,
    /// The value.
    pub value: T,
}

/// An error the server reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ErrorReply {
    /// The server's time stamp.
    pub time: TimeVal,
    /// What went wrong.
    pub error: GeneratorError,
    /// On which channel.
    pub channel: i32,
}

struct RemoteState {
    channels: RefCell<Vec<ChannelFunction>>,
    sample_rate: Cell<f32>,
    interpreter: RefCell<Option<String>>,
    channel_replies: CallbackList<ChannelReply>,
    start_replies: CallbackList<Reply<bool>>,
    stop_replies: CallbackList<Reply<bool>>,
    rate_replies: CallbackList<Reply<f32>>,
    interpreter_replies: CallbackList<Reply<String>>,
    errors: CallbackList<ErrorReply>,
}

/// Client half of a function generator (C++ `vrpn_FunctionGenerator_Remote`). Requests are
/// RELIABLE; the latest replies are kept ([`channel`](Self::channel),
/// [`sample_rate`](Self::sample_rate), [`interpreter_description`](Self::interpreter_description)).
pub struct FunctionGeneratorRemote {
    core: RemoteCore,
    ids: FunctionGeneratorIds,
    state: Rc<RemoteState>,
}

impl Deref for FunctionGeneratorRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl FunctionGeneratorRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<FunctionGeneratorRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(
        device: &str,
        conn: &Connection,
    ) -> Result<FunctionGeneratorRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, FunctionGeneratorIds::register)?;
        let state = Rc::new(RemoteState {
            channels: RefCell::new(vec![ChannelFunction::Null; MAX_CHANNELS]),
            sample_rate: Cell::new(0.0),
            interpreter: RefCell::new(None),
            channel_replies: CallbackList::default(),
            start_replies: CallbackList::default(),
            stop_replies: CallbackList::default(),
            rate_replies: CallbackList::default(),
            interpreter_replies: CallbackList::default(),
            errors: CallbackList::default(),
        });
        let s = state.clone();
        core.handle(ids.channel_reply(), move |m| {
            let Ok(c) = ChannelMessage::decode(m.payload) else {
                return;
            };
            if c.channel as usize >= MAX_CHANNELS {
                return;
            }
            let function = ChannelFunction::from_wire(&c.function);
            s.channels.borrow_mut()[c.channel as usize] = function.clone();
            s.channel_replies.call(&ChannelReply {
                time: m.time,
                channel: c.channel,
                function,
            });
        });
        for (type_id, start) in [(ids.start_reply(), true), (ids.stop_reply(), false)] {
            let s = state.clone();
            core.handle(type_id, move |m| {
                if let Ok(f) = Flag::decode(m.payload) {
                    let r = Reply {
                        time: m.time,
                        value: f.value != 0,
                    };
                    if start {
                        s.start_replies.call(&r);
                    } else {
                        s.stop_replies.call(&r);
                    }
                }
            });
        }
        let s = state.clone();
        core.handle(ids.sample_rate_reply(), move |m| {
            if let Ok(r) = SampleRate::decode(m.payload) {
                s.sample_rate.set(r.rate);
                s.rate_replies.call(&Reply {
                    time: m.time,
                    value: r.rate,
                });
            }
        });
        let s = state.clone();
        core.handle(ids.interpreter_reply(), move |m| {
            if let Ok(d) = Description::decode(m.payload) {
                let text = String::from_utf8_lossy(d.text).into_owned();
                *s.interpreter.borrow_mut() = Some(text.clone());
                s.interpreter_replies.call(&Reply {
                    time: m.time,
                    value: text,
                });
            }
        });
        let s = state.clone();
        core.handle(ids.error(), move |m| {
            if let Ok(e) = ErrorReport::decode(m.payload) {
                s.errors.call(&ErrorReply {
                    time: m.time,
                    error: GeneratorError::from_code(e.error),
                    channel: e.channel,
                });
            }
        });
        Ok(FunctionGeneratorRemote { core, ids, state })
    }

    /// Asks the server to give channel `channel` (0..128) the function `function`.
    pub fn set_channel(&self, channel: u32, function: &ChannelFunction) -> Result<(), Error> {
        check_channel(channel)?;
        let msg = ChannelMessage {
            channel,
            function: function.wire(),
        };
        if msg.encoded_len() > crate::wire::MAX_PAYLOAD {
            return Err(Error::PayloadTooLarge(msg.encoded_len()));
        }
        let mut buf = vec![0u8; msg.encoded_len()];
        msg.encode(&mut buf);
        self.core.send(self.ids.channel(), &buf)
    }

    /// Asks for channel `channel`'s function.
    pub fn request_channel(&self, channel: u32) -> Result<(), Error> {
        check_channel(channel)?;
        let mut buf = [0u8; ChannelNumber::LEN];
        ChannelNumber { channel }.encode(&mut buf);
        self.core.send(self.ids.channel_request(), &buf)
    }

    /// Asks for every channel's function (the server answers for all 128).
    pub fn request_all_channels(&self) -> Result<(), Error> {
        self.core.send(self.ids.all_channel_request(), &[])
    }

    /// Asks the server to start generating.
    pub fn request_start(&self) -> Result<(), Error> {
        self.core.send(self.ids.start(), &[])
    }

    /// Asks the server to stop generating.
    pub fn request_stop(&self) -> Result<(), Error> {
        self.core.send(self.ids.stop(), &[])
    }

    /// Asks for a sample rate (samples per second); the server replies with the rate it
    /// took.
    pub fn request_sample_rate(&self, rate: f32) -> Result<(), Error> {
        let mut buf = [0u8; SampleRate::LEN];
        SampleRate { rate }.encode(&mut buf);
        self.core.send(self.ids.sample_rate(), &buf)
    }

    /// Asks what the server's script interpreter is.
    pub fn request_interpreter_description(&self) -> Result<(), Error> {
        self.core.send(self.ids.interpreter_request(), &[])
    }

    /// The latest function reported for `channel`.
    pub fn channel(&self, channel: u32) -> Option<ChannelFunction> {
        self.state.channels.borrow().get(channel as usize).cloned()
    }

    /// The latest sample rate reported (0 before any).
    pub fn sample_rate(&self) -> f32 {
        self.state.sample_rate.get()
    }

    /// The latest interpreter description reported.
    pub fn interpreter_description(&self) -> Option<String> {
        self.state.interpreter.borrow().clone()
    }

    /// Calls `f` with each channel reply.
    pub fn on_channel_reply(&self, f: impl FnMut(&ChannelReply) + 'static) -> HandlerId {
        self.state.channel_replies.add(f)
    }

    /// Calls `f` with each start reply (true: generation started).
    pub fn on_start_reply(&self, f: impl FnMut(&Reply<bool>) + 'static) -> HandlerId {
        self.state.start_replies.add(f)
    }

    /// Calls `f` with each stop reply (true: generation stopped).
    pub fn on_stop_reply(&self, f: impl FnMut(&Reply<bool>) + 'static) -> HandlerId {
        self.state.stop_replies.add(f)
    }

    /// Calls `f` with each sample rate reply.
    pub fn on_sample_rate_reply(&self, f: impl FnMut(&Reply<f32>) + 'static) -> HandlerId {
        self.state.rate_replies.add(f)
    }

    /// Calls `f` with each interpreter description.
    pub fn on_interpreter_reply(&self, f: impl FnMut(&Reply<String>) + 'static) -> HandlerId {
        self.state.interpreter_replies.add(f)
    }

    /// Calls `f` with each error report.
    pub fn on_error(&self, f: impl FnMut(&ErrorReply) + 'static) -> HandlerId {
        self.state.errors.add(f)
    }

    /// Removes a callback an `on_*` returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        let s = &self.state;
        s.channel_replies.remove(id)
            || s.start_replies.remove(id)
            || s.stop_replies.remove(id)
            || s.rate_replies.remove(id)
            || s.interpreter_replies.remove(id)
            || s.errors.remove(id)
    }
}

fn check_channel(channel: u32) -> Result<(), Error> {
    if channel as usize >= MAX_CHANNELS {
        return Err(Error::InvalidArgument(format!(
            "channel {channel}: a function generator has channels 0..{MAX_CHANNELS}"
        )));
    }
    Ok(())
}

/// What a program does when a function generator's remote asks (C++ implements these as
/// the pure virtual methods of `vrpn_FunctionGenerator_Server`). Each method's result is
/// sent back as the reply; every method has a default that accepts the request.
pub trait FunctionGeneratorHandler {
    /// A remote sets `channel`'s function. `Err` refuses it: the error is reported to the
    /// remotes and the channel keeps its function.
    fn set_channel(
        &mut self,
        channel: u32,
        function: &ChannelFunction,
    ) -> Result<(), GeneratorError> {
        let _ = (channel, function);
        Ok(())
    }
    /// Start generating; returns whether it started.
    fn start(&mut self) -> bool {
        true
    }
    /// Stop generating; returns whether it stopped.
    fn stop(&mut self) -> bool {
        true
    }
    /// A remote asks for `requested` samples per second; returns the rate in force.
    fn set_sample_rate(&mut self, requested: f32) -> f32 {
        requested
    }
    /// Describes the script interpreter.
    fn interpreter_description(&mut self) -> String {
        String::new()
    }
}

struct ServerState {
    channels: RefCell<Vec<ChannelFunction>>,
    sample_rate: Cell<f32>,
    handler: RefCell<Box<dyn FunctionGeneratorHandler>>,
    bad: Cell<u64>,
}

/// The server half (C++ `vrpn_FunctionGenerator_Server`): decodes requests, asks its
/// [`FunctionGeneratorHandler`], keeps the channels and the sample rate, and replies.
pub struct FunctionGeneratorServer {
    conn: Connection,
    ids: FunctionGeneratorIds,
    base: BaseIds,
    state: Rc<ServerState>,
}

impl FunctionGeneratorServer {
    /// Registers `device` on `conn`, run by `handler`.
    pub fn new(
        device: &str,
        conn: &Connection,
        handler: impl FunctionGeneratorHandler + 'static,
    ) -> Result<FunctionGeneratorServer, Error> {
        let (base, ids) = base::register_server(conn, device, FunctionGeneratorIds::register)?;
        let state = Rc::new(ServerState {
            channels: RefCell::new(vec![ChannelFunction::Null; MAX_CHANNELS]),
            sample_rate: Cell::new(0.0),
            handler: RefCell::new(Box::new(handler)),
            bad: Cell::new(0),
        });
        let only = SenderFilter::Only(base.sender);
        let sender = base.sender;
        let s = state.clone();
        conn.register_handler(ids.channel(), only, move |m| {
            let c = m.connection();
            match ChannelMessage::decode(m.payload) {
                Ok(msg) if (msg.channel as usize) < MAX_CHANNELS => {
                    let f = ChannelFunction::from_wire(&msg.function);
                    let result = s.handler.borrow_mut().set_channel(msg.channel, &f);
                    match result {
                        Ok(()) => s.channels.borrow_mut()[msg.channel as usize] = f,
                        Err(e) => send_error(c, &ids, sender, e, msg.channel as i32),
                    }
                    send_channel(c, &ids, sender, &s, msg.channel);
                }
                _ => {
                    s.bad.set(s.bad.get() + 1);
                    // As C++: a channel it could not read is answered with what it has.
                    if let Ok(n) = ChannelNumber::decode(m.payload) {
                        if (n.channel as usize) < MAX_CHANNELS {
                            send_channel(c, &ids, sender, &s, n.channel);
                        }
                    }
                }
            }
        });
        let s = state.clone();
        conn.register_handler(
            ids.channel_request(),
            only,
            move |m| match ChannelNumber::decode(m.payload) {
                Ok(n) if (n.channel as usize) < MAX_CHANNELS => {
                    send_channel(m.connection(), &ids, sender, &s, n.channel)
                }
                _ => s.bad.set(s.bad.get() + 1),
            },
        );
        let s = state.clone();
        conn.register_handler(ids.all_channel_request(), only, move |m| {
            for ch in 0..MAX_CHANNELS as u32 {
                send_channel(m.connection(), &ids, sender, &s, ch);
            }
        });
        let s = state.clone();
        conn.register_handler(ids.start(), only, move |m| {
            let ok = s.handler.borrow_mut().start();
            send_flag(m.connection(), ids.start_reply(), sender, ok);
        });
        let s = state.clone();
        conn.register_handler(ids.stop(), only, move |m| {
            let ok = s.handler.borrow_mut().stop();
            send_flag(m.connection(), ids.stop_reply(), sender, ok);
        });
        let s = state.clone();
        conn.register_handler(ids.sample_rate(), only, move |m| {
            if let Ok(r) = SampleRate::decode(m.payload) {
                let rate = s.handler.borrow_mut().set_sample_rate(r.rate);
                s.sample_rate.set(rate);
            } else {
                s.bad.set(s.bad.get() + 1);
            }
            send_rate(m.connection(), &ids, sender, s.sample_rate.get());
        });
        let s = state.clone();
        conn.register_handler(ids.interpreter_request(), only, move |m| {
            let text = s.handler.borrow_mut().interpreter_description();
            let d = Description {
                text: text.as_bytes(),
            };
            let mut buf = vec![0u8; d.encoded_len()];
            d.encode(&mut buf);
            let c = m.connection();
            let _ = c.pack_message(
                c.now().wall,
                ids.interpreter_reply(),
                sender,
                &buf,
                class::RELIABLE,
            );
        });
        Ok(FunctionGeneratorServer {
            conn: conn.clone(),
            ids,
            base,
            state,
        })
    }

    /// Reports an error to the remotes (e.g. samples not generated in time).
    pub fn send_error(&self, error: GeneratorError, channel: i32) {
        send_error(&self.conn, &self.ids, self.base.sender, error, channel);
    }

    /// Sends channel `channel`'s function to the remotes.
    pub fn send_channel(&self, channel: u32) -> Result<(), Error> {
        check_channel(channel)?;
        send_channel(
            &self.conn,
            &self.ids,
            self.base.sender,
            &self.state,
            channel,
        );
        Ok(())
    }

    /// The function of `channel`.
    pub fn channel(&self, channel: u32) -> Option<ChannelFunction> {
        self.state.channels.borrow().get(channel as usize).cloned()
    }

    /// The sample rate in force.
    pub fn sample_rate(&self) -> f32 {
        self.state.sample_rate.get()
    }

    /// Requests that could not be decoded.
    pub fn bad_messages(&self) -> u64 {
        self.state.bad.get()
    }
}

fn send_channel(
    conn: &Connection,
    ids: &FunctionGeneratorIds,
    sender: crate::dispatch::SenderId,
    s: &ServerState,
    channel: u32,
) {
    let chans = s.channels.borrow();
    let msg = ChannelMessage {
        channel,
        function: chans[channel as usize].wire(),
    };
    let mut buf = vec![0u8; msg.encoded_len()];
    msg.encode(&mut buf);
    drop(chans);
    let _ = conn.pack_message(
        conn.now().wall,
        ids.channel_reply(),
        sender,
        &buf,
        class::RELIABLE,
    );
}

fn send_flag(conn: &Connection, type_id: TypeId, sender: crate::dispatch::SenderId, value: bool) {
    let mut buf = [0u8; Flag::LEN];
    Flag {
        value: i16::from(value),
    }
    .encode(&mut buf);
    let _ = conn.pack_message(conn.now().wall, type_id, sender, &buf, class::RELIABLE);
}

fn send_rate(
    conn: &Connection,
    ids: &FunctionGeneratorIds,
    sender: crate::dispatch::SenderId,
    rate: f32,
) {
    let mut buf = [0u8; SampleRate::LEN];
    SampleRate { rate }.encode(&mut buf);
    let _ = conn.pack_message(
        conn.now().wall,
        ids.sample_rate_reply(),
        sender,
        &buf,
        class::RELIABLE,
    );
}

fn send_error(
    conn: &Connection,
    ids: &FunctionGeneratorIds,
    sender: crate::dispatch::SenderId,
    error: GeneratorError,
    channel: i32,
) {
    let mut buf = [0u8; ErrorReport::LEN];
    ErrorReport {
        error: error.code(),
        channel,
    }
    .encode(&mut buf);
    let _ = conn.pack_message(conn.now().wall, ids.error(), sender, &buf, class::RELIABLE);
}
