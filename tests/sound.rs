//! Sound through real sockets on 127.0.0.1: every client request arrives at the server's
//! callbacks decoded, with the C++ payload lengths.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::sound::{
    Material, MaterialName, PolyQuad, SoundClient, SoundDef, SoundRequest, SoundServer,
};
use vrpn::{Connection, SenderFilter};

#[test]
fn every_request_reaches_the_server() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    srv.on_notice(|_| {});
    let port = srv.local_port().unwrap();
    let server = SoundServer::new("Sound0", &srv).unwrap();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    server.on_request(move |r| g.borrow_mut().push(r.request.clone()));
    // Payload lengths as the server receives them.
    let lengths = Rc::new(RefCell::new(Vec::new()));
    let l = lengths.clone();
    srv.register_any_type_handler(SenderFilter::Only(server_sender(&srv)), move |m| {
        l.borrow_mut().push(m.payload.len())
    });
    let sound = SoundClient::new(&format!("Sound0@127.0.0.1:{port}")).unwrap();
    let cli = sound.connection().clone();
    let start = Instant::now();
    while !cli.connected() && start.elapsed() < Duration::from_secs(10) {
        srv.mainloop().unwrap();
        cli.mainloop().unwrap();
    }
    let def = SoundDef {
        volume: 0.5,
        pitch: 1.25,
        ..SoundDef::default()
    };
    assert_eq!(sound.load_sound("ding.wav", 4, &def).unwrap(), 4);
    sound.play_sound(4, 0).unwrap();
    sound
        .set_sound_pose(4, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    sound.set_sound_distances(4, 10.0, 1.0, 5.0, 0.5).unwrap();
    sound
        .set_listener_pose([0.0; 3], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    sound.set_sound_volume(4, 0.75).unwrap();
    let quad = PolyQuad {
        tag: 9,
        opening_factor: 0.5,
        material: MaterialName::new("glass").unwrap(),
        ..PolyQuad::default()
    };
    sound.load_poly_quad(&quad).unwrap();
    sound
        .load_material(&Material {
            id: 2,
            name: MaterialName::new("glass").unwrap(),
            reflectance_gain: 0.9,
            ..Material::default()
        })
        .unwrap();
    sound.set_poly_material(9, "wood").unwrap();
    sound.load_model_local("room.obj").unwrap();
    sound.stop_sound(4).unwrap();
    sound.unload_sound(4).unwrap();
    let start = Instant::now();
    while got.borrow().len() < 12 && start.elapsed() < Duration::from_secs(10) {
        srv.mainloop().unwrap();
        cli.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(300));
    }
    let got = got.borrow();
    assert_eq!(got.len(), 12, "{got:?}");
    assert_eq!(
        got[0],
        SoundRequest::LoadLocal {
            id: 4,
            def,
            file: "ding.wav".into()
        }
    );
    assert_eq!(got[1], SoundRequest::Play { id: 4, repeat: 0 });
    match &got[2] {
        SoundRequest::Pose(p) => assert_eq!((p.id, p.position), (4, [1.0, 2.0, 3.0])),
        other => panic!("{other:?}"),
    }
    match &got[3] {
        SoundRequest::Distances(d) => {
            assert_eq!(
                (d.max_front, d.min_front, d.max_back, d.min_back),
                (10.0, 1.0, 5.0, 0.5)
            )
        }
        other => panic!("{other:?}"),
    }
    match &got[6] {
        SoundRequest::PolyQuad(q) => {
            assert_eq!((q.tag, q.material.as_str()), (9, Some("glass")))
        }
        other => panic!("{other:?}"),
    }
    match &got[8] {
        SoundRequest::PolyMaterial(p) => assert_eq!(p.material.as_str(), Some("wood")),
        other => panic!("{other:?}"),
    }
    assert_eq!(got[9], SoundRequest::LoadModelLocal("room.obj".into()));
    assert_eq!(got[10], SoundRequest::Stop(4));
    assert_eq!(got[11], SoundRequest::Unload(4));
    // The C++ client's lengths: 181 + name, 8, 60, 36, 88, 12, 248, 164, 132, 4 + name + 1.
    let user: Vec<usize> = lengths
        .borrow()
        .iter()
        .copied()
        .filter(|&n| n > 0)
        .collect();
    assert!(
        user.ends_with(&[189, 8, 60, 36, 88, 12, 248, 164, 132, 13, 4, 4]),
        "{user:?}"
    );
    assert_eq!(server.bad_messages(), 0);
}

fn server_sender(conn: &Connection) -> vrpn::SenderId {
    conn.register_sender("Sound0").unwrap()
}
