//! The shared `int32` "a" of C++ `testSharedObjectServer` and `testSharedObject`: both sides
//! serialized, the server denying remote changes; the remote sets 3 and -3, takes the
//! serializer role, and sets them again.
//!
//! - `cargo run --example shared_object -- server PORT`
//! - `cargo run --example shared_object -- remote HOST:PORT`

use std::time::{Duration, Instant};

use vrpn::devices::shared_object::{SerializerPolicy, SharedInt32, SharedMode};
use vrpn::Connection;

/// Services the connection for a quarter of a second (C++ `mainloop(&qsec)`).
fn quarter(conn: &Connection) -> Result<(), vrpn::Error> {
    let end = Instant::now() + Duration::from_millis(250);
    while Instant::now() < end {
        conn.mainloop()?;
        conn.wait(Duration::from_millis(10))?;
    }
    Ok(())
}

fn main() -> Result<(), vrpn::Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize| args.get(i).map(String::as_str).unwrap_or("");
    match arg(0) {
        "server" => {
            let conn = Connection::server(None, arg(1).parse().unwrap_or(3883))?;
            let a = SharedInt32::server("a", &conn, 0, SharedMode::SERIALIZED)?;
            a.set_policy(SerializerPolicy::DenyRemote);
            a.on_change(|c| println!("Server a set to {}.", c.value));
            conn.mainloop()?;
            println!("a = {}.", a.value());
            a.set(3)?;
            println!("a = {}.", a.value());
            a.set(-3)?;
            println!("a = {}.", a.value());
            loop {
                conn.mainloop()?;
                conn.wait(Duration::from_millis(50))?;
            }
        }
        "remote" => {
            let conn = Connection::open(arg(1))?;
            let a = SharedInt32::remote("a", &conn, 0, SharedMode::SERIALIZED)?;
            a.on_change(|c| println!("Remote a set to {}.", c.value));
            quarter(&conn)?;
            println!("a = {}.", a.value());
            quarter(&conn)?;
            a.set(3)?;
            quarter(&conn)?;
            println!("a = {}.", a.value());
            quarter(&conn)?;
            a.set(-3)?;
            quarter(&conn)?;
            println!("a = {}.", a.value());
            a.become_serializer();
            quarter(&conn)?;
            quarter(&conn)?;
            println!("a = {}. (serializer: {})", a.value(), a.is_serializer());
            quarter(&conn)?;
            a.set(3)?;
            quarter(&conn)?;
            println!("a = {}.", a.value());
            quarter(&conn)?;
            a.set(-3)?;
            quarter(&conn)?;
            println!("a = {}.", a.value());
            quarter(&conn)?;
            Ok(())
        }
        _ => {
            eprintln!("usage: shared_object server PORT | remote HOST:PORT");
            std::process::exit(2);
        }
    }
}
