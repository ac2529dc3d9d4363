//! The monitor's web side: one thread that answers HTTP requests (the page, its script, the
//! latest snapshot as JSON) and pushes every new snapshot to the open pages as server-sent
//! events. The VRPN loop stays on the main thread and only publishes snapshots here.
//!
//! The page has no authentication: anyone who reaches the port sees the devices. The
//! monitor binds 127.0.0.1 unless told otherwise.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use tiny_http::{Header, Method, Request, Response, Server, StatusCode};

/// The page and its script, built into the program (no network fetches).
const PAGE: &str = include_str!("page.html");
const SCRIPT: &str = include_str!("monitor.js");

/// Pages that may watch at once (each costs one write per snapshot).
const MAX_STREAMS: usize = 16;
/// How long the thread waits for a request before it looks for a new snapshot.
const TICK: Duration = Duration::from_millis(5);

/// The newest snapshot, numbered.
#[derive(Default)]
pub struct Latest {
    seq: u64,
    json: Arc<str>,
}

/// Where the VRPN loop publishes snapshots for the HTTP thread.
#[derive(Clone, Default)]
pub struct Feed(Arc<Mutex<Latest>>);

impl Feed {
    /// Replaces the snapshot.
    pub fn publish(&self, json: String) {
        if let Ok(mut l) = self.0.lock() {
            l.seq += 1;
            l.json = json.into();
        }
    }

    fn newer_than(&self, seq: u64) -> Option<(u64, Arc<str>)> {
        let l = self.0.lock().ok()?;
        (l.seq != seq).then(|| (l.seq, l.json.clone()))
    }

    fn current(&self) -> Arc<str> {
        self.0.lock().map(|l| l.json.clone()).unwrap_or_default()
    }
}

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("a valid header")
}

fn send(req: Request, status: u16, kind: &str, body: &str) {
    let response = Response::from_string(body)
        .with_status_code(StatusCode(status))
        .with_header(header("Content-Type", kind))
        .with_header(header("Cache-Control", "no-store"));
    let _ = req.respond(response);
}

/// Answers one request; an event-stream request becomes one of `streams`.
fn answer(req: Request, feed: &Feed, streams: &mut Vec<Box<dyn Write + Send>>) {
    if *req.method() != Method::Get && *req.method() != Method::Head {
        return send(req, 405, "text/plain", "only GET\n");
    }
    let path = req.url().split('?').next().unwrap_or("/").to_string();
    match path.as_str() {
        "/" | "/index.html" => send(req, 200, "text/html; charset=utf-8", PAGE),
        "/monitor.js" => send(req, 200, "text/javascript; charset=utf-8", SCRIPT),
        "/state.json" => send(req, 200, "application/json", &feed.current()),
        "/events" if streams.len() >= MAX_STREAMS => {
            send(req, 503, "text/plain", "too many pages open\n")
        }
        "/events" => {
            let mut w = req.into_writer();
            let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\n\
                        Cache-Control: no-store\r\nConnection: close\r\n\r\nretry: 1000\n\n";
            let first = format!("data: {}\n\n", feed.current());
            let ok = w.write_all(head.as_bytes()).is_ok()
                && w.write_all(first.as_bytes()).is_ok()
                && w.flush().is_ok();
            if ok {
                streams.push(w);
            }
        }
        _ => send(req, 404, "text/plain", "not found\n"),
    }
}

/// Serves on `server` until `stop` is set: requests as they come, and each new snapshot of
/// `feed` to every open event stream (a page that went away is dropped at its next write).
pub fn spawn(server: Server, feed: Feed, stop: Arc<AtomicBool>) -> JoinHandle<()> {
    std::thread::Builder::new()
        .name("http".into())
        .spawn(move || {
            let mut streams: Vec<Box<dyn Write + Send>> = Vec::new();
            let mut sent = 0;
            while !stop.load(Ordering::Relaxed) {
                if let Ok(Some(req)) = server.recv_timeout(TICK) {
                    answer(req, &feed, &mut streams);
                }
                let Some((seq, json)) = feed.newer_than(sent) else {
                    continue;
                };
                sent = seq;
                let event = format!("data: {json}\n\n");
                streams.retain_mut(|w| {
                    w.write_all(event.as_bytes())
                        .and_then(|()| w.flush())
                        .is_ok()
                });
            }
        })
        .expect("spawning the HTTP thread")
}
