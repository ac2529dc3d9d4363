//! Fuzz target bodies, shared by the cargo-fuzz crate in `fuzz/` and by the plain test
//! `tests/fuzz_corpus.rs` that replays the corpora and deterministic mutations in CI.
//!
//! Every function here takes arbitrary bytes and must return without panicking. None of them
//! is part of the public API; they exist only so both runners exercise identical code.

use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpStream};
use std::time::{Duration, Instant};

use crate::log::names::NameTable;
use crate::log::reader::LogReader;
use crate::wire::payload::{
    analog, analog_output, button, clock, dial, force, poser, text as text_payload, tracker,
};
use crate::wire::{self, lob, system, Cookie, DatagramMessages, StreamDecoder, COOKIE_LEN};
use crate::{Connection, Limits};

/// Runs every payload decoder of `crate::wire::payload` (and the system decoders) over `p`.
/// Results are discarded; only "no panic" matters.
pub fn all_payload_decoders(p: &[u8]) {
    macro_rules! each {
        ($($t:path),* $(,)?) => { $( let _ = <$t>::decode(p); )* };
    }
    each!(
        tracker::PosQuat,
        tracker::Velocity,
        tracker::Acceleration,
        tracker::ToRoom,
        tracker::UnitToSensor,
        tracker::Workspace,
        tracker::UpdateRate,
        analog::Channels,
        analog_output::ChangeRequest,
        analog_output::NumChannelsReport,
        analog_output::ChangeChannelsRequest,
        button::Change,
        button::Admin,
        button::Alert,
        button::States,
        dial::Update,
        force::Force,
        force::Scp,
        force::ForceError,
        force::Plane,
        force::Plane2,
        force::ForceField,
        force::AddObject,
        force::ObjectId,
        force::ObjectVec3,
        force::ObjectOrientation,
        force::IndexedVec3,
        force::SetTriangle,
        force::RemoveTriangle,
        force::UpdateTrimeshChanges,
        force::TransformTrimesh,
        force::SetTrimeshType,
        force::Origin,
        force::HapticScale,
        force::SetObjectIsTouchable,
        force::ConstraintInt,
        force::ConstraintVec3,
        force::ConstraintKSpring,
        poser::PoseRequest,
        poser::VelocityRequest,
        clock::Query,
        clock::Reply,
    );
    if let Ok(c) = analog::Channels::decode(p) {
        let _ = c.as_slice().len();
    }
    let mut out = [0.0f64; 8];
    let _ = analog::decode_channels_into(p, &mut out);
    let mut big = [0.0f64; 256];
    let _ = analog::decode_channels_into(p, &mut big);
    if let Ok(c) = analog::Channels::decode(p) {
        for i in 0..c.as_slice().len() + 2 {
            let _ = analog::Channels::peek(p, i);
        }
    }
    if let Ok(s) = button::States::decode(p) {
        let _ = s.as_slice().len();
    }
    if let Ok(e) = force::CustomEffect::decode(p) {
        let _: f32 = e.params().sum();
        let _ = e.param(e.len());
    }
    if let Ok(t) = text_payload::TextMessage::decode(p) {
        let _ = t.as_str();
    }
    let _ = system::decode_description(p);
    let _ = system::decode_udp_description(p);
    let _ = system::decode_log_description(p);
}

/// Decodes one message: system payloads by type, user payloads with every decoder.
fn one_message(h: &wire::Header, payload: &[u8]) {
    match h.type_id {
        system::SENDER_DESCRIPTION | system::TYPE_DESCRIPTION => {
            let _ = system::decode_description(payload);
        }
        system::UDP_DESCRIPTION => {
            let _ = system::decode_udp_description(payload);
        }
        system::LOG_DESCRIPTION => {
            let _ = system::decode_log_description(payload);
        }
        _ => all_payload_decoders(payload),
    }
}

/// TCP stream decoding over arbitrary split reads: the first byte seeds the read sizes, the
/// rest is the stream (a 24-byte cookie, then messages).
pub fn wire_stream(data: &[u8]) {
    let Some((&seed, stream)) = data.split_first() else {
        return;
    };
    let mut dec = StreamDecoder::with_capacity(0);
    let mut rng = u32::from(seed) | 0x100;
    let mut at = 0;
    let mut cookie_done = false;
    while at < stream.len() {
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        let chunk = 1 + (rng as usize % 4096);
        let end = (at + chunk).min(stream.len());
        let taken = dec.feed(&stream[at..end]);
        at += taken;
        if !cookie_done {
            if let Some(c) = dec.take_exact(COOKIE_LEN) {
                if let Ok(cookie) = Cookie::parse(c) {
                    let _ = cookie.check();
                    let _ = cookie.version();
                    let _ = cookie.minor_differs();
                }
                cookie_done = true;
            }
        }
        if cookie_done {
            loop {
                match dec.next_message() {
                    Some(Ok((h, p))) => one_message(&h, p),
                    Some(Err(_)) => return,
                    None => break,
                }
            }
        }
        if taken == 0 {
            // Buffer full and nothing decodable: a framing error would have returned above.
            return;
        }
    }
}

/// One UDP datagram: message walk plus the connection-request parser.
pub fn wire_datagram(data: &[u8]) {
    for m in DatagramMessages::new(data) {
        match m {
            Ok((h, p)) => one_message(&h, p),
            Err(_) => break,
        }
    }
    if let Ok(r) = lob::parse_request(data) {
        let _ = r.host.len();
    }
}

/// A log file image: cookie check, every entry, the name tables, every payload decoder.
pub fn log_reader(data: &[u8]) {
    let Ok(reader) = LogReader::from_bytes(data.to_vec(), "fuzz.vrpn") else {
        return;
    };
    let mut names = NameTable::new();
    let mut entries = reader.entries();
    while let Some(e) = entries.next_entry() {
        let Ok(entry) = e else {
            break;
        };
        let _ = names.observe(&entry);
        let _ = names.sender_name(entry.sender());
        let _ = names.type_name(entry.type_id());
        if entry.is_system() {
            if let Some(s) = entry.system() {
                let _ = s.is_ok();
            }
        } else {
            all_payload_decoders(entry.payload);
        }
        let _ = entry.end_offset();
    }
    let _ = names.senders().count() + names.types().count();
}

/// Configuration text: strict and lenient server config parsers and the tracker config parser.
pub fn config(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let _ = crate::server::config::parse_str(&text, "fuzz.cfg");
    let _ = crate::server::config::parse_str_lenient(&text, "fuzz.cfg");
    let name = text.split_whitespace().next().unwrap_or("Tracker0");
    let _ = crate::server::config::parse_tracker_cfg(&text, "vrpn_Tracker.cfg", name);
    let _ = crate::server::config::parse_tracker_cfg(&text, "vrpn_Tracker.cfg", "Tracker0");
}

/// A real server connection on 127.0.0.1 port 0 fed `data` by a raw TCP peer. If the first byte
/// is even, a valid cookie precedes the rest so the fuzzer reaches the message layer quickly.
/// The server's mainloop runs a bounded number of times; it must never panic.
pub fn handshake(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let limits = Limits {
        max_pending_output: 256 * 1024,
        ..Limits::default()
    };
    let Ok(server) = Connection::server_with_limits(Some(Ipv4Addr::LOCALHOST), 0, limits) else {
        return;
    };
    server.on_notice(|_| {});
    let _ = server.register_sender("Tracker0");
    let _ = server.register_type("vrpn_Tracker Pos_Quat");
    let Some(port) = server.local_port() else {
        return;
    };
    let Ok(mut peer) = TcpStream::connect((Ipv4Addr::LOCALHOST, port)) else {
        return;
    };
    let _ = peer.set_nodelay(true);
    let mut bytes = Vec::with_capacity(rest.len() + COOKIE_LEN);
    if mode & 1 == 0 {
        bytes.extend_from_slice(&Cookie::ours(0).to_bytes());
    }
    bytes.extend_from_slice(rest);
    let _ = peer.set_nonblocking(true);
    let deadline = Instant::now() + Duration::from_secs(2);
    let mut sent = 0;
    let mut sink = [0u8; 16 * 1024];
    let mut quiet = 0;
    for _ in 0..2000 {
        if Instant::now() > deadline {
            break;
        }
        if sent < bytes.len() {
            match peer.write(&bytes[sent..]) {
                Ok(n) => sent += n,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(_) => sent = bytes.len(),
            }
        }
        let _ = server.mainloop();
        let _ = server.wait(Duration::from_millis(1));
        let _ = server.mainloop();
        let closed = match peer.read(&mut sink) {
            Ok(0) => true,
            Ok(_) => false,
            Err(e) => e.kind() != std::io::ErrorKind::WouldBlock,
        };
        if closed {
            break;
        }
        if sent >= bytes.len() {
            quiet += 1;
            if quiet > 3 {
                break;
            }
        }
    }
    // Also send something while the peer may still be there.
    let t = server.register_type("fuzz type").ok();
    if let Some(t) = t {
        let _ = server.pack_message(
            crate::TimeVal::now(),
            t,
            crate::SenderId(0),
            &[1, 2, 3],
            wire::class::RELIABLE,
        );
    }
    let _ = server.mainloop();
}
