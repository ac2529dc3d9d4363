//! ForceDevice client-to-server requests in process: every trimesh / scene / constraint message,
//! custom effects, and the remote's constraint-as-force-field behaviour.

use std::cell::RefCell;
use std::rc::Rc;

use vrpn::devices::force::*;
use vrpn::Connection;

fn setup() -> (Connection, ForceDeviceServer, ForceDeviceRemote) {
    let conn = Connection::new_loopback();
    let server = ForceDeviceServer::new("Phantom0", &conn).unwrap();
    let remote = ForceDeviceRemote::on_connection("Phantom0", &conn).unwrap();
    (conn, server, remote)
}

#[test]
fn every_request_round_trips() {
    let (conn, server, remote) = setup();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    server.on_request(move |m| g.borrow_mut().push(m.request));
    let v = [0.5f32, -1.25, 2.0];
    let mut matrix = [0.0f32; 16];
    for (i, x) in matrix.iter_mut().enumerate() {
        *x = i as f32 * 0.5 - 3.0;
    }
    let origin = Origin {
        pos: v,
        axis: [0.0, 0.0, 1.0],
        angle: 1.5,
    };
    let sent = vec![
        ForceRequest::AddObject(AddObject { obj: 3, parent: -1 }),
        ForceRequest::AddObjectExScene(ObjectId { obj: 4 }),
        ForceRequest::MoveToParent(AddObject { obj: 4, parent: 3 }),
        ForceRequest::SetObjectPosition(ObjectVec3 { obj: 3, v }),
        ForceRequest::SetObjectOrientation(ObjectOrientation {
            obj: 3,
            axis: [1.0, 0.0, 0.0],
            angle: 0.25,
        }),
        ForceRequest::SetObjectScale(ObjectVec3 {
            obj: 3,
            v: [2.0, 2.0, 2.0],
        }),
        ForceRequest::RemoveObject(ObjectId { obj: 4 }),
        ForceRequest::SetVertex(IndexedVec3 {
            obj: 0,
            index: 7,
            v,
        }),
        ForceRequest::SetNormal(IndexedVec3 {
            obj: 0,
            index: 2,
            v: [0.0, 1.0, 0.0],
        }),
        ForceRequest::SetTriangle(SetTriangle {
            obj: 0,
            index: 1,
            vertices: [0, 1, 2],
            normals: [-1, -1, -1],
        }),
        ForceRequest::RemoveTriangle(RemoveTriangle { obj: 0, index: 1 }),
        ForceRequest::UpdateTrimeshChanges(UpdateTrimeshChanges {
            obj: 0,
            kspring: 0.8,
            kdamp: 0.001,
            fstat: 0.7,
            fdyn: 0.3,
        }),
        ForceRequest::TransformTrimesh(TransformTrimesh { obj: 0, matrix }),
        ForceRequest::SetTrimeshType(SetTrimeshType {
            obj: -1,
            kind: TRIMESH_HCOLLIDE,
        }),
        ForceRequest::ClearTrimesh(ObjectId { obj: 0 }),
        ForceRequest::SetHapticOrigin(origin),
        ForceRequest::SetHapticScale(HapticScale { scale: 0.5 }),
        ForceRequest::SetSceneOrigin(Origin {
            angle: -1.0,
            ..origin
        }),
        ForceRequest::SetObjectIsTouchable(SetObjectIsTouchable {
            obj: 3,
            touchable: 1,
        }),
        ForceRequest::ConstraintEnable(ConstraintInt { value: 1 }),
        ForceRequest::ConstraintMode(ConstraintInt {
            value: CONSTRAINT_MODE_PLANE,
        }),
        ForceRequest::ConstraintPoint(ConstraintVec3 { v }),
        ForceRequest::ConstraintLinePoint(ConstraintVec3 { v: [1.0, 0.0, 0.0] }),
        ForceRequest::ConstraintLineDirection(ConstraintVec3 { v: [0.0, 0.0, 1.0] }),
        ForceRequest::ConstraintPlanePoint(ConstraintVec3 { v: [0.0, 2.0, 0.0] }),
        ForceRequest::ConstraintPlaneNormal(ConstraintVec3 { v: [0.0, 1.0, 0.0] }),
        ForceRequest::ConstraintKSpring(ConstraintKSpring { k: 150.0 }),
    ];
    // 27 request types: the trimesh, scene and constraint messages clients send.
    assert_eq!(sent.len(), 27);
    let mut names: Vec<_> = sent.iter().map(|r| r.type_name()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), 27);
    assert_eq!(sent[0].type_name(), "vrpn_ForceDevice addObject");
    assert_eq!(sent[26].type_name(), "vrpn_ForceDevice constraint_KSpring");
    for r in &sent {
        remote.send_request(r).unwrap();
    }
    conn.mainloop().unwrap();
    assert_eq!(*got.borrow(), sent);
    assert_eq!(server.bad_messages(), 0);
}

#[test]
fn custom_effects_round_trip() {
    let (conn, server, remote) = setup();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    server.on_custom_effect(move |m| {
        g.borrow_mut()
            .push((m.effect.effect_id, m.effect.params().collect::<Vec<f32>>()))
    });
    remote.send_custom_effect(7, &[1.0, -0.5, 3.25]).unwrap();
    remote.send_custom_effect(8, &[]).unwrap();
    remote.stop_effect().unwrap();
    conn.mainloop().unwrap();
    assert_eq!(
        *got.borrow(),
        vec![
            (7, vec![1.0, -0.5, 3.25]),
            (8, vec![]),
            (STOP_EFFECT_ID, vec![]),
        ]
    );
}

fn close(a: &ForceField, origin: [f32; 3], j: [[f32; 3]; 3]) {
    assert_eq!(a.origin, origin);
    assert_eq!(a.force, [0.0; 3]);
    assert_eq!(a.radius, 100.0);
    for (r, (got, want)) in a.jacobian.iter().zip(j).enumerate() {
        for (c, (g, w)) in got.iter().zip(want).enumerate() {
            assert!((g - w).abs() < 1e-6, "J[{r}][{c}] = {g}, expected {w}");
        }
    }
}

#[test]
fn constraints_become_force_fields() {
    let (conn, server, remote) = setup();
    let fields = Rc::new(RefCell::new(Vec::new()));
    let f = fields.clone();
    server.on_force_field(move |(_, ff)| f.borrow_mut().push(*ff));
    let requests = Rc::new(RefCell::new(0));
    let r = requests.clone();
    server.on_request(move |_| *r.borrow_mut() += 1);
    let n = |conn: &Connection| {
        conn.mainloop().unwrap();
        fields.borrow().len()
    };

    // Disabled: setters send nothing.
    remote.set_constraint_kspring(2.0).unwrap();
    remote.set_constraint_point([1.0, 2.0, 3.0]).unwrap();
    assert_eq!(n(&conn), 0);
    assert!(remote.enable_constraint(2).is_err());
    // Enable in the default POINT mode: origin = point, J = −k·I = diag(−2, −2, −2).
    remote.enable_constraint(1).unwrap();
    assert_eq!(n(&conn), 1);
    close(
        &fields.borrow()[0],
        [1.0, 2.0, 3.0],
        [[-2.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, -2.0]],
    );
    remote.enable_constraint(1).unwrap(); // same value: nothing
    assert_eq!(n(&conn), 1);

    // PLANE: each setter re-sends. Normal (0,0,2) → n = (0,0,1); J[i][j] = −k·n_i·n_j: only
    // J[2][2] = −2·1·1 = −2.
    remote.set_constraint_mode(CONSTRAINT_MODE_PLANE).unwrap();
    remote.set_constraint_plane_point([0.0, 0.0, 1.0]).unwrap();
    remote.set_constraint_plane_normal([0.0, 0.0, 2.0]).unwrap();
    assert_eq!(n(&conn), 4);
    close(
        &fields.borrow()[3],
        [0.0, 0.0, 1.0],
        [[0.0; 3], [0.0; 3], [0.0, 0.0, -2.0]],
    );

    // LINE through (1,0,0) along (0,3,4): e = (−0, −3, 4)/5 = (0, −0.6, 0.8) (x, y mirrored);
    // e·eᵀ = [[0,0,0],[0,0.36,−0.48],[0,−0.48,0.64]]; J = −2·(I − e·eᵀ) =
    // [[−2,0,0],[0,−1.28,−0.96],[0,−0.96,−0.72]].
    remote.set_constraint_mode(CONSTRAINT_MODE_LINE).unwrap();
    remote.set_constraint_line_point([1.0, 0.0, 0.0]).unwrap();
    remote
        .set_constraint_line_direction([0.0, 3.0, 4.0])
        .unwrap();
    assert_eq!(n(&conn), 7);
    let line_j = [[-2.0, 0.0, 0.0], [0.0, -1.28, -0.96], [0.0, -0.96, -0.72]];
    close(&fields.borrow()[6], [1.0, 0.0, 0.0], line_j);

    // NONE keeps the last field (and re-sends it).
    remote.set_constraint_mode(CONSTRAINT_MODE_NONE).unwrap();
    assert_eq!(n(&conn), 8);
    close(&fields.borrow()[7], [1.0, 0.0, 0.0], line_j);

    // Disable: a zero field stops it.
    remote.enable_constraint(0).unwrap();
    assert_eq!(n(&conn), 9);
    assert_eq!(fields.borrow()[8], ForceField::default());
    // No constraint_* message was sent on the way (07.35 remote behaviour).
    assert_eq!(*requests.borrow(), 0);
    assert_eq!(remote.constraint().mode, CONSTRAINT_MODE_NONE);
}
