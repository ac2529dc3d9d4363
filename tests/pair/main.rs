//! The protocol layer on virtual time: a client and a server session joined in memory, driven
//! through handshakes, time-outs, drops, reconnects and a faulty link. Every test runs in
//! milliseconds of real time and is deterministic for its seed.

mod harness;

use std::time::Duration;

use harness::{Faults, Pair, Seen, Who, DEVICE, PING, PONG, REPORT, TEXT};
use vrpn::proto::{ConnectionEvent, ConnectionState, Limits};
use vrpn::wire::{class, Cookie};

fn secs(s: f64) -> Duration {
    Duration::from_secs_f64(s)
}

fn limits() -> Limits {
    Limits::default()
}

#[test]
fn handshake_over_the_udp_path_opens_both_channels() {
    // Without clock sync, like a C++ peer (which never answers a clock query): the hold after
    // the descriptions runs its whole time.
    let no_clock = Limits {
        clock_sync: None,
        ..limits()
    };
    let mut p = Pair::new(false, no_clock, 1);
    p.faults.latency = Duration::from_micros(200);
    let start = p.now.mono;
    assert!(p.run_until(secs(1.0), Pair::connected));
    // Both handshakes complete within a round trip (each side counts the other as connected
    // once it has the other's cookie); the descriptions follow within the next latency.
    assert!(p.now.mono - start < Duration::from_millis(2));
    p.run_for(secs(0.01));
    assert_eq!(p.client.session.state(), ConnectionState::Connected);
    assert_eq!(p.server.session.state(), ConnectionState::Connected);
    // The call-back went to the address the request came from, once.
    assert_eq!(p.connections, 1);
    assert_eq!(p.requests_sent.len(), 1);
    // Each side learned the other's device and offers it.
    assert!(p
        .client
        .session
        .peer_sender_names()
        .contains(&DEVICE.to_string()));
    assert!(p
        .server
        .session
        .peer_sender_names()
        .contains(&DEVICE.to_string()));
    for who in [Who::Client, Who::Server] {
        assert_eq!(p.events(who, ConnectionEvent::GotFirstConnection).len(), 1);
        assert_eq!(p.events(who, ConnectionEvent::GotConnection).len(), 1);
    }
    // Right after the handshake LOW_LATENCY keeps to TCP (the client may not have read the
    // descriptions yet: a C++ peer reads UDP first and drops messages of types it does not
    // know); once Limits::udp_after_descriptions has passed it goes over UDP. RELIABLE is
    // always TCP, and everything arrives.
    let sent_before = p.datagrams_sent;
    for i in 0..5u8 {
        p.send(Who::Server, REPORT, &[i; 16], class::LOW_LATENCY);
    }
    p.run_for(secs(0.01));
    assert_eq!(
        p.datagrams_sent, sent_before,
        "reports went by UDP right behind the descriptions"
    );
    p.run_for(limits().udp_after_descriptions);
    let sent_before = p.datagrams_sent;
    for i in 5..10u8 {
        p.send(Who::Server, REPORT, &[i; 16], class::LOW_LATENCY);
    }
    p.send(Who::Server, TEXT, b"reliable", class::RELIABLE);
    p.run_for(secs(0.01));
    assert!(
        p.datagrams_sent > sent_before,
        "no datagram carried the reports"
    );
    let reports: Vec<Vec<u8>> = p
        .received(Who::Client, REPORT)
        .into_iter()
        .map(|s| match s {
            Seen::Message { payload, .. } => payload.clone(),
            _ => unreachable!(),
        })
        .collect();
    assert_eq!(reports, (0..10u8).map(|i| vec![i; 16]).collect::<Vec<_>>());
    assert_eq!(p.received(Who::Client, TEXT).len(), 1);
}

/// Two peers of this crate (clock sync on): a clock query sent during the hold goes by TCP
/// behind the descriptions, and its answer shows the peer has read them, so unreliable
/// messages take UDP long before `Limits::udp_after_descriptions` has passed.
#[test]
fn a_clock_reply_ends_the_hold_after_the_descriptions_early() {
    let mut p = Pair::new(false, limits(), 11);
    p.faults.latency = Duration::from_micros(200);
    assert!(p.run_until(secs(1.0), Pair::connected));
    let connected = p.now.mono;
    // One report every 2 ms until one goes out in a datagram. A clock query leaves at most a
    // quick-round spacing (20 ms) after the hold began and is answered within a round trip.
    let mut first_by_udp = None;
    for i in 0..100u8 {
        let payload = [0x80 | i; 16];
        p.send(Who::Server, REPORT, &payload, class::LOW_LATENCY);
        p.run_for(secs(0.002));
        let by_udp = p
            .datagram_log
            .iter()
            .any(|(who, dg)| *who == Who::Server && dg.windows(16).any(|w| w == payload));
        if by_udp {
            first_by_udp = Some((i, p.now.mono - connected));
            break;
        }
    }
    let (n, after) = first_by_udp.expect("every report kept to TCP");
    assert!(
        n > 0,
        "the first report went by UDP right behind the descriptions"
    );
    assert!(
        after < Duration::from_millis(60),
        "reports took UDP only after {after:?} (the timed hold is {:?})",
        limits().udp_after_descriptions
    );
    // Nothing lost or reordered by the change of channel.
    let reports: Vec<Vec<u8>> = p
        .received(Who::Client, REPORT)
        .into_iter()
        .map(|s| match s {
            Seen::Message { payload, .. } => payload.clone(),
            _ => unreachable!(),
        })
        .collect();
    assert_eq!(
        reports,
        (0..=n).map(|k| vec![0x80 | k; 16]).collect::<Vec<_>>()
    );
}

#[test]
fn handshake_over_the_tcp_only_path() {
    let mut p = Pair::new(true, limits(), 2);
    p.faults.latency = Duration::from_millis(1);
    p.faults.tcp_split = true;
    assert!(p.run_until(secs(1.0), Pair::connected));
    assert!(p.requests_sent.is_empty());
    let sent_before = p.datagrams_sent;
    for i in 0..5u8 {
        p.send(Who::Server, REPORT, &[i; 40], class::LOW_LATENCY);
    }
    p.run_for(secs(0.05));
    assert_eq!(
        p.datagrams_sent, sent_before,
        "the TCP-only path never uses UDP"
    );
    assert_eq!(p.received(Who::Client, REPORT).len(), 5);
}

#[test]
fn ping_cycle_warns_at_three_and_errs_at_ten_seconds() {
    let mut p = Pair::new(false, limits(), 3);
    p.faults.no_pongs = true;
    assert!(p.run_until(secs(1.0), Pair::connected));
    let connected_at = p.now.mono;
    p.run_for(secs(12.0));
    let texts: Vec<(f64, u32, u32)> = p
        .client
        .seen
        .iter()
        .filter_map(|s| match s {
            Seen::PingText(at, sev, level) => {
                Some((at.duration_since(connected_at).as_secs_f64(), *sev, *level))
            }
            _ => None,
        })
        .collect();
    // Warnings from 3 s, each second, then the error at 10 s.
    assert_eq!(texts.first().map(|t| (t.1, t.2)), Some((1, 3)), "{texts:?}");
    assert!((texts[0].0 - 3.0).abs() < 0.01, "{texts:?}");
    let error = texts.iter().find(|t| t.1 == 2).expect("an error text");
    assert!((error.0 - 10.0).abs() < 0.01 && error.2 == 10, "{texts:?}");
    // The texts went over the connection: the server heard them.
    assert!(p.received(Who::Server, TEXT).len() >= 8);
    // Pings went out once a second.
    let pings = p.received(Who::Server, PING).len();
    assert!((12..=14).contains(&pings), "{pings} pings");
    assert!(p.ping.waiting_for_pong());
}

#[test]
fn an_answered_ping_ends_the_cycle_without_warnings() {
    let mut p = Pair::new(false, limits(), 4);
    p.faults.latency = Duration::from_millis(5);
    assert!(p.run_until(secs(1.0), Pair::connected));
    p.run_for(secs(15.0));
    assert!(!p.ping.waiting_for_pong());
    assert_eq!(p.received(Who::Client, PONG).len(), 1);
    assert!(!p
        .client
        .seen
        .iter()
        .any(|s| matches!(s, Seen::PingText(..))));
}

#[test]
fn drop_and_reconnect_with_the_one_second_retry() {
    let mut p = Pair::new(false, limits(), 5);
    p.faults.latency = Duration::from_micros(300);
    assert!(p.run_until(secs(1.0), Pair::connected));
    p.run_for(secs(2.0));
    // The server goes down: its side of the connection breaks and it answers nothing.
    p.faults.server_down = true;
    p.break_connection(Who::Server);
    let down_at = p.now.mono;
    assert!(p.run_until(secs(1.0), |p| p.client.session.connected_peers() == 0));
    assert_eq!(p.client.session.state(), ConnectionState::Reconnecting);
    p.run_for(secs(3.5));
    // Requests while the server is down: at once (the connection had lasted), then every
    // second, on the dot.
    let tries: Vec<f64> = p
        .requests_sent
        .iter()
        .filter(|t| **t >= down_at)
        .map(|t| t.duration_since(down_at).as_secs_f64())
        .collect();
    assert_eq!(tries.len(), 4, "{tries:?}");
    for (k, t) in tries.iter().enumerate() {
        assert!((t - k as f64).abs() < 0.01, "{tries:?}");
    }
    // Back up: the next request reconnects; no false "no response" after the reconnect.
    // The outage itself is reported (3 s without an answer), as C++ does.
    assert!(p
        .client
        .seen
        .iter()
        .any(|s| matches!(s, Seen::PingText(_, 1, 3))));
    p.faults.server_down = false;
    assert!(p.run_until(secs(2.0), Pair::connected));
    let back_at = p.now.mono;
    p.run_for(secs(5.0));
    assert!(!p
        .client
        .seen
        .iter()
        .any(|s| matches!(s, Seen::PingText(at, ..) if *at >= back_at)));
    assert_eq!(
        p.events(Who::Client, ConnectionEvent::GotConnection).len(),
        2
    );
    assert_eq!(
        p.events(Who::Client, ConnectionEvent::DroppedConnection)
            .len(),
        1
    );
    assert_eq!(p.client.session.state(), ConnectionState::Connected);
}

#[test]
fn a_stalled_reader_is_shed_then_dropped() {
    let small = Limits {
        max_pending_output: 64 * 1024,
        ..Limits::default()
    };
    let mut p = Pair::new(true, small, 6);
    assert!(p.run_until(secs(1.0), Pair::connected));
    p.faults.stall = Some(Who::Client);
    // Unreliable reports (TCP-only path, so they queue on TCP) and some reliable traffic.
    for i in 0..20_000u32 {
        let class = if i % 10 == 0 {
            class::RELIABLE
        } else {
            class::LOW_LATENCY
        };
        p.send(Who::Server, REPORT, &i.to_be_bytes(), class);
        if i % 100 == 0 {
            p.run_for(secs(0.001));
        }
        if p.server.session.connected_peers() == 0 {
            break;
        }
    }
    p.run_for(secs(0.1));
    let notices = p.notices(Who::Server).join("\n");
    assert!(notices.contains("is falling behind"), "{notices}");
    assert!(
        notices.contains("is not reading: more than 65536 bytes"),
        "{notices}"
    );
    assert_eq!(p.server.session.connected_peers(), 0);
}

#[test]
fn a_peer_with_a_bad_cookie_is_dropped_and_the_server_goes_on() {
    let mut p = Pair::new(false, limits(), 7);
    let raw = p
        .raw_peer_to_server(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
        .unwrap();
    p.run_for(secs(0.01));
    assert!(p.server.session.peer_at(raw.slot).is_none());
    let notices = p.notices(Who::Server).join("\n");
    assert!(notices.contains("bad cookie \"GET / HTTP/1.1"), "{notices}");
    // A real client still connects.
    assert!(p.run_until(secs(2.0), Pair::connected));
}

#[test]
fn a_silent_peer_is_dropped_at_the_handshake_deadline() {
    let mut p = Pair::new(false, limits(), 8);
    let raw = p.raw_peer_to_server(b"").unwrap();
    p.run_for(secs(4.9));
    assert!(p.server.session.peer_at(raw.slot).is_some());
    p.run_for(secs(0.2));
    assert!(p.server.session.peer_at(raw.slot).is_none());
    let notices = p.notices(Who::Server).join("\n");
    assert!(notices.contains("no VRPN greeting within 5s"), "{notices}");
}

#[test]
fn a_half_cookie_waits_and_a_full_one_connects() {
    let mut p = Pair::new(false, limits(), 9);
    let cookie = Cookie::ours(0).to_bytes();
    let raw = p.raw_peer_to_server(&cookie[..10]).unwrap();
    let label = "10.0.0.9:40009".to_string();
    let is_connected = |p: &Pair| {
        p.server
            .session
            .peer_descriptions()
            .iter()
            .any(|(who, _)| *who == label)
    };
    p.run_for(secs(1.0));
    assert!(!is_connected(&p));
    p.server.session.handle_tcp(raw, &cookie[10..]);
    p.run_for(secs(0.01));
    assert!(is_connected(&p));
}

/// The UDP channel under loss, duplication, reordering and truncation: nothing crashes, a
/// truncated datagram is discarded with a notice, every delivered report is one that was sent,
/// and the counts add up.
#[test]
fn udp_channel_under_loss_reorder_duplicate_and_truncation() {
    for seed in 10..14 {
        let mut p = Pair::new(false, limits(), seed);
        assert!(p.run_until(secs(1.0), Pair::connected));
        p.faults = Faults {
            latency: Duration::from_micros(500),
            udp_jitter: Duration::from_millis(3),
            udp_loss: 0.2,
            udp_duplicate: 0.1,
            udp_truncate: 0.05,
            ..Faults::default()
        };
        let n = 2000u32;
        for i in 0..n {
            // One report per datagram (each step flushes).
            p.send(Who::Server, REPORT, &i.to_be_bytes(), class::LOW_LATENCY);
            p.run_for(secs(0.001));
        }
        p.run_for(secs(0.1));
        let got: Vec<u32> = p
            .received(Who::Client, REPORT)
            .into_iter()
            .map(|s| match s {
                Seen::Message { payload, .. } => {
                    u32::from_be_bytes(payload[..4].try_into().unwrap())
                }
                _ => unreachable!(),
            })
            .collect();
        assert!(got.iter().all(|&i| i < n), "a report that was never sent");
        // Loss 20%, duplicates 10%, truncation 5%: roughly 0.8 × 1.1 × 0.95 of n arrive.
        let ratio = got.len() as f64 / n as f64;
        assert!((0.7..0.95).contains(&ratio), "seed {seed}: {ratio}");
        let reordered = got.windows(2).filter(|w| w[1] < w[0]).count();
        assert!(reordered > 0, "jitter reorders datagrams");
        let dups = got.len() - {
            let mut u = got.clone();
            u.sort_unstable();
            u.dedup();
            u.len()
        };
        assert!(
            dups > 0,
            "duplicates are delivered twice (UDP has no de-duplication)"
        );
        let notices = p.notices(Who::Client).join("\n");
        assert!(
            notices.contains("discarded a malformed UDP datagram"),
            "{notices}"
        );
        assert_eq!(
            p.client.session.connected_peers(),
            1,
            "nobody is dropped for it"
        );
    }
}

/// The same seed gives the same run, to the notice text and the microsecond.
#[test]
fn runs_are_deterministic() {
    let trace = |seed| {
        let mut p = Pair::new(false, limits(), seed);
        p.faults.udp_loss = 0.3;
        p.faults.udp_jitter = Duration::from_millis(2);
        p.faults.tcp_split = true;
        p.run_until(secs(1.0), Pair::connected);
        let t0 = p.now.mono;
        for i in 0..200u32 {
            p.send(Who::Server, REPORT, &i.to_be_bytes(), class::LOW_LATENCY);
            p.run_for(secs(0.002));
        }
        p.client
            .seen
            .iter()
            .map(|s| match s {
                Seen::Message { at, payload, .. } => {
                    format!("{:?} {payload:?}", at.saturating_duration_since(t0))
                }
                other => format!("{other:?}").replace(char::is_numeric, ""),
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(trace(42), trace(42));
    assert_ne!(trace(42), trace(43));
}

/// A port that answers with something else than VRPN and closes: one connection per retry
/// interval (not a storm), and one explanation.
#[test]
fn an_impostor_server_costs_one_connection_per_interval_and_one_notice() {
    let mut p = Pair::new(true, limits(), 15);
    p.faults.latency = Duration::from_micros(100);
    p.faults.impostor = Some(b"HTTP/1.1 400 Bad Request\r\n\r\n");
    p.run_for(secs(10.0));
    assert!(
        (10..=11).contains(&p.connections),
        "{} connections",
        p.connections
    );
    let notices = p.notices(Who::Client);
    let bad: Vec<&String> = notices
        .iter()
        .filter(|n| n.contains("not with a VRPN greeting"))
        .collect();
    assert_eq!(bad.len(), 1, "{notices:?}");
    assert!(bad[0].contains("HTTP/1.1 400"), "{}", bad[0]);
    assert_eq!(p.client.session.state(), ConnectionState::Connecting);
}

/// A port that accepts and never answers: the client gives up on it after the greeting
/// time-out, says why, and keeps trying on schedule.
#[test]
fn a_silent_server_is_explained_and_retried() {
    let mut p = Pair::new(true, limits(), 16);
    p.faults.impostor = Some(b"");
    p.run_for(secs(5.5));
    let notices = p.notices(Who::Client).join("\n");
    assert!(
        notices.contains("sent no VRPN greeting within 5s"),
        "{notices}"
    );
    p.run_for(secs(6.5));
    // Attempt at 0 s, given up at 5 s, retried at 6 s, given up at 11 s, retried at 12 s.
    assert_eq!(p.connections, 3);
    assert_eq!(
        p.notices(Who::Client)
            .iter()
            .filter(|n| n.contains("no VRPN greeting"))
            .count(),
        1
    );
}

/// One peer describing thousands of names cannot lock others out: its names are refused
/// past the table's room without dropping anyone, and freed when it leaves.
#[test]
fn a_name_flood_from_one_peer_locks_nobody_out() {
    use vrpn::wire::{header, system};
    let mut p = Pair::new(false, limits(), 17);
    let mut flood = Cookie::ours(0).to_bytes().to_vec();
    let mut payload = [0u8; 64];
    for i in 0..1990 {
        let name = format!("junk type {i}");
        let n = system::encode_description(&mut payload, &name);
        let h = header::Header {
            payload_len: n,
            time: vrpn::TimeVal::ZERO,
            sender: i,
            type_id: system::TYPE_DESCRIPTION,
            seq: 0,
        };
        let mut buf = vec![0u8; h.wire_size()];
        header::encode_message(&mut buf, &h, &payload[..n]);
        flood.extend_from_slice(&buf);
    }
    let raw = p.raw_peer_to_server(&flood[..24]).unwrap();
    let mut fed = 24;
    while fed < flood.len() {
        p.run_for(secs(0.001));
        fed += p.server.session.handle_tcp(raw, &flood[fed..]);
    }
    p.run_for(secs(0.01));
    // The flooder is still connected (it broke no rule), and so is a real client that
    // describes a type the server never heard of.
    assert!(p.server.session.peer_at(raw.slot).is_some());
    let now = p.now;
    p.client
        .session
        .register(now, false, b"client-only type")
        .unwrap();
    assert!(p.run_until(secs(2.0), |p| p.client.session.connected_peers() == 1));
    assert_eq!(p.server.session.connected_peers(), 2);
    p.run_for(secs(0.1));
    for i in 0..20u8 {
        p.send(Who::Server, REPORT, &[i; 8], class::LOW_LATENCY);
    }
    p.run_for(secs(0.01));
    assert_eq!(p.received(Who::Client, REPORT).len(), 20);
    let notices = p.notices(Who::Server).join("\n");
    assert!(notices.contains("no room for type name"), "{notices}");
}
