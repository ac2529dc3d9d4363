"""The imager remote, mutexes and shared objects from Python, on 127.0.0.1: a Python server
and Python remotes, each side through the Rust library."""

import struct

import pytest

import vrpn
from conftest import pump


def test_imager_regions_frames_and_throttle():
    server = vrpn.Server(0)
    cam = vrpn.ImagerServer(server, "Cam0", 8, 4)
    assert cam.add_channel("gray", "counts") == 0
    assert cam.add_channel("temp", "K", 0.0, 400.0, 0.5, 10.0) == 1
    remote = vrpn.ImagerRemote(f"Cam0@127.0.0.1:{server.port}")
    regions, ends = [], []
    remote.on_region(regions.append)
    remote.on_end_frame(ends.append)
    pump([server, remote], lambda: remote.description is not None, what="the description")
    d = remote.description
    assert (d.cols, d.rows, d.depth, d.channels) == (8, 4, 1, 2)
    assert remote.channel(1).units == "K"
    assert remote.channel(1).scale == 0.5
    assert remote.channel_index("temp") == 1
    assert remote.channel(2) is None

    gray = bytes(range(32))
    temps = struct.pack("<4f", 280.0, 281.5, 282.0, 283.25)
    assert cam.send_begin_frame(0, 7, 0, 3)
    assert cam.send_region(0, 0, 7, 0, 3, gray)
    assert cam.send_region(1, 2, 3, 1, 2, temps, value_type="f32")
    assert cam.send_end_frame(0, 7, 0, 3)
    pump([server, remote], lambda: len(ends) == 1, what="the end of the frame")
    g, t = regions
    assert (g.channel, g.columns, g.rows, g.value_type) == (0, (0, 7), (0, 3), "u8")
    assert g.data == gray and len(g) == 32
    assert t.value_type == "f32" and t.values() == [280.0, 281.5, 282.0, 283.25]
    frame = remote.take_end_frame()
    assert frame.seq == 1 and frame.columns == (0, 7)
    assert remote.take_end_frame() is None

    discarded = []
    remote.on_discarded_frames(lambda n: discarded.append(n.count))
    remote.throttle_sender(0)
    pump([server, remote], lambda: cam.frames_to_send == 0, what="the throttle")
    assert cam.send_begin_frame(0, 7, 0, 3) is False
    assert cam.send_region(0, 0, 7, 0, 3, gray) is False
    remote.throttle_sender(-1)
    pump([server, remote], lambda: cam.frames_to_send == -1, what="the throttle lifted")
    assert cam.send_begin_frame(0, 7, 0, 3)
    assert cam.send_end_frame(0, 7, 0, 3)
    pump([server, remote], lambda: len(ends) == 2, what="the next frame")
    assert discarded == [1]
    with pytest.raises(vrpn.VrpnError):
        cam.send_region(5, 0, 7, 0, 3, gray)
    remote.close()
    server.close()


def test_mutex_between_two_remotes():
    server = vrpn.Server(0)
    lock = vrpn.MutexServer(server, "lock")
    at = f"lock@127.0.0.1:{server.port}"
    a = vrpn.MutexRemote(at)
    b = vrpn.MutexRemote(f"lock@localhost:{server.port}")
    events = []
    a.on_granted(lambda: events.append("a granted"))
    b.on_denied(lambda: events.append("b denied"))
    b.on_released(lambda: events.append("b released"))
    pump([server, a, b], lambda: a.index is not None and b.index is not None, what="indices")
    a.request()
    pump([server, a, b], lambda: a.is_held_locally and b.is_held_remotely, what="the grant")
    assert lock.is_held and lock.holder == a.index
    assert a.state == "ours" and b.state == "held_remotely"
    b.request()
    assert events == ["a granted", "b denied"]
    a.release()
    pump([server, a, b], lambda: b.is_available and not lock.is_held, what="the release")
    assert events[-1] == "b released"
    a.set_request_timeout(0.5)
    with pytest.raises(ValueError):
        a.set_request_timeout(-1.0)
    for m in (a, b):
        m.close()
    server.close()


def test_peer_mutex():
    p = vrpn.PeerMutex("peers", 0, "127.0.0.1")
    q = vrpn.PeerMutex("peers", 0, "127.0.0.1")
    p.add_peer(f"127.0.0.1:{q.port}")
    q.add_peer(f"127.0.0.1:{p.port}")
    pump([p, q], lambda: p.peers_connected and q.peers_connected, what="the peers")
    p.request()
    pump([p, q], lambda: p.is_held_locally and q.is_held_remotely, what="the grant")
    p.release()
    pump([p, q], lambda: q.is_available, what="the release")
    p.close()
    q.close()


def test_shared_objects():
    server = vrpn.Server(0)
    at = f"127.0.0.1:{server.port}"
    n = vrpn.SharedInt32.server(server, "n", 5)
    f = vrpn.SharedFloat64.server(server, "f", 0.5)
    s = vrpn.SharedString.server(server, "s", "hello", serialized=True)
    s.set_policy("deny_remote")
    rn = vrpn.SharedInt32(f"n@{at}")
    rf = vrpn.SharedFloat64(f"f@{at}")
    rs = vrpn.SharedString(f"s@{at}", serialized=True)
    changes = []
    rn.on_change(changes.append)
    deferred = []
    rs.on_deferred_update(lambda: deferred.append(1))
    objs = [server, rn, rf, rs]
    pump(objs, lambda: (rn.value, rf.value, rs.value) == (5, 0.5, "hello"), what="initial values")
    assert changes[0].value == 5 and not changes[0].is_local
    n.set(7)
    rf.set(2.25)
    pump(objs, lambda: rn.value == 7 and f.value == 2.25, what="both directions")
    # Serialized, the server denying remote changes: the remote's change goes nowhere.
    rs.set("changed here")
    assert rs.value == "hello" and deferred == [1]
    s.set("changed by the server")
    pump(objs, lambda: rs.value == "changed by the server", what="the serializer's change")
    # A policy callback on the serializer.
    seen = []
    s.set_policy_callback(lambda v, when: seen.append(v) or v.startswith("ok"))
    rs.set("no")
    rs.set("ok then")
    pump(objs, lambda: rs.value == "ok then", what="the accepted change")
    # (The earlier remote change may reach the server only now, and be judged too.)
    assert seen[-2:] == ["no", "ok then"]
    assert s.value == "ok then"
    assert not rs.is_serializer and s.is_serializer
    for o in (rn, rf, rs):
        o.close()
    server.close()
    with pytest.raises(vrpn.ClosedError):
        n.value
