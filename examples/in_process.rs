//! A server device and a remote in one process: reports reach the callback directly, with no
//! sockets and no serialisation beyond the payload.

use vrpn::{Connection, TimeVal, TrackerRemote, TrackerServer};

fn main() -> Result<(), vrpn::Error> {
    let conn = Connection::loopback();
    let server = TrackerServer::new("Hand", &conn, 1)?;
    let remote = TrackerRemote::on_connection("Hand", &conn)?;
    remote.on_pose(|p| println!("Hand at {:?}", p.pos));
    for i in 0..3 {
        server.report_pose(
            0,
            TimeVal::now(),
            [i as f64 * 0.1, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        )?;
    }
    Ok(())
}
