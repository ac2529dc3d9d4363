//! The recorded C++ `button_analog_dial` server stream, played by a raw TCP peer to our
//! ButtonRemote / DialRemote / AnalogRemote on a TCP-only client: every decoded value and
//! timestamp must equal the capture's JSON truth.
//!
//! The capture carried the analog reports over UDP; the test appends those datagrams' messages
//! to the TCP stream (the message framing is the same on both channels and the ids come from
//! the same server), so they arrive after the recorded TCP messages.

use std::cell::RefCell;
use std::io::Write;
use std::net::{Ipv4Addr, TcpListener};
use std::rc::Rc;
use std::time::{Duration, Instant};

use serde_json::Value;
use vrpn::{AnalogRemote, ButtonRemote, Connection, DialRemote, Limits, TimeVal};

fn fixture(name: &str) -> Vec<u8> {
    let p = format!(
        "{}/tests/fixtures/golden/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

/// A decoded report, in a form both sides can produce.
#[derive(Clone, Debug, PartialEq)]
enum Ev {
    Change(String, TimeVal, i32, i32),
    States(String, TimeVal, Vec<i32>),
    Dial(TimeVal, i32, f64),
    Analog(TimeVal, Vec<f64>),
}

fn close(a: &Ev, b: &Ev) -> bool {
    let near = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(1.0);
    match (a, b) {
        (Ev::Dial(t1, d1, c1), Ev::Dial(t2, d2, c2)) => t1 == t2 && d1 == d2 && near(*c1, *c2),
        (Ev::Analog(t1, v1), Ev::Analog(t2, v2)) => {
            t1 == t2 && v1.len() == v2.len() && v1.iter().zip(v2).all(|(x, y)| near(*x, *y))
        }
        _ => a == b,
    }
}

fn expected_event(m: &Value) -> Option<Ev> {
    let time = TimeVal::new(m["sec"].as_i64().unwrap(), m["usec"].as_i64().unwrap());
    let p = &m["payload"];
    let sender = m["sender"].as_str().unwrap_or_default().to_string();
    let ints = |v: &Value| -> Vec<i32> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_i64().unwrap() as i32)
            .collect()
    };
    Some(match m["type"].as_str()? {
        "vrpn_Button Change" => Ev::Change(
            sender,
            time,
            p["button"].as_i64().unwrap() as i32,
            p["state"].as_i64().unwrap() as i32,
        ),
        "vrpn_Button States" => Ev::States(sender, time, ints(&p["states"])),
        "vrpn_Dial update" => Ev::Dial(
            time,
            p["dial"].as_i64().unwrap() as i32,
            p["change"].as_f64().unwrap(),
        ),
        "vrpn_Analog Channel" => Ev::Analog(
            time,
            p["channels"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect(),
        ),
        _ => return None,
    })
}

#[test]
fn button_analog_dial_stream_decodes_to_the_json_truth() {
    let exp: Value = serde_json::from_slice(&fixture("button_analog_dial.expected.json")).unwrap();
    let conn_json = &exp["connections"][0];
    let mut stream = fixture("button_analog_dial.server_to_client.bin");
    let mut expected: Vec<Ev> = conn_json["server_to_client"]["messages"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(expected_event)
        .collect();
    // Append the UDP datagrams (4-byte big-endian length, then the datagram) to the stream.
    let frames = fixture("button_analog_dial.udp_server_to_client.frames.bin");
    let mut at = 0;
    while at < frames.len() {
        let n = u32::from_be_bytes(frames[at..at + 4].try_into().unwrap()) as usize;
        stream.extend_from_slice(&frames[at + 4..at + 4 + n]);
        at += 4 + n;
    }
    for d in conn_json["udp_server_to_client"]["datagrams"]
        .as_array()
        .unwrap()
    {
        expected.extend(
            d["messages"]
                .as_array()
                .unwrap()
                .iter()
                .filter_map(expected_event),
        );
    }
    assert_eq!(expected.len(), 24 + 12 + 60 + 60);

    let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    listener.set_nonblocking(true).unwrap();
    let port = listener.local_addr().unwrap().port();
    let client = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
    let got = Rc::new(RefCell::new(Vec::new()));
    let button = ButtonRemote::on_connection("Button0", &client).unwrap();
    // The Joylin exports buttons under the analog's name.
    let joy_buttons = ButtonRemote::on_connection("Analog0", &client).unwrap();
    let dial = DialRemote::on_connection("Dial0", &client).unwrap();
    let analog = AnalogRemote::on_connection("Analog0", &client).unwrap();
    for (name, remote) in [("Button0", &button), ("Analog0", &joy_buttons)] {
        let g = got.clone();
        remote.on_change(move |c| {
            g.borrow_mut().push(Ev::Change(
                name.into(),
                c.time,
                c.button as i32,
                c.state.raw(),
            ))
        });
        let g = got.clone();
        remote.on_states(move |s| {
            g.borrow_mut().push(Ev::States(
                name.into(),
                s.time,
                s.as_slice().iter().map(|b| b.raw()).collect(),
            ))
        });
    }
    let g = got.clone();
    dial.on_update(move |d| {
        g.borrow_mut()
            .push(Ev::Dial(d.time, d.dial as i32, d.change))
    });
    let g = got.clone();
    analog.on_report(move |r| {
        g.borrow_mut()
            .push(Ev::Analog(r.time, r.channels().to_vec()))
    });

    let start = Instant::now();
    let mut sock = loop {
        client.mainloop().unwrap();
        if let Ok((s, _)) = listener.accept() {
            break s;
        }
        assert!(start.elapsed() < Duration::from_secs(5), "no connection");
        std::thread::sleep(Duration::from_micros(200));
    };
    sock.write_all(&stream).unwrap();
    while got.borrow().len() < expected.len() && start.elapsed() < Duration::from_secs(10) {
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(200));
    }
    let got = got.borrow();
    assert_eq!(got.len(), expected.len());
    for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
        assert!(close(g, e), "report {i}: got {g:?}, expected {e:?}");
    }
    assert_eq!(button.num_buttons(), 2);
    assert_eq!(analog.num_channels(), 2);
    drop(sock);
}
