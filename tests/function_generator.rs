//! FunctionGenerator through real sockets on 127.0.0.1: every request answered, the handler's
//! results in the replies, refused channels reported as errors, latest replies kept.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::function_generator::{
    ChannelFunction, FunctionGeneratorHandler, FunctionGeneratorRemote, FunctionGeneratorServer,
    GeneratorError,
};
use vrpn::Connection;

#[derive(Default)]
struct Log(Rc<RefCell<Vec<String>>>);

impl FunctionGeneratorHandler for Log {
    fn set_channel(&mut self, ch: u32, f: &ChannelFunction) -> Result<(), GeneratorError> {
        self.0.borrow_mut().push(format!("set {ch} {f:?}"));
        match f {
            ChannelFunction::Script(s) if s == "bad" => Err(GeneratorError::Interpreter),
            _ => Ok(()),
        }
    }
    fn start(&mut self) -> bool {
        self.0.borrow_mut().push("start".into());
        true
    }
    fn stop(&mut self) -> bool {
        self.0.borrow_mut().push("stop".into());
        false
    }
    fn set_sample_rate(&mut self, requested: f32) -> f32 {
        requested.min(48_000.0)
    }
    fn interpreter_description(&mut self) -> String {
        "test interpreter 1.0".into()
    }
}

fn run(conns: &[&Connection], done: impl Fn() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        for c in conns {
            c.mainloop().unwrap();
        }
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    false
}

#[test]
fn requests_and_replies_over_tcp() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    srv.on_notice(|_| {});
    let port = srv.local_port().unwrap();
    let calls = Rc::new(RefCell::new(Vec::new()));
    let server = FunctionGeneratorServer::new("FG0", &srv, Log(calls.clone())).unwrap();
    let fg = FunctionGeneratorRemote::new(&format!("FG0@127.0.0.1:{port}")).unwrap();
    let cli = fg.connection().clone();
    let replies = Rc::new(RefCell::new(Vec::new()));
    let r = replies.clone();
    fg.on_channel_reply(move |c| {
        r.borrow_mut()
            .push(format!("channel {} {:?}", c.channel, c.function))
    });
    let r = replies.clone();
    fg.on_start_reply(move |s| r.borrow_mut().push(format!("started {}", s.value)));
    let r = replies.clone();
    fg.on_stop_reply(move |s| r.borrow_mut().push(format!("stopped {}", s.value)));
    let r = replies.clone();
    fg.on_error(move |e| {
        r.borrow_mut()
            .push(format!("error {:?} on {}", e.error, e.channel))
    });
    assert!(run(&[&srv, &cli], || cli.connected()));

    fg.set_channel(3, &ChannelFunction::Script("sin(2*pi*t)".into()))
        .unwrap();
    fg.set_channel(4, &ChannelFunction::Script("bad".into()))
        .unwrap();
    fg.request_sample_rate(96_000.0).unwrap();
    fg.request_interpreter_description().unwrap();
    fg.request_start().unwrap();
    fg.request_stop().unwrap();
    assert!(run(&[&srv, &cli], || replies.borrow().len() >= 5
        && fg.interpreter_description().is_some()));
    assert_eq!(
        *replies.borrow(),
        [
            "channel 3 Script(\"sin(2*pi*t)\")",
            "error Interpreter on 4",
            "channel 4 Null",
            "started true",
            "stopped false"
        ]
    );
    assert_eq!(fg.sample_rate(), 48_000.0);
    assert_eq!(server.sample_rate(), 48_000.0);
    assert_eq!(
        fg.interpreter_description().as_deref(),
        Some("test interpreter 1.0")
    );
    assert_eq!(
        fg.channel(3),
        Some(ChannelFunction::Script("sin(2*pi*t)".into()))
    );
    assert_eq!(server.channel(4), Some(ChannelFunction::Null));
    assert_eq!(
        calls.borrow()[..2],
        ["set 3 Script(\"sin(2*pi*t)\")", "set 4 Script(\"bad\")"]
    );

    // All channels: one reply per channel, 128 of them.
    replies.borrow_mut().clear();
    fg.request_all_channels().unwrap();
    assert!(run(&[&srv, &cli], || replies.borrow().len() == 128));
    assert_eq!(replies.borrow()[3], "channel 3 Script(\"sin(2*pi*t)\")");
    // An asynchronous error from the server.
    server.send_error(GeneratorError::TakingTooLong, 3);
    assert!(run(&[&srv, &cli], || replies.borrow().len() == 129));
    assert_eq!(replies.borrow()[128], "error TakingTooLong on 3");
    assert!(fg.set_channel(128, &ChannelFunction::Null).is_err());
    assert!(fg.request_channel(200).is_err());
}

#[test]
fn malformed_requests_are_counted_and_answered_as_cpp_does() {
    let conn = Connection::new_loopback();
    let server = FunctionGeneratorServer::new("FG0", &conn, Log::default()).unwrap();
    let fg = FunctionGeneratorRemote::on_connection("FG0", &conn).unwrap();
    let replies = Rc::new(RefCell::new(0));
    let r = replies.clone();
    fg.on_channel_reply(move |_| *r.borrow_mut() += 1);
    let channel = conn
        .register_type("vrpn_FunctionGenerator channel")
        .unwrap();
    // Channel 2, unknown function code 9: the server answers with channel 2 as it is.
    conn.pack_message(
        conn.now().wall,
        channel,
        fg.sender(),
        &[0, 0, 0, 2, 0, 0, 0, 9],
        vrpn::ServiceClass::RELIABLE,
    )
    .unwrap();
    assert_eq!(server.bad_messages(), 1);
    assert_eq!(*replies.borrow(), 1);
    assert_eq!(fg.channel(2), Some(ChannelFunction::Null));
}
