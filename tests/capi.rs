//! The C ABI (feature `capi`) from C: the committed header is what cbindgen makes of
//! `src/capi`, and C programs built against the shared and the static library talk to a
//! `vrpn_server` child and to each other over 127.0.0.1.
//!
//! The library is built by a nested `cargo rustc --features capi --crate-type cdylib,staticlib`
//! (dev profile) into its own target directory (`<target>/capi`), so this test runs in a plain
//! `cargo test --release` without the feature and without fighting the outer build's lock.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// What cbindgen makes of `src/capi` with `cbindgen.toml`.
fn generated_header() -> String {
    let root = Path::new(ROOT);
    let config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(root.join("src/capi/mod.rs"))
        .generate()
        .expect("cbindgen cannot parse src/capi");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).expect("header is UTF-8")
}

#[test]
fn header_is_current() {
    let path = Path::new(ROOT).join("include/vrpn.h");
    let fresh = generated_header();
    if std::env::var_os("VRPN_BLESS").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "include/vrpn.h does not match src/capi: regenerate it with \
         `VRPN_BLESS=1 cargo test --release --test capi header_is_current` and commit it"
    );
}

/// The shared and static libraries, built once per test run.
struct Library {
    /// Folder holding `libvrpn.so` and `libvrpn.a`.
    dir: PathBuf,
    /// The system libraries a program linked with `libvrpn.a` needs.
    native_libs: Vec<String>,
}

fn library() -> &'static Library {
    static LIB: std::sync::OnceLock<Library> = std::sync::OnceLock::new();
    LIB.get_or_init(build_library)
}

/// `<target>/capi`: beside the outer build's profile folders, never inside them.
fn capi_target_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    // <target>/release/deps/capi-HASH
    exe.ancestors().nth(3).unwrap().join("capi")
}

fn build_library() -> Library {
    let target = capi_target_dir();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(ROOT)
        // The dev profile: half the build time of --release, and overflow checks on.
        .args(["rustc", "--lib", "--no-default-features"])
        .args(["--features", "capi", "--crate-type", "cdylib,staticlib"])
        .arg("--target-dir")
        .arg(&target)
        .args(["--", "--print", "native-static-libs"])
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("RUSTFLAGS")
        .output()
        .expect("cannot run cargo");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "building the C library failed:\n{stderr}"
    );
    let dir = target.join("debug");
    assert!(dir.join("libvrpn.so").is_file() && dir.join("libvrpn.a").is_file());
    // "note: native-static-libs: -lgcc_s -lutil …" (replayed by cargo when fresh).
    let native_libs = stderr
        .lines()
        .find_map(|l| l.split("native-static-libs:").nth(1))
        .map(|l| l.split_whitespace().map(String::from).collect())
        .unwrap_or_else(|| {
            [
                "-lgcc_s",
                "-lutil",
                "-lrt",
                "-lpthread",
                "-lm",
                "-ldl",
                "-lc",
            ]
            .map(String::from)
            .to_vec()
        });
    Library { dir, native_libs }
}

/// A scratch folder for compiled programs, removed on drop.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("vrpn-capi-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

enum Link {
    Shared,
    Static,
}

/// Compiles the C program `source` (relative to the crate) strictly, linked as `link` says.
fn compile(source: &str, out: &Path, link: Link) {
    let lib = library();
    let mut cc = Command::new(std::env::var("CC").unwrap_or_else(|_| "cc".into()));
    cc.current_dir(ROOT)
        .args([
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-O1",
        ])
        .arg("-Iinclude")
        .arg(source)
        .arg("-o")
        .arg(out);
    match link {
        Link::Shared => {
            cc.arg(format!("-L{}", lib.dir.display()))
                .arg("-lvrpn")
                .arg(format!("-Wl,-rpath,{}", lib.dir.display()));
        }
        Link::Static => {
            cc.arg(lib.dir.join("libvrpn.a"));
        }
    }
    cc.arg("-lpthread").args(&lib.native_libs);
    let o = cc.output().expect("cannot run cc");
    assert!(
        o.status.success(),
        "cc {source} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs a program to its end (it has its own deadline) and returns its standard output.
fn run(program: &Path, args: &[&str]) -> String {
    // cargo points LD_LIBRARY_PATH at its own output folders, which it searches before the
    // program's run path: a libvrpn.so another build left there (maturin's, with Python in it)
    // must not stand in for the one just built.
    let o = Command::new(program)
        .args(args)
        .env_remove("LD_LIBRARY_PATH")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{} {args:?} failed ({}):\nstdout:\n{stdout}\nstderr:\n{}",
        program.display(),
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

/// One `pose sensor=S time=T pos=X,Y,Z quat=X,Y,Z,W` line of tracker_client.
struct PoseLine {
    sensor: i32,
    time: f64,
    pos: Vec<f64>,
    quat: Vec<f64>,
}

fn pose_lines(out: &str) -> Vec<PoseLine> {
    let field = |l: &str, key: &str| -> String {
        l.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .unwrap_or_else(|| panic!("no {key} in {l:?}"))
            .to_string()
    };
    let numbers = |s: String| -> Vec<f64> { s.split(',').map(|x| x.parse().unwrap()).collect() };
    out.lines()
        .filter(|l| l.starts_with("pose "))
        .map(|l| PoseLine {
            sensor: field(l, "sensor=").parse().unwrap(),
            time: field(l, "time=").parse().unwrap(),
            pos: numbers(field(l, "pos=")),
            quat: numbers(field(l, "quat=")),
        })
        .collect()
}

fn wall_seconds() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

#[test]
fn c_api_checks() {
    let scratch = Scratch::new("checks");
    let exe = scratch.0.join("api_checks");
    compile("tests/c/api_checks.c", &exe, Link::Shared);
    let out = run(&exe, &[]);
    assert!(out.contains("checks passed"), "{out}");
}

/// `vrpn_tracker_wait` and a `poll()` on `vrpn_tracker_fd` read a 60 Hz two-sensor tracker
/// with about one wake-up per datagram (both sensors' poses), not one per millisecond.
#[test]
fn c_wait_and_fd_do_not_spin() {
    let scratch = Scratch::new("wait");
    let exe = scratch.0.join("wait_checks");
    compile("tests/c/wait_checks.c", &exe, Link::Shared);
    let server = common::start_server("vrpn_Tracker_NULL Tracker0 2 60.0\n", 0);
    let name = format!("Tracker0@127.0.0.1:{}", server.port);
    let out = run(&exe, &[&name, "2"]);
    assert!(out.contains("wait checks passed"), "{out}");
    for way in ["wait", "fd"] {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("{way} ")))
            .unwrap_or_else(|| panic!("no {way} line in {out}"));
        let field = |k: &str| -> u64 {
            line.split_whitespace()
                .find_map(|w| w.strip_prefix(k))
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("no {k} in {line}"))
        };
        let (poses, wakeups) = (field("poses="), field("wakeups="));
        assert!(poses >= 120, "{way}: {poses} poses in 2 s: {out}");
        assert!(
            wakeups <= 2 * poses,
            "{way}: {wakeups} wake-ups for {poses} poses"
        );
    }
}

#[test]
fn c_discovery_texts_and_replay() {
    let scratch = Scratch::new("discovery");
    let exe = scratch.0.join("discovery_replay");
    compile("tests/c/discovery_replay.c", &exe, Link::Shared);
    let server = common::start_server(
        "vrpn_Tracker_NULL Tracker0 1 10.0\nvrpn_Text_Example Text0 0.05 hello from the server\n",
        0,
    );
    // A log of Tracker0: 20 poses 25 ms apart, x = 0 .. 19 (what the C program expects).
    let log = scratch.0.join("tracker.vrpn");
    {
        let conn = vrpn::Connection::server(Some([127, 0, 0, 1].into()), 0).unwrap();
        conn.log_outgoing(log.to_str().unwrap()).unwrap();
        let tracker = vrpn::TrackerServer::new("Tracker0", &conn, 1).unwrap();
        let t0 = conn.now().wall;
        for i in 0..20u32 {
            let t = t0.plus(std::time::Duration::from_millis(25 * u64::from(i)));
            tracker
                .report_pose(0usize, t, [f64::from(i), 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
                .unwrap();
        }
        conn.close_logs().unwrap();
    }
    let at = format!("127.0.0.1:{}", server.port);
    let out = run(&exe, &[&at, log.to_str().unwrap()]);
    assert!(out.contains("checks passed"), "{out}");
}

#[test]
fn c_tracker_client_reads_vrpn_server() {
    let scratch = Scratch::new("client");
    let exe = scratch.0.join("tracker_client");
    compile("examples/c/tracker_client.c", &exe, Link::Shared);
    let server = common::start_server("vrpn_Tracker_NULL Tracker0 2 60.0\n", 0);
    let name = format!("Tracker0@127.0.0.1:{}", server.port);
    let start = wall_seconds();
    let out = run(&exe, &[&name, "20", "10"]);
    let poses = pose_lines(&out);
    assert!(poses.len() >= 20, "{out}");
    for s in 0..2 {
        assert!(poses.iter().any(|p| p.sensor == s), "no sensor {s}:\n{out}");
    }
    for p in &poses {
        // The NULL tracker's identity pose, stamped by the server's clock (this machine's).
        assert!((0..2).contains(&p.sensor), "{out}");
        assert_eq!(p.pos, [0.0; 3], "{out}");
        assert_eq!(p.quat, [0.0, 0.0, 0.0, 1.0], "{out}");
        assert!((p.time - start).abs() < 30.0, "time {} vs {start}", p.time);
    }
    assert!(
        out.contains("latest sensor=0 pos=0.000000,0.000000,0.000000"),
        "{out}"
    );
    assert!(out.contains("state=1 sensors=2"), "{out}");
}

#[test]
fn c_tracker_client_reads_static_c_server() {
    let scratch = Scratch::new("pair");
    let (client, server_exe) = (scratch.0.join("client"), scratch.0.join("server"));
    compile("examples/c/tracker_client.c", &client, Link::Shared);
    compile("examples/c/tracker_server.c", &server_exe, Link::Static);
    // The server's only run-time dependency on us is none: it is linked statically.
    let ldd = Command::new("ldd").arg(&server_exe).output();
    if let Ok(o) = ldd {
        assert!(!String::from_utf8_lossy(&o.stdout).contains("libvrpn"));
    }
    let mut child = Command::new(&server_exe)
        .args(["0", "20"])
        .stdout(std::process::Stdio::piped())
        // Its notice when the client leaves is expected.
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut first = String::new();
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    std::io::BufRead::read_line(&mut stdout, &mut first).unwrap();
    let port: u16 = first
        .trim()
        .strip_prefix("listening on port ")
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no port in {first:?}"));
    let out = Command::new(&client)
        .args([&format!("Tracker0@127.0.0.1:{port}"), "50", "10"])
        .env_remove("LD_LIBRARY_PATH")
        .output()
        .unwrap();
    let _ = child.kill();
    let _ = child.wait();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let poses = pose_lines(&text);
    assert!(poses.len() >= 50, "{text}");
    let mut last_z = [f64::NEG_INFINITY; 2];
    for p in &poses {
        let s = p.sensor as usize;
        assert!(s < 2, "{text}");
        let k = s as f64 + 1.0;
        assert_eq!((p.pos[0], p.pos[1]), (k, -k), "{text}");
        assert_eq!(p.quat, [0.0, 0.0, 0.6, 0.8], "{text}");
        // Frames arrive in order, each sensor's z one step of 0.001 apart or more.
        assert!(p.pos[2] > last_z[s], "{text}");
        last_z[s] = p.pos[2];
    }
}

#[test]
fn c_steady_state_allocates_nothing() {
    let scratch = Scratch::new("alloc");
    let exe = scratch.0.join("steady_alloc");
    // Static: the interposed malloc then also serves the library's own code in the program.
    compile("tests/c/steady_alloc.c", &exe, Link::Static);
    let out = run(&exe, &["1.5", "2.0"]);
    assert!(out.contains(", 0 in "), "{out}");
}

#[test]
fn header_is_valid_cpp() {
    let scratch = Scratch::new("cpp");
    let (src, exe) = (scratch.0.join("use.cpp"), scratch.0.join("use"));
    std::fs::write(
        &src,
        "#include \"vrpn.h\"\n\
         #include <memory>\n\
         struct TrackerFree { void operator()(VrpnTracker *t) const { vrpn_tracker_free(t); } };\n\
         int main() {\n\
           std::unique_ptr<VrpnTracker, TrackerFree> t(vrpn_tracker_open(\"T0@\"));\n\
           VrpnStatus s = vrpn_last_error_status();\n\
           return (!t && s == VRPN_STATUS_NAME && vrpn_abi_version() == VRPN_ABI_VERSION) ? 0 : 1;\n\
         }\n",
    )
    .unwrap();
    let lib = library();
    let o = Command::new(std::env::var("CXX").unwrap_or_else(|_| "c++".into()))
        .current_dir(ROOT)
        .args(["-std=c++11", "-Wall", "-Wextra", "-Werror", "-Iinclude"])
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .arg(format!("-L{}", lib.dir.display()))
        .arg("-lvrpn")
        .arg(format!("-Wl,-rpath,{}", lib.dir.display()))
        .output()
        .expect("cannot run c++");
    assert!(
        o.status.success(),
        "c++ failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    run(&exe, &[]);
}

#[test]
fn c_imager_client_reads_a_rust_imager_server() {
    use vrpn::devices::imager::{BufferLayout, Extent, ImagerServer};
    let scratch = Scratch::new("imager");
    let exe = scratch.0.join("imager_client");
    compile("examples/c/imager_client.c", &exe, Link::Shared);
    let conn = vrpn::Connection::server(Some(std::net::Ipv4Addr::LOCALHOST), 0).unwrap();
    conn.on_notice(|_| {});
    let port = conn.local_port().unwrap();
    let server = ImagerServer::new("Cam0", &conn, 32, 16, 1).unwrap();
    server
        .add_channel("gray", "counts", 0.0, 65535.0, 1.0, 0.0)
        .unwrap();
    let mut child = Command::new(&exe)
        .args([&format!("Cam0@127.0.0.1:{port}"), "5", "20"])
        .env_remove("LD_LIBRARY_PATH")
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // 16-bit pixels whose high byte is the column: the C client reads them as 8-bit.
    let image: Vec<u16> = (0..32 * 16)
        .map(|i| ((i % 32) as u16) << 8 | 0x7f)
        .collect();
    let whole = Extent::whole(32, 16, 1);
    let layout = BufferLayout::packed(32, 16);
    let start = std::time::Instant::now();
    let mut next = start;
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < std::time::Duration::from_secs(30));
        conn.mainloop().unwrap();
        if conn.connected() && std::time::Instant::now() >= next {
            server.send_begin_frame(&whole, None).unwrap();
            for r0 in [0u16, 8] {
                let e = Extent::rect(0, 31, r0, r0 + 7);
                server.send_region(0, &e, &image, &layout, None).unwrap();
            }
            server.send_end_frame(&whole, None).unwrap();
            next += std::time::Duration::from_millis(20);
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("description 32x16x1 channels=1"), "{text}");
    // Each row sums 0 + 1 + ... + 31 = 496, 16 rows.
    let sums: Vec<&str> = text.lines().filter(|l| l.starts_with("frame ")).collect();
    assert!(sums.len() >= 5, "{text}");
    assert!(sums.iter().all(|l| l.contains("sum=7936")), "{text}");
    assert!(
        text.contains("channel 0 name=gray units=counts scale=1"),
        "{text}"
    );
    assert!(text.contains("bad=0"), "{text}");
}
