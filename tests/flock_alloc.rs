//! The Flock drivers report records without allocating: checked with a counting global
//! allocator around every driver call while a Flock streams through them (one line in group
//! mode, and one line per receiver) with reads split at random points and garbage on the line.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::drivers::flock::sim::{FlockSim, SimConfig};
use vrpn::drivers::flock::{FlockDriver, FlockParallelPort};
use vrpn::serial::testing::{VirtualLine, VirtualLines};
use vrpn::serial::{PortKind, PortOps, SerialDriver};
use vrpn::server::config::{parse_str, DeviceConfig};
use vrpn::{Connection, Now, TimeVal, TrackerRemote};

struct Counting;

thread_local! {
    static ENABLED: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

fn note_alloc() {
    if ENABLED.try_with(Cell::get).unwrap_or(false) {
        let _ = COUNT.try_with(|c| c.set(c.get() + 1));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_alloc();
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note_alloc();
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_alloc();
        System.realloc(ptr, layout, new_size)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn counted<T>(f: impl FnOnce() -> T) -> T {
    ENABLED.with(|e| e.set(true));
    let out = f();
    ENABLED.with(|e| e.set(false));
    out
}

/// Counts allocations made inside the wrapped driver's calls only (the simulator and the
/// virtual line allocate freely).
struct Counted<D>(D);

impl<D: SerialDriver> SerialDriver for Counted<D> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn port_kind(&self) -> PortKind {
        self.0.port_kind()
    }
    fn opened(&mut self, now: Now, port: &mut PortOps) {
        self.0.opened(now, port)
    }
    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        counted(|| self.0.received(bytes, arrived, port))
    }
    fn poll(&mut self, now: Now, port: &mut PortOps) {
        counted(|| self.0.poll(now, port))
    }
    fn next_deadline(&self) -> Option<Instant> {
        counted(|| self.0.next_deadline())
    }
    fn closed(&mut self, now: Now) {
        self.0.closed(now)
    }
}

fn start() -> Now {
    Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    }
}

fn pose_counter(remote: &TrackerRemote) -> Rc<Cell<u64>> {
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    remote.on_pose(move |_| p.set(p.get() + 1));
    poses
}

#[test]
fn one_line_flock_streams_without_allocating() {
    let text = "vrpn_Tracker_Flock Tracker0 4 /dev/ttyS0 115200 1\n";
    let DeviceConfig::Flock(cfg) = parse_str(text, "alloc.cfg").unwrap().remove(0).config else {
        panic!("not a Flock entry");
    };
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let driver = FlockDriver::new(&cfg, &conn).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = pose_counter(&tracker);
    let mut line = VirtualLine::new(
        Counted(driver),
        FlockSim::new(SimConfig::for_flock(&cfg)),
        start(),
        3,
    );
    line.split_reads = true;
    // Reset, then streaming with one resynchronisation note to warm every path up.
    line.run_for(Duration::from_millis(1500));
    assert!(line.driver.0.is_streaming());
    line.inject(&[0x01, 0x80, 0x02]);
    line.run_for(Duration::from_millis(500));
    COUNT.with(|c| c.set(0));
    let before = poses.get();
    for _ in 0..5 {
        line.run_for(Duration::from_secs(1));
        line.inject(&[0x03, 0x81, 0x04]);
    }
    let allocations = COUNT.with(Cell::get);
    let poses = poses.get() - before;
    assert!(poses > 1900, "{poses} poses");
    assert!(line.driver.0.skipped_bytes() >= 6);
    assert_eq!(
        allocations, 0,
        "allocations while streaming {poses} records"
    );
}

#[test]
fn parallel_flock_streams_without_allocating() {
    let text = "vrpn_Tracker_Flock_Parallel Tracker0 3 /dev/m 38400 0 /dev/a /dev/b /dev/c\n";
    let DeviceConfig::FlockParallel(cfg) = parse_str(text, "alloc.cfg").unwrap().remove(0).config
    else {
        panic!("not a Flock_Parallel entry");
    };
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let ports = FlockParallelPort::new_group(&cfg, &conn).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = pose_counter(&tracker);
    let sims = FlockSim::parallel(SimConfig::for_parallel(&cfg));
    let mut lines = VirtualLines::new(ports.into_iter().map(Counted).zip(sims), start(), 4);
    for l in &mut lines.lines {
        l.split_reads = true;
    }
    lines.run_for(Duration::from_millis(2000));
    assert!(lines.lines[0].driver.0.is_streaming());
    lines.line(2).inject(&[0x01, 0x80, 0x02]);
    lines.run_for(Duration::from_millis(500));
    COUNT.with(|c| c.set(0));
    let before = poses.get();
    for _ in 0..5 {
        lines.run_for(Duration::from_secs(1));
        lines.line(3).inject(&[0x03, 0x81, 0x04]);
    }
    let allocations = COUNT.with(Cell::get);
    let poses = poses.get() - before;
    assert!(poses > 1400, "{poses} poses");
    assert_eq!(
        allocations, 0,
        "allocations while streaming {poses} records"
    );
}
