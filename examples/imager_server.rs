//! Serves a 256 × 256 test image, 10 frames a second, as C++ `testimager_server` does: one
//! 8-bit channel "Slope" holding `(x + y + frame) % 256`, sent as frames of row strips.
//!
//! `cargo run --example imager_server -- [port] [name]` (default port 3883, name TestImage).

use std::time::{Duration, Instant};

use vrpn::devices::imager::{BufferLayout, Extent, ImagerServer, MAX_REGION_U8};
use vrpn::Connection;

const SIZE: usize = 256;

fn main() -> Result<(), vrpn::Error> {
    let mut args = std::env::args().skip(1);
    let port: u16 = args.next().and_then(|a| a.parse().ok()).unwrap_or(3883);
    let name = args.next().unwrap_or_else(|| "TestImage".into());
    let conn = Connection::server(None, port)?;
    let server = ImagerServer::new(&name, &conn, SIZE as i32, SIZE as i32, 1)?;
    let channel = server.add_channel("Slope", "unsigned8bit", 0.0, 255.0, 1.0, 0.0)?;
    println!("{name} on port {port}");
    let mut image = vec![0u8; SIZE * SIZE];
    let layout = BufferLayout::packed(SIZE, SIZE);
    let whole = Extent::whole(SIZE as u16, SIZE as u16, 1);
    let rows_per_region = MAX_REGION_U8 / SIZE;
    let mut frame = 0usize;
    let mut next = Instant::now();
    loop {
        conn.mainloop()?;
        if Instant::now() >= next {
            for (i, v) in image.iter_mut().enumerate() {
                *v = ((i % SIZE + i / SIZE + frame) % 256) as u8;
            }
            frame += 1;
            if server.send_begin_frame(&whole, None)? {
                for y in (0..SIZE).step_by(rows_per_region) {
                    let last = (y + rows_per_region).min(SIZE) - 1;
                    let strip = Extent::rect(0, SIZE as u16 - 1, y as u16, last as u16);
                    server.send_region(channel, &strip, &image, &layout, None)?;
                }
                server.send_end_frame(&whole, None)?;
            }
            next += Duration::from_millis(100);
        }
        conn.wait_until(Some(next), Duration::from_millis(100))?;
    }
}
