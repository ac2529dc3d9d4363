"""What the Python module refuses and how its objects end: the same device limits as vrpn.cfg
and the C ABI, out-of-range indices, another thread, close() and `with`, new-versus-stale
reports (take_pose, seq, arrival) and sender discovery."""

import gc
import threading
import time

import pytest

import vrpn
from conftest import pump


# ----------------------------------------------------------------------------- limits


@pytest.mark.parametrize("sensors", [0, -1, 1025, 10**8, 4_000_000_000, 2**64 - 1, 10**40])
def test_tracker_server_sensor_counts_are_bounded_like_the_config_file(sensors):
    server = vrpn.Server(0)
    t0 = time.monotonic()
    with pytest.raises(vrpn.LimitError, match=r"a tracker has 1 to 1024 sensors .*got " + str(sensors)):
        vrpn.TrackerServer(server, "T", sensors)
    # Refused before anything is allocated: no gigabytes, no abort.
    assert time.monotonic() - t0 < 1.0
    # A LimitError is both a VrpnError and a ValueError.
    assert issubclass(vrpn.LimitError, vrpn.VrpnError) and issubclass(vrpn.LimitError, ValueError)


def test_every_count_has_the_config_files_bounds():
    server = vrpn.Server(0)
    assert vrpn.TrackerServer(server, "T", sensors=1024).num_sensors == 1024
    assert vrpn.ButtonServer(server, "B", buttons=256).num_buttons == 256
    assert vrpn.AnalogServer(server, "A", channels=128).num_channels == 128
    assert vrpn.DialServer(server, "D", dials=128).num_dials == 128
    for make, n, words in [
        (vrpn.ButtonServer, 1000, "a button device has 1 to 256 buttons"),
        (vrpn.ButtonServer, 0, "a button device has 1 to 256 buttons"),
        (vrpn.AnalogServer, 129, "an analog device has 1 to 128 channels"),
        (vrpn.DialServer, 129, "a dial device has 1 to 128 dials"),
        (vrpn.DialServer, -3, "a dial device has 1 to 128 dials"),
    ]:
        with pytest.raises(vrpn.LimitError, match=words):
            make(server, "X", n)
    with pytest.raises(TypeError):
        vrpn.TrackerServer(server, "T2", 2.0)
    for port in (-1, 65536, 2**70):
        with pytest.raises(ValueError, match=f"port must be between 0 and 65535 .*got {port}"):
            vrpn.Server(port)


def test_names_clients_cannot_open_and_duplicates_are_refused():
    server = vrpn.Server(0)
    with pytest.raises(vrpn.DeviceNameError, match="must not contain '@'"):
        vrpn.TrackerServer(server, "Tracker0@host")
    with pytest.raises(vrpn.DeviceNameError, match="cannot be empty"):
        vrpn.ButtonServer(server, "")
    with pytest.raises(vrpn.DeviceNameError, match="at most 95"):
        vrpn.TextSender(server, "x" * 96)
    first = vrpn.TrackerServer(server, "Tracker0")
    with pytest.raises(vrpn.DeviceNameError, match='a tracker named "Tracker0" already exists'):
        vrpn.TrackerServer(server, "Tracker0", sensors=2)
    # Other interfaces under the same name make one VRPN device, as in C++.
    vrpn.ButtonServer(server, "Tracker0", 2)
    vrpn.TextSender(server, "Tracker0")
    # The name is free again once the first tracker is closed (or collected).
    first.close()
    assert vrpn.TrackerServer(server, "Tracker0", sensors=2).num_sensors == 2


# ----------------------------------------------------------------------------- indices


def test_out_of_range_reads_and_writes_raise():
    server = vrpn.Server(0)
    buttons = vrpn.ButtonServer(server, "Dev0", buttons=2)
    analog = vrpn.AnalogServer(server, "Dev0", channels=4)
    tracker = vrpn.TrackerServer(server, "Dev0", sensors=1)
    at = f"Dev0@127.0.0.1:{server.port}"
    b, a, t = vrpn.ButtonRemote(at), vrpn.AnalogRemote(at), vrpn.TrackerRemote(at)
    pump([server, b], lambda: b.num_buttons == 2, what="the button count")
    analog.report([0.5, 0.25, 0.0, -1.0])
    pump([server, a], lambda: a.latest() is not None, what="an analog report")

    assert b.button_state(1) == 0 and a.channel(3) == -1.0
    with pytest.raises(vrpn.OutOfRangeError, match=r"button 5 is out of range: the device has 2 buttons \(0 to 1\)"):
        b.button_state(5)
    with pytest.raises(IndexError):
        b.pressed(2)
    with pytest.raises(vrpn.OutOfRangeError, match="channel 9 is out of range: the device has 4 channels"):
        a.channel(9)
    with pytest.raises(vrpn.OutOfRangeError, match="sensor -1 is negative"):
        t.pose(-1)
    with pytest.raises(vrpn.VrpnError, match="sensor 1180591620717411303424 is out of range"):
        t.take_pose(2**70)
    assert t.pose(5) is None  # a sensor the server may have but has not reported

    with pytest.raises(vrpn.OutOfRangeError, match="button 2 is out of range"):
        buttons.set_button(2, True)
    with pytest.raises(vrpn.OutOfRangeError, match="channel -1 is negative"):
        analog.set_channel(-1, 0.0)
    with pytest.raises(vrpn.OutOfRangeError, match="sensor 1 is out of range: the device has 1 sensors"):
        tracker.report_pose(1, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


# ----------------------------------------------------------------------------- threads


def test_another_thread_gets_wrong_thread_error_and_the_object_stays_usable():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0")
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    caught = []

    def other():
        for call in (t.mainloop, lambda: t.pose(0), lambda: t.state, server.mainloop,
                     lambda: tracker.report_pose(0, (0, 0, 0), (0, 0, 0, 1)), t.close, server.close):
            try:
                call()
            except Exception as e:  # a VrpnError: an ordinary Exception, not a BaseException
                caught.append(e)

    th = threading.Thread(target=other)
    th.start()
    th.join()
    assert len(caught) == 7
    assert all(isinstance(e, vrpn.WrongThreadError) and isinstance(e, vrpn.VrpnError) for e in caught)
    assert "belongs to the thread that created it" in str(caught[0])
    assert "vrpn.TrackerRemote" in str(caught[0]) and "vrpn.Server" in str(caught[3])
    # Unharmed on its own thread.
    pump([server, t], lambda: t.connected, what="the connection")
    tracker.report_pose(0, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0))
    pump([server, t], lambda: t.pose(0) is not None, what="a pose")
    assert repr(t).endswith("connected>")


# ----------------------------------------------------------------------------- lifetimes


def test_close_releases_the_port_at_once_with_its_devices():
    gc.disable()  # no help from the garbage collector
    try:
        server = vrpn.Server(0)
        port = server.port
        tracker = vrpn.TrackerServer(server, "Tracker0")
        server.on_state_change(lambda s: server)  # a cycle through a callback
        t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{port}")
        pump([server, t], lambda: t.connected, what="the connection")
        server.close()
        assert server.closed
        again = vrpn.Server(port)  # the port is free now
        with pytest.raises(vrpn.ClosedError, match="this vrpn.Server is closed"):
            server.mainloop()
        with pytest.raises(vrpn.ClosedError, match="this vrpn.TrackerServer is closed"):
            tracker.report_pose(0, (0, 0, 0), (0, 0, 0, 1))
        server.close()  # twice is fine
        again.close()
        pump([t], lambda: t.state == "reconnecting", what="the client to see the server go")
        t.close()
        assert t.closed and repr(t) == '<vrpn.TrackerRemote "Tracker0" closed>'
        with pytest.raises(vrpn.ClosedError):
            t.pose(0)
    finally:
        gc.enable()


def test_with_blocks_close_servers_and_remotes():
    with vrpn.Server(0) as server:
        port = server.port
        tracker = vrpn.TrackerServer(server, "Tracker0")
        with vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{port}") as t:
            pump([server, t], lambda: t.connected, what="the connection")
        assert t.closed
    assert server.closed
    with pytest.raises(vrpn.ClosedError):
        tracker.num_sensors
    with vrpn.Server(port):  # free again, without a gc.collect()
        pass


def test_dropping_the_server_closes_it_deterministically():
    gc.disable()
    try:
        server = vrpn.Server(0)
        port = server.port
        vrpn.TrackerServer(server, "Tracker0")
        del server
        vrpn.Server(port).close()
    finally:
        gc.enable()


# ----------------------------------------------------------------------------- new or stale


def test_take_pose_seq_and_arrival_tell_new_from_stale():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0")
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    pump([server, t], lambda: t.connected, what="the connection")
    assert t.take_pose(0) is None
    tracker.report_pose(0, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), time=100.0)
    before = time.time()
    pump([server, t], lambda: t.pose(0) is not None, what="the first pose")
    first = t.take_pose(0)
    assert first is not None and first.seq == 1 and first.pos == (1.0, 0.0, 0.0)
    assert before - 1 <= first.arrival <= time.time() and first.sender_time == 100.0
    assert t.take_pose(0) is None and t.pose(0).seq == 1  # nothing new; the latest stays
    tracker.report_pose(0, (2.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    pump([server, t], lambda: t.pose(0).seq == 2, what="the second pose")
    second = t.take_pose(0)
    assert second.seq == 2 and second.pos == (2.0, 0.0, 0.0) and second.arrival >= first.arrival
    # The server dies: the last pose stays, nothing new comes, and its age grows.
    server.close()
    pump([t], lambda: t.state == "reconnecting", what="the drop")
    assert t.take_pose(0) is None and t.pose(0).seq == 2
    assert time.time() - t.pose(0).arrival >= 0.0 and not t.connected


def test_button_analog_and_dial_polling_takes():
    server = vrpn.Server(0)
    buttons = vrpn.ButtonServer(server, "Dev0", buttons=2)
    analog = vrpn.AnalogServer(server, "Dev0", channels=2)
    dials = vrpn.DialServer(server, "Dev0", dials=2)
    at = f"Dev0@127.0.0.1:{server.port}"
    b, a, d = vrpn.ButtonRemote(at), vrpn.AnalogRemote(at), vrpn.DialRemote(at)
    pump([server, b], lambda: b.connected and b.num_buttons == 2, what="the connection")
    for pressed in (True, False, True, False):  # two clicks between two frames
        buttons.set_button(1, pressed)
        buttons.report_changes()
    analog.report([0.5, 1.0])
    dials.report_rotation(1, 0.25)
    dials.report_rotation(1, 0.5)
    pump([server, b], lambda: d.last_update(1) is not None and d.last_update(1).seq == 2
         and a.latest() is not None and b.last_change(1) is not None and b.last_change(1).seq == 4,
         what="the reports")
    assert b.take_presses(1) == 2 and b.take_presses(1) == 0
    assert b.take_change(1).seq == 4 and b.take_change(1) is None
    assert a.take_report().channels == [0.5, 1.0] and a.take_report() is None
    assert d.take_rotation(1) == 0.75 and d.take_rotation(1) == 0.0


# ----------------------------------------------------------------------------- discovery


def test_sender_discovery_names_the_servers_devices():
    server = vrpn.Server(0)
    vrpn.TrackerServer(server, "Tracker0")
    vrpn.ButtonServer(server, "Button0")
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    described = []
    t.on_peer_sender(described.append)
    pump([server, t], lambda: "Button0" in t.peer_senders, what="the device names")
    assert {"Tracker0", "Button0"} <= set(t.peer_senders)
    assert {"Tracker0", "Button0"} <= set(described)
    assert all(isinstance(n, str) for n in server.peer_senders)
