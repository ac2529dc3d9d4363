// Scratch capture tool (not committed): runs a vrpn_server with vrpn_Tracker_JsonNet, sends
// datagrams from a file (one per line), prints what a client hears.
use std::cell::RefCell;
use std::net::UdpSocket;
use std::process::{Command, Stdio};
use std::rc::Rc;
use std::time::{Duration, Instant};
use vrpn::{AnalogRemote, ButtonRemote, TextReceiver, TrackerRemote};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let exe = &args[1];
    let port: u16 = args[2].parse().unwrap();
    let udp: u16 = args[3].parse().unwrap();
    let lines = std::fs::read_to_string(&args[4]).unwrap();
    let cfgpath = format!("/tmp/fam2json/vrpn-{port}.cfg");
    std::fs::write(&cfgpath, format!("vrpn_Tracker_JsonNet JN {udp}\n")).unwrap();
    let mut child = Command::new(exe)
        .arg("-f")
        .arg(&cfgpath)
        .arg("-millisleep")
        .arg("1")
        .arg(port.to_string())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1000));
    let out: Rc<RefCell<Vec<String>>> = Rc::default();
    let at = format!("JN@tcp://127.0.0.1:{port}");
    let tr = TrackerRemote::new(&at).unwrap();
    let o = out.clone();
    tr.on_pose(move |p| {
        o.borrow_mut().push(format!(
            "OUT {} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            p.sensor, p.pos.x, p.pos.y, p.pos.z, p.quat.i, p.quat.j, p.quat.k, p.quat.w
        ))
    });
    let br = ButtonRemote::new(&at).unwrap();
    let o = out.clone();
    br.on_change(move |c| {
        o.borrow_mut()
            .push(format!("BTN {} {}", c.button, c.state.raw()))
    });
    let ar = AnalogRemote::new(&at).unwrap();
    let o = out.clone();
    ar.on_report(move |r| {
        let nz: Vec<String> = r
            .channels()
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(i, v)| format!("{i} {v:?}"))
            .collect();
        o.borrow_mut()
            .push(format!("ANA {} {}", r.channels().len(), nz.join(" ")))
    });
    let tx = TextReceiver::new(&at).unwrap();
    let o = out.clone();
    tx.on_message(move |m| {
        o.borrow_mut()
            .push(format!("TXT {} {:?}", m.severity.code(), m.text()))
    });
    let pump = |d: Duration| {
        let s = Instant::now();
        while s.elapsed() < d {
            let _ = tr.mainloop();
            let _ = br.mainloop();
            let _ = ar.mainloop();
            let _ = tx.mainloop();
            std::thread::sleep(Duration::from_millis(1));
        }
    };
    pump(Duration::from_millis(1500));
    out.borrow_mut().clear();
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    for (i, l) in lines.lines().enumerate() {
        out.borrow_mut().push(format!("SEND {i} {l}"));
        sock.send_to(l.as_bytes(), ("127.0.0.1", udp)).unwrap();
        pump(Duration::from_millis(120));
    }
    pump(Duration::from_millis(300));
    for l in out.borrow().iter() {
        println!("{l}");
    }
    let _ = child.kill();
    let _ = child.wait();
}
