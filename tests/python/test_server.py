"""A Python server read by the Rust vrpn_print_devices and by Python remotes; callbacks that
raise; garbage collection of callback cycles."""

import gc
import json
import math
import sys
import time
import weakref

import pytest

import vrpn
from conftest import Child, program, pump

HALF = math.sqrt(0.5)


def test_python_server_read_by_vrpn_print_devices():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0", sensors=2)
    buttons = vrpn.ButtonServer(server, "Button0", buttons=2)
    analog = vrpn.AnalogServer(server, "Analog0", channels=3)
    at = f"127.0.0.1:{server.port}"
    child = Child([program("vrpn_print_devices"), "--json", "--seconds", "3",
                   f"Tracker0@{at}", f"Button0@{at}", f"Analog0@{at}"])
    child.collect()
    n = 0
    end = time.monotonic() + 20
    while child.proc.poll() is None and time.monotonic() < end:
        server.mainloop()
        if server.connected:
            tracker.report_pose(n % 2, (1.5, -2.25, 0.125 * n), (0.0, 0.0, HALF, HALF))
            buttons.set_button(1, n % 20 < 10)
            buttons.report_changes()
            analog.report([0.5, -0.25, float(n)])
            n += 1
        time.sleep(0.005)
    out, err = child.wait(timeout=10)
    child.stop()
    assert child.proc.returncode == 0, err
    lines = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    poses = [r for r in lines if r["kind"] == "pose"]
    assert len(poses) >= 10, out[:2000]
    p = poses[-1]
    assert p["device"] == "Tracker0" and p["sensor"] in (0, 1)
    assert p["pos"][:2] == [1.5, -2.25] and p["pos"][2] == 0.125 * round(p["pos"][2] / 0.125)
    assert p["quat"] == [0.0, 0.0, HALF, HALF]
    assert abs(p["time"] - time.time()) < 30
    assert any(r["kind"] == "button" and r["button"] == 1 for r in lines)
    analogs = [r for r in lines if r["kind"] == "analog"]
    assert analogs and analogs[-1]["channels"][:2] == [0.5, -0.25]


def test_python_server_read_by_python_remotes():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0")
    dial = vrpn.DialServer(server, "Dial0", dials=2)
    text = vrpn.TextSender(server, "Tracker0")
    events = []
    server.on_event("got_first_connection", lambda: events.append("first"))
    at = f"127.0.0.1:{server.port}"
    t = vrpn.TrackerRemote(f"Tracker0@{at}")
    d = vrpn.DialRemote(f"Dial0@{at}")
    x = vrpn.TextReceiver(f"Tracker0@{at}")
    updates, texts = [], []
    d.on_update(updates.append)
    x.on_message(texts.append)
    pump([server, t], lambda: server.connected and t.connected, what="the connection")
    assert events == ["first"] and server.connected_peers == 1
    tracker.report_pose(0, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0), time=1234.5)
    dial.report_rotation(1, 0.25)
    text.send("careful", severity="warning", level=3)
    pump([server, t], lambda: t.pose(0) is not None and updates and texts, what="the reports")
    p = t.pose(0)
    assert p.pos == (1.0, 2.0, 3.0) and p.quat == (0.0, 0.0, 0.0, 1.0) and p.time == 1234.5
    assert (updates[0].dial, updates[0].change) == (1, 0.25)
    assert (texts[0].text, texts[0].severity, texts[0].level) == ("careful", "warning", 3)


def test_velocity_buttons_and_analogs_round_trip_between_python_objects():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Dev0", sensors=2)
    buttons = vrpn.ButtonServer(server, "Dev0", buttons=3)
    analog = vrpn.AnalogServer(server, "Dev0", channels=2)
    at = f"Dev0@127.0.0.1:{server.port}"
    t, b, a = vrpn.TrackerRemote(at), vrpn.ButtonRemote(at), vrpn.AnalogRemote(at)
    velocities, changes, reports = [], [], []
    t.on_velocity(velocities.append)
    b.on_change(changes.append)
    a.on_report(reports.append)
    pump([server, t], lambda: t.connected and b.num_buttons == 3, what="the button count")
    assert b.button_state(2) == 0 and not b.pressed(2)

    tracker.report_velocity(1, (0.5, 0.0, 0.0), (0.0, 0.0, HALF, HALF), 0.25, time=10.0)
    buttons.set_button(2, True)
    buttons.report_changes(time=11.0)
    analog.set_channel(1, -0.75)
    assert analog.report_changes(time=12.0) is True
    assert analog.report_changes() is False  # nothing changed since
    pump([server, t], lambda: velocities and changes and reports, what="the reports")

    v = t.velocity(1)
    assert v is not None and t.velocity(0) is None and velocities[0].time == 10.0
    assert v.vel == (0.5, 0.0, 0.0) and v.vel_quat_dt == 0.25
    # 90 degrees about z in 0.25 s: 2*pi rad/s about z.
    assert abs(v.angular_velocity[2] - 2 * math.pi) < 1e-9
    assert (changes[0].button, changes[0].pressed, changes[0].time) == (2, True, 11.0)
    assert b.button_state(2) == 1 and b.pressed(2)
    assert reports[0].channels == [0.0, -0.75] and a.latest().time == 12.0
    with pytest.raises(ValueError, match="3 values given for 2 channels"):
        analog.report([1.0, 2.0, 3.0])


def test_a_raising_callback_surfaces_from_mainloop_and_the_loop_goes_on():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0")
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    seen = []

    def bad(p):
        seen.append(p)
        if len(seen) == 1:
            raise ValueError("callback failed on purpose")

    t.on_pose(bad)
    after = []
    t.on_pose(after.append)  # registered later: still called for the same report
    pump([server, t], lambda: t.connected, what="the connection")
    tracker.report_pose(0, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="callback failed on purpose"):
        pump([server, t], lambda: False, timeout=5)
    assert len(seen) == 1 and len(after) == 1
    # The connection and the callbacks keep working.
    tracker.report_pose(0, (2.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    pump([server, t], lambda: len(after) == 2, what="the next report")
    assert len(seen) == 2 and t.connected


def test_a_second_exception_in_the_same_pass_goes_to_the_unraisable_hook(monkeypatch):
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0", sensors=2)
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)

    def bad(p):
        raise KeyError(p.sensor)

    t.on_pose(bad)
    pump([server, t], lambda: t.connected, what="the connection")
    # Two reports in one TCP write are delivered in the same mainloop() pass.
    tracker.report_pose(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    tracker.report_pose(1, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    server.mainloop()
    with pytest.raises(KeyError) as first:
        pump([t], lambda: False, timeout=5)
    assert first.value.args == (0,)
    pump([t], lambda: unraisable, what="the second exception")
    assert isinstance(unraisable[0].exc_value, KeyError) and unraisable[0].exc_value.args == (1,)


def test_callback_cycles_are_collected():
    server = vrpn.Server(0)

    class App:
        def __init__(self):
            self.tracker = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
            self.tracker.on_pose(self.on_pose)  # app -> tracker -> bound method -> app
            self.tracker.on_state_change(self.on_state)

        def on_pose(self, p):
            pass

        def on_state(self, s):
            pass

    app = App()
    ref = weakref.ref(app)
    del app
    gc.collect()
    assert ref() is None


def test_server_errors_carry_the_crate_messages():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0", sensors=1)
    with pytest.raises(vrpn.OutOfRangeError, match="sensor 3 is out of range: the device has 1 sensors"):
        tracker.report_pose(3, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    with pytest.raises(vrpn.VrpnError, match="[Aa]ddress already in use"):
        vrpn.Server(server.port)
    with pytest.raises(ValueError, match="nic must be an IPv4 address"):
        vrpn.Server(0, nic="eth0")
    with pytest.raises(IndexError, match="button 5 is out of range"):
        vrpn.ButtonServer(server, "Button0", 2).set_button(5, True)
    with pytest.raises(ValueError, match="severity must be"):
        vrpn.TextSender(server, "T").send("x", severity="loud")
    with pytest.raises(ValueError, match="length 3"):
        tracker.report_pose(0, (0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def test_notices_go_to_python_instead_of_stderr():
    import socket

    server = vrpn.Server(0)
    notices, states = [], []
    server.on_notice(notices.append)
    server.on_state_change(states.append)
    # Something that is not VRPN connects to the server's TCP port.
    with socket.create_connection(("127.0.0.1", server.port)) as s:
        s.sendall(b"GET / HTTP/1.0\r\n\r\n" * 4)
        pump([server], lambda: notices, what="a notice about the bad peer")
    assert isinstance(notices[0], vrpn.Notice)
    assert notices[0].severity in ("info", "warning", "error")
    assert "127.0.0.1" in notices[0].text and "bad cookie" in notices[0].text, notices[0].text
    assert states == [] and server.state == "listening"
