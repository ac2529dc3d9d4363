//! A sound server without an audio engine: prints every request a client sends (for C++
//! `sound_client`, which asks for a server and a device name, then takes menu numbers).
//!
//! `cargo run --example sound_server -- [port] [name]` (default 3883, Sound0)

use std::time::Duration;

use vrpn::devices::sound::{SoundRequest, SoundServer};
use vrpn::{Connection, TextSeverity};

fn main() -> Result<(), vrpn::Error> {
    let mut args = std::env::args().skip(1);
    let port: u16 = args.next().and_then(|a| a.parse().ok()).unwrap_or(3883);
    let name = args.next().unwrap_or_else(|| "Sound0".into());
    let conn = Connection::server(None, port)?;
    let server = std::rc::Rc::new(SoundServer::new(&name, &conn)?);
    let s = std::rc::Rc::downgrade(&server);
    server.on_request(move |r| {
        println!("{:?}", r.request);
        if let (SoundRequest::LoadLocal { file, .. }, Some(s)) = (&r.request, s.upgrade()) {
            let _ = s.send_text(
                TextSeverity::Normal,
                &format!("no audio here: {file} not played"),
            );
        }
    });
    println!("{name} on port {port}");
    loop {
        conn.mainloop()?;
        conn.wait(Duration::from_millis(100))?;
    }
}
