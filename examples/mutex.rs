//! A mutex server, remote or peer driven from standard input, as C++ `test_mutexServer`,
//! `test_mutex` and `test_peerMutex` are.
//!
//! - `cargo run --example mutex -- server NAME PORT`
//! - `cargo run --example mutex -- remote NAME@HOST:PORT` then lines `req`, `rel`, `?`, `quit`
//! - `cargo run --example mutex -- peer NAME PORT` then lines `add HOST:PORT`, `req`, `rel`,
//!   `?`, `quit`

use std::io::BufRead;
use std::sync::mpsc;
use std::time::Duration;

use vrpn::devices::mutex::{MutexRemote, MutexServer};
use vrpn::devices::peer_mutex::PeerMutex;
use vrpn::Connection;

/// Lines of standard input, read on a thread so the loop keeps running.
fn stdin_lines() -> mpsc::Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

fn main() -> Result<(), vrpn::Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize| args.get(i).map(String::as_str).unwrap_or("");
    match arg(0) {
        "server" => {
            let conn = Connection::server(None, arg(2).parse().unwrap_or(3883))?;
            let server = MutexServer::new(arg(1), &conn)?;
            let mut held = None;
            loop {
                conn.mainloop()?;
                if server.holder() != held {
                    held = server.holder();
                    println!("holder: {held:?}");
                }
                conn.wait(Duration::from_millis(50))?;
            }
        }
        "remote" => {
            let m = MutexRemote::new(arg(1))?;
            m.on_granted(|| println!("callback - Mutex granted."));
            m.on_denied(|| println!("callback - Mutex denied."));
            m.on_released(|| println!("callback - Mutex released."));
            let lines = stdin_lines();
            loop {
                m.mainloop()?;
                match lines.try_recv().as_deref() {
                    Ok(l) if l.starts_with("req") => m.request()?,
                    Ok(l) if l.starts_with("rel") => m.release()?,
                    Ok(l) if l.starts_with('?') => {
                        println!("state {:?}, index {:?}", m.state(), m.index())
                    }
                    Ok(l) if l.starts_with("quit") => return Ok(()),
                    Err(mpsc::TryRecvError::Disconnected) => return Ok(()),
                    _ => {}
                }
                m.connection().wait(Duration::from_millis(20))?;
            }
        }
        "peer" => {
            let p = PeerMutex::new(arg(1), arg(2).parse().unwrap_or(0), None)?;
            let (ip, port) = p.identity();
            println!("peer {} at {ip}:{port}", arg(1));
            p.on_granted(|| println!("callback - Mutex granted."));
            p.on_denied(|| println!("callback - Mutex denied."));
            p.on_released(|| println!("callback - Mutex released."));
            let lines = stdin_lines();
            loop {
                p.mainloop()?;
                match lines.try_recv().as_deref() {
                    Ok(l) if l.starts_with("add") => p.add_peer(l[3..].trim())?,
                    Ok(l) if l.starts_with("req") => {
                        if let Err(e) = p.request() {
                            println!("request: {e}");
                        }
                    }
                    Ok(l) if l.starts_with("rel") => p.release(),
                    Ok(l) if l.starts_with('?') => {
                        println!("state {:?}, {} peer(s)", p.state(), p.num_peers())
                    }
                    Ok(l) if l.starts_with("quit") => return Ok(()),
                    Err(mpsc::TryRecvError::Disconnected) => return Ok(()),
                    _ => {}
                }
                p.connection().wait(Duration::from_millis(20))?;
            }
        }
        _ => {
            eprintln!("usage: mutex server NAME PORT | remote NAME@HOST:PORT | peer NAME PORT");
            std::process::exit(2);
        }
    }
}
