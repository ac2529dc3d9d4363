//! Reads an imager: prints its description, each frame's end with a checksum of the image
//! assembled from its regions, and discarded-frame notices.
//!
//! `cargo run --example imager_client -- TestImage@localhost [frames] [throttle]`
//!
//! `frames`: stop after that many frames (default: run until interrupted). `throttle`: ask
//! the server for at most that many frames, then for unlimited frames once they arrived (as
//! the C++ `testimager_client`'s number keys and `-` key do). Against C++
//! `testimager_server`, whose single channel holds `(x + y + frame) % 256`, each frame also
//! says whether every pixel fits that slope.

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::Duration;

use vrpn::devices::imager::{BufferLayout, ImagerRemote};

fn main() -> Result<(), vrpn::Error> {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "TestImage@localhost".into());
    let frames: Option<u64> = args.next().and_then(|a| a.parse().ok());
    let throttle: Option<i32> = args.next().and_then(|a| a.parse().ok());
    let imager = ImagerRemote::new(&name)?;
    let image = Rc::new(RefCell::new(Vec::<u8>::new()));
    let size = Rc::new(Cell::new((0usize, 0usize)));
    let (img, sz) = (image.clone(), size.clone());
    imager.on_description(move |d| {
        println!(
            "description: {} columns, {} rows, depth {}, {} channel(s)",
            d.cols, d.rows, d.depth, d.channels
        );
        let (c, r) = (d.cols.max(0) as usize, d.rows.max(0) as usize);
        sz.set((c, r));
        img.borrow_mut().resize(c * r, 0);
    });
    let img = image.clone();
    let sz = size.clone();
    imager.on_region(move |r| {
        let (c, rows) = sz.get();
        if let Err(e) = r.read_into(&mut img.borrow_mut()[..], &BufferLayout::packed(c, rows)) {
            eprintln!("region {:?} does not fit: {e}", r.extent);
        }
    });
    imager.on_discarded_frames(|d| println!("server discarded {} frame(s)", d.count));
    let done = Rc::new(Cell::new(0u64));
    let (d, img) = (done.clone(), image.clone());
    imager.on_end_frame(move |f| {
        let img = img.borrow();
        let (c, _) = size.get();
        let sum: u64 = img.iter().map(|&v| u64::from(v)).sum();
        // The C++ test server's slope: every pixel minus (x + y) is the same offset.
        let offset = img.first().copied().unwrap_or(0);
        let slope = c > 0
            && img
                .iter()
                .enumerate()
                .all(|(i, &v)| v == ((i % c + i / c + usize::from(offset)) % 256) as u8);
        println!(
            "frame {} ended: extent {:?}, sum {sum}, slope {}",
            f.seq,
            f.extent,
            if slope {
                format!("yes (offset {offset})")
            } else {
                "no".into()
            }
        );
        d.set(f.seq);
    });
    let mut throttled = false;
    let mut lifted = false;
    loop {
        imager.mainloop()?;
        if let Some(n) = throttle {
            if !throttled && imager.description().is_some() {
                println!("throttling the server to {n} frame(s)");
                imager.throttle_sender(n)?;
                throttled = true;
            }
            if throttled && !lifted && done.get() >= n.max(0) as u64 {
                std::thread::sleep(Duration::from_millis(500));
                println!("lifting the throttle");
                imager.throttle_sender(-1)?;
                lifted = true;
            }
        }
        if frames.is_some_and(|n| done.get() >= n) {
            return Ok(());
        }
        imager.connection().wait(Duration::from_millis(10))?;
    }
}
