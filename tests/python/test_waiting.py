"""Waiting without spinning: wait() blocks in poll(2) on the connection's descriptor with the
GIL released, and fileno() lets asyncio wait on the same descriptor. Wake-ups are counted as
the thread's voluntary context switches (each is one sleep that ended)."""

import asyncio
import os
import signal
import threading
import time

import pytest

import vrpn

NULL = "vrpn_Tracker_NULL Tracker0 2 60.0\n"


def wakeups():
    """Voluntary context switches of the calling thread so far."""
    for line in open("/proc/thread-self/status"):
        if line.startswith("voluntary_ctxt_switches"):
            return int(line.split()[1])
    raise AssertionError("no voluntary_ctxt_switches in /proc/thread-self/status")


def connected_tracker(port):
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{port}")
    poses = []
    t.on_pose(poses.append)
    end = time.monotonic() + 10
    while len(poses) < 10:
        assert time.monotonic() < end, "no poses"
        t.wait(0.1)
        t.mainloop()
    return t, poses


def test_wait_wakes_once_per_datagram_not_every_millisecond(start_server):
    server = start_server(NULL)
    t, poses = connected_tracker(server.port)
    n0, w0, t0 = len(poses), wakeups(), time.monotonic()
    while time.monotonic() - t0 < 2.0:
        t.wait(0.1)
        t.mainloop()
    got, woke = len(poses) - n0, wakeups() - w0
    assert got >= 60, f"only {got} poses in 2 s from a 60 Hz two-sensor tracker"
    # Both sensors come in one datagram: about one wake-up per two poses. The old wait polled
    # every millisecond (about 900 wake-ups a second).
    assert woke <= 2 * got, f"{woke} wake-ups for {got} poses"
    assert woke / (time.monotonic() - t0) < 200, f"{woke} wake-ups in 2 s"


def test_idle_wait_sleeps_until_the_timeout(start_server):
    server = start_server("vrpn_Button_Example Button0 1 0.01\n")
    b = vrpn.ButtonRemote(f"Button0@127.0.0.1:{server.port}")
    end = time.monotonic() + 10
    while not b.connected:
        assert time.monotonic() < end, "never connected"
        b.wait(0.1)
        b.mainloop()
    for _ in range(20):  # let the connection settle (clock exchanges, pings)
        b.wait(0.05)
        b.mainloop()
    w0, t0 = wakeups(), time.monotonic()
    while time.monotonic() - t0 < 1.0:
        b.wait(0.5)
        b.mainloop()
    woke = wakeups() - w0
    # Liveness pings and clock exchanges wake it a few times a second at most.
    assert woke < 40, f"{woke} wake-ups in 1 s of an idle connection"


def test_wait_releases_the_gil_and_returns_at_its_timeout():
    # Nothing listens on port 9: the connection only has its retry deadlines.
    t = vrpn.TrackerRemote("Tracker0@127.0.0.1:9")
    t.mainloop()
    counted = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counted[0] += 1

    th = threading.Thread(target=count)
    th.start()
    try:
        t0 = time.monotonic()
        got = t.wait(0.3)
        elapsed = time.monotonic() - t0
    finally:
        stop.set()
        th.join()
    assert got is False
    assert elapsed <= 2.0
    assert counted[0] > 1000, "the other thread did not run during wait()"


def test_ctrl_c_interrupts_a_long_wait():
    t = vrpn.TrackerRemote("Tracker0@127.0.0.1:9")
    timer = threading.Timer(0.2, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        while time.monotonic() - t0 < 10:
            t.wait(10.0)
    timer.join()
    assert time.monotonic() - t0 < 5


def test_asyncio_add_reader_gets_poses_and_reconnects_through_the_descriptor(start_server):
    """The recipe of docs/PYTHON.md: the descriptor alone drives the remote, also for its
    timed work (the reconnection attempts after a server restart)."""
    server = start_server(NULL)
    port = server.port
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{port}")
    poses = []
    t.on_pose(poses.append)

    async def until(cond, timeout):
        end = time.monotonic() + timeout
        while not cond():
            assert time.monotonic() < end, "timed out"
            await asyncio.sleep(0.05)

    async def main():
        loop = asyncio.get_running_loop()
        loop.add_reader(t.fileno(), t.mainloop)
        t.mainloop()
        await until(lambda: len(poses) >= 20, 10)
        server.stop()
        stopped = time.time()
        await until(lambda: t.state == "reconnecting", 10)
        start_server(NULL, port=port)
        await until(lambda: t.connected and poses[-1].time > stopped, 15)
        loop.remove_reader(t.fileno())

    asyncio.run(main())


def test_fileno_is_the_same_for_remotes_sharing_a_connection_and_refused_for_a_replay(tmp_path):
    a = vrpn.TrackerRemote("Tracker0@127.0.0.1:9")
    b = vrpn.ButtonRemote("Tracker0@127.0.0.1:9")
    assert a.fileno() == b.fileno() >= 0
    server = vrpn.Server(0)
    assert server.fileno() >= 0 and server.fileno() != a.fileno()
    log = tmp_path / "empty.vrpn"
    log.write_bytes(b"vrpn: ver. 07.35\0" + bytes(7))
    try:
        r = vrpn.TrackerRemote(f"Tracker0@file:{log}")
    except vrpn.LogFileError:
        pytest.skip("this log header is not accepted")
    with pytest.raises(ValueError, match="no descriptor"):
        r.fileno()
