"""Python remotes against our vrpn_server on 127.0.0.1: poses by polling and by callback,
reconnection after a server restart, connection state and events."""

import math
import time

import vrpn
from conftest import pump

SPIN = "vrpn_Tracker_Spin Tracker0 2 100.0 0 0 1 0.5\n"


def test_pose_is_none_until_the_first_report_then_polled(start_server):
    server = start_server(SPIN)
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    assert t.pose(0) is None and t.pose(1) is None
    assert t.state == "connecting" and not t.connected
    pump([t], lambda: t.pose(0) is not None and t.pose(1) is not None, what="poses of both sensors")
    assert t.connected and t.state == "connected"
    first = t.pose(0)
    assert first.sensor == 0 and len(first.pos) == 3 and len(first.quat) == 4
    # A spin about z: unit quaternion with no x or y part; stamped with the wall clock.
    assert abs(math.sqrt(sum(c * c for c in first.quat)) - 1.0) < 1e-9
    assert first.quat[0] == 0.0 and first.quat[1] == 0.0
    assert abs(first.time - time.time()) < 5.0
    assert t.pose(2) is None and t.sensor_count == 2
    # Polling again later gives a newer report with another angle.
    pump([t], lambda: t.pose(0).time > first.time + 0.1, what="a newer pose")
    assert t.pose(0).quat != first.quat


def test_poses_by_callback_with_and_without_sensor_filter(start_server):
    server = start_server(SPIN)
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    every, only_one = [], []
    t.on_pose(every.append)
    t.on_pose(only_one.append, sensor=1)
    pump([t], lambda: len(only_one) >= 20, what="20 poses of sensor 1")
    assert {p.sensor for p in every} == {0, 1}
    assert {p.sensor for p in only_one} == {1}
    times = [p.time for p in every if p.sensor == 0]
    assert times == sorted(times) and times[-1] > times[0]
    # The latest-state API agrees with the last callback.
    last0 = [p for p in every if p.sensor == 0][-1]
    assert t.pose(0).time == last0.time and t.pose(0).quat == last0.quat


def test_remove_callback_stops_it(start_server):
    server = start_server(SPIN)
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    removed, kept = [], []
    h = t.on_pose(removed.append)
    t.on_pose(kept.append)
    pump([t], lambda: len(removed) >= 3, what="the first poses")
    t.remove_callback(h)
    n = len(removed)
    pump([t], lambda: len(kept) >= n + 20, what="more poses")
    assert len(removed) == n


def test_reconnects_after_a_server_restart(start_server):
    server = start_server(SPIN)
    port = server.port
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{port}")
    states, events, poses = [], [], []
    t.on_state_change(states.append)
    t.on_event("got_connection", lambda: events.append("got"))
    t.on_event("dropped_connection", lambda: events.append("dropped"))
    t.on_pose(poses.append)
    pump([t], lambda: len(poses) >= 5, what="poses from the first server")

    server.stop()
    killed_at = time.time()
    pump([t], lambda: t.state == "reconnecting", what="the client to notice the drop")
    assert not t.connected

    start_server(SPIN, port=port)
    pump([t], lambda: poses[-1].time > killed_at and t.connected, timeout=10,
         what="poses from the restarted server")
    assert states == ["connected", "reconnecting", "connected"]
    assert events == ["got", "dropped", "got"]


def test_buttons_analogs_dials_and_text_from_vrpn_server(start_server):
    cfg = (
        "vrpn_Button_Example Button0 3 20.0\n"
        "vrpn_Analog_Example Analog0 4 50.0\n"
        "vrpn_Dial_Example Dial0 2 2.0 20.0\n"
        "vrpn_Text_Example Text0 0.05 hello from the server\n"
    )
    server = start_server(cfg)
    at = f"127.0.0.1:{server.port}"
    b = vrpn.ButtonRemote(f"Button0@{at}")
    a = vrpn.AnalogRemote(f"Analog0@{at}")
    d = vrpn.DialRemote(f"Dial0@{at}")
    x = vrpn.TextReceiver(f"Text0@{at}")
    changes, states, reports, updates, texts = [], [], [], [], []
    b.on_change(changes.append)
    b.on_states(states.append)
    a.on_report(reports.append)
    d.on_update(updates.append)
    x.on_message(texts.append)
    assert a.latest() is None and a.num_channels == 0
    pump([b, a, d, x], lambda: changes and states and len(reports) > 2 and updates and texts,
         what="a report of every kind")
    assert states[0].num_buttons == 3 and b.num_buttons == 3
    assert changes[-1].button in (0, 1, 2) and changes[-1].state in (0, 1)
    assert a.num_channels == 4 and len(a.latest().channels) == 4
    assert all(-1.0 <= v <= 1.0 for v in a.latest().channels)
    assert a.channel(3) == a.latest().channels[3]
    assert abs(updates[0].change - 0.1) < 1e-9 and updates[0].dial in (0, 1)
    assert texts[0].text == "hello from the server" and texts[0].severity == "normal"
    assert x.received >= 1


def test_a_live_remote_has_no_replay_controls(start_server):
    server = start_server(SPIN)
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    assert t.replay is None
    assert t.device == "Tracker0"
    assert repr(t) == '<vrpn.TrackerRemote "Tracker0" connecting>'
    pump([t], lambda: t.connected, what="the connection")
    assert repr(t) == '<vrpn.TrackerRemote "Tracker0" connected>'
    assert repr(vrpn.Server(0)).startswith("<vrpn.Server port=")
