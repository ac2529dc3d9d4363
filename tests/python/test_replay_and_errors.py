"""Replay of a log file recorded by vrpn_print_devices from vrpn_server (rate, seek, play-to),
and the errors a Python user sees for bad names, hosts, files and arguments."""

import pytest

import vrpn
from conftest import Child, VrpnServer, program, pump


@pytest.fixture(scope="module")
def recorded_log(tmp_path_factory):
    """A log of about 1.5 s of a 100 Hz, 1-sensor Spin tracker (recorded once per module)."""
    tmp = tmp_path_factory.mktemp("replay")
    cfg = tmp / "vrpn.cfg"
    cfg.write_text("vrpn_Tracker_Spin Tracker0 1 100.0 0 0 1 0.5\n")
    server = VrpnServer(cfg)
    path = tmp / "session.vrpn"
    try:
        child = Child([program("vrpn_print_devices"), "--seconds", "1.5", "--log", str(path),
                       f"Tracker0@127.0.0.1:{server.port}"])
        _, err = child.proc.communicate(timeout=30)
        child.stop()
    finally:
        server.stop()
    assert child.proc.returncode == 0, err
    return path


def replay_all(t, poses):
    t.replay.rate = float("inf")
    pump([t], lambda: t.replay.eof, what="the end of the log")
    t.mainloop()
    return list(poses)


def test_replay_delivers_the_recorded_poses(recorded_log):
    t = vrpn.TrackerRemote(f"Tracker0@file:{recorded_log}")
    poses = []
    t.on_pose(poses.append)
    r = t.replay
    assert r is not None and r.rate == 1.0 and not r.eof
    assert 1.0 < r.length < 2.0, r.length
    everything = replay_all(t, poses)
    assert len(everything) > 50
    times = [p.time for p in everything]
    assert times == sorted(times)
    # The log's first and last messages may be pings or texts: the poses lie within.
    assert r.start_time - 1e-6 <= times[0] < r.start_time + 0.1
    assert r.start_time + r.length - 0.1 < times[-1] <= r.start_time + r.length + 1e-6
    assert t.pose(0).time == times[-1]
    assert t.connected


def test_replay_paused_seek_and_play_to(recorded_log):
    t = vrpn.TrackerRemote(f"Tracker0@file:{recorded_log}")
    poses = []
    t.on_pose(poses.append)
    r = t.replay
    r.rate = 0.0
    for _ in range(50):
        t.mainloop()
    assert poses == [] and r.rate == 0.0

    half = r.length / 2
    assert r.seek(half)
    assert poses == []  # a seek delivers nothing in between
    r.play_to(half + 0.2)
    assert poses, "play_to delivers at once"
    assert all(half - 1e-3 <= p.time - r.start_time <= half + 0.2 + 1e-3 for p in poses)
    assert abs(r.position - (half + 0.2)) < 0.05

    poses.clear()
    r.reset()
    assert r.play_one() and len(poses) <= 1
    assert not r.seek(r.length + 10.0)


def test_replay_callback_exception_surfaces_from_the_control(recorded_log):
    t = vrpn.TrackerRemote(f"Tracker0@file:{recorded_log}")

    seen = []

    def bad(p):
        seen.append(p)
        if len(seen) == 1:
            raise RuntimeError("in replay")

    t.on_pose(bad)
    t.replay.rate = 0.0
    with pytest.raises(RuntimeError, match="in replay"):
        t.replay.play_to(0.5)
    assert len(seen) > 1  # the replay went on after the exception


def test_bad_names_hosts_and_files():
    with pytest.raises(vrpn.DeviceNameError, match="device name before '@' is empty"):
        vrpn.TrackerRemote("@localhost")
    with pytest.raises(vrpn.DeviceNameError, match="expected DEVICE@HOST"):
        vrpn.ButtonRemote("Button0@localhost:99999")
    # A name without "@HOST" says so, instead of failing to resolve "Tracker0" as a host.
    with pytest.raises(vrpn.DeviceNameError, match='no .@.: .* "Tracker0@localhost"'):
        vrpn.TrackerRemote("Tracker0")
    with pytest.raises(vrpn.ResolveError, match='cannot resolve host "no-such-host.invalid"'):
        vrpn.AnalogRemote("Analog0@no-such-host.invalid")
    with pytest.raises(vrpn.LogFileError, match="missing.vrpn"):
        vrpn.TrackerRemote("Tracker0@file:/nonexistent/missing.vrpn")
    # All of them are VrpnError.
    with pytest.raises(vrpn.VrpnError):
        vrpn.DialRemote("@x")


def test_a_file_that_is_not_a_log(tmp_path):
    path = tmp_path / "not-a-log.vrpn"
    path.write_bytes(b"this is not a VRPN log file at all, just text\n" * 4)
    with pytest.raises(vrpn.LogFileError, match="not-a-log.vrpn"):
        vrpn.TrackerRemote(f"Tracker0@file:{path}")


def test_bad_arguments():
    t = vrpn.TrackerRemote("Tracker0@127.0.0.1:9")
    with pytest.raises(TypeError, match="a callback must be callable, got int"):
        t.on_pose(42)
    with pytest.raises(ValueError, match='unknown connection event "connected"'):
        t.on_event("connected", lambda: None)
    with pytest.raises(ValueError, match="no callback with handle 999"):
        t.remove_callback(999)
    with pytest.raises(ValueError, match="timeout must be"):
        t.wait(-1.0)
    assert t.wait(0.0) in (True, False)


@pytest.mark.parametrize("control", ["rate", "seek", "play_to", "play_one", "reset", "queries"])
def test_every_replay_control_from_inside_a_callback(recorded_log, control):
    """Issue 29, item 1: a control called from a pose callback used to panic
    (PanicException) and break the remote for good."""
    t = vrpn.TrackerRemote(f"Tracker0@file:{recorded_log}")
    r = t.replay
    poses = []

    def cb(p):
        poses.append(p.time)
        if len(poses) != 5:
            return
        if control == "rate":
            r.rate = 2.0
        elif control == "seek":
            assert r.seek(r.length / 2)
        elif control == "play_to":
            r.play_to(r.length / 2)
        elif control == "play_one":
            assert r.play_one()
        elif control == "reset":
            r.reset()
        else:
            assert not r.eof and 0.0 <= r.position < r.length and r.start_time > 0

    t.on_pose(cb)
    r.rate = 0.0
    r.play_to(0.2)
    n = len(poses)
    assert n >= 5
    if control == "seek":
        # Nothing between the 5th pose and the middle of the log.
        assert abs(r.position - r.length / 2) < 1e-3
        assert poses[5:] == []
    if control == "play_to":
        assert abs(r.position - r.length / 2) < 1e-3
        assert all(a <= b for a, b in zip(poses, poses[1:]))
    if control == "reset":
        # Back to the start when the callback returned; the play-to ended with the old
        # position.
        assert n == 5 and r.position < 0.2
    # The remote still works: the rest plays, in order, and a reset from outside too.
    r.play_to(r.length + 1.0)
    assert r.eof and len(poses) > n
    if control == "reset":
        assert poses[5] == poses[0], "the replay started over after the callback"
    r.reset()
    assert not r.eof
    before = len(poses)
    r.play_to(0.2)
    assert len(poses) > before
