"""The documented client runs as written, and objects stay on their thread."""

import re
import sys
import threading
import time

import pytest

import vrpn
from conftest import ROOT, Child


def python_block(path, after):
    text = path.read_text()
    start = text.index(after)
    m = re.search(r"```python\n(.*?)```", text[start:], re.S)
    return m.group(1)


@pytest.mark.parametrize("doc,heading", [("README.md", "## Python"), ("docs/PYTHON.md", "## The complete client")])
def test_the_documented_client_prints_poses(start_server, doc, heading):
    server = start_server("vrpn_Tracker_Spin Tracker0 1 50.0 0 0 1 0.5\n")
    code = python_block(ROOT / doc, heading)
    assert code.count("\n") <= 10 and '"Tracker0@localhost"' in code
    code = code.replace("Tracker0@localhost", f"Tracker0@127.0.0.1:{server.port}")
    client = Child([sys.executable, "-u", "-c", code])
    try:
        lines = [client.proc.stdout.readline() for _ in range(3)]
    finally:
        client.stop()
    for line in lines:
        # "0 (0.0, 0.0, 0.0) (0.0, 0.0, 0.3826..., 0.9238...)"
        assert re.fullmatch(r"0 \(0\.0, 0\.0, 0\.0\) \(0\.0, 0\.0, -?[0-9.e-]+, -?[0-9.e-]+\)\n", line), lines


def test_objects_refuse_another_thread():
    t = vrpn.TrackerRemote("Tracker0@127.0.0.1:9")
    caught = []

    def other():
        try:
            t.mainloop()
        except vrpn.VrpnError as e:  # an ordinary Exception, as C returns WRONG_THREAD
            caught.append(e)

    th = threading.Thread(target=other)
    th.start()
    th.join()
    assert len(caught) == 1 and isinstance(caught[0], vrpn.WrongThreadError)
    assert "cannot be used from another one" in str(caught[0])
    t.mainloop()  # still fine on its own thread
    assert t.pose(0) is None


def test_wait_lets_other_threads_run_and_wakes_on_data():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0")
    t = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    th = threading.Thread(target=ticker)
    th.start()
    try:
        # Nothing to read on an idle server: wait() sleeps (until its timeout or the server's
        # next deadline) with the GIL released.
        t0 = time.monotonic()
        while time.monotonic() - t0 < 0.3:
            assert server.wait(0.3) is False
        t1 = time.monotonic()
        during = [x for x in ticks if t0 < x < t1]
        assert len(during) >= 30, f"only {len(during)} ticks of the other thread in 0.3 s"
    finally:
        stop.set()
        th.join()
    # Data wakes it early.
    while not (server.connected and t.connected):
        server.wait(0.01)
        server.mainloop()
        t.wait(0.01)
        t.mainloop()
    tracker.report_pose(0, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0))
    server.mainloop()
    t0 = time.monotonic()
    while t.pose(0) is None:
        assert time.monotonic() - t0 < 5
        t.wait(5.0)
        t.mainloop()
    assert time.monotonic() - t0 < 1.0
