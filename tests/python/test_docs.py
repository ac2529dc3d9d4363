"""The documented client runs as written, and objects stay on their thread."""

import re
import sys
import threading

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
        except BaseException as e:  # pyo3's PanicException is a BaseException
            caught.append(e)

    th = threading.Thread(target=other)
    th.start()
    th.join()
    assert len(caught) == 1 and "unsendable" in str(caught[0])
    t.mainloop()  # still fine on its own thread
    assert t.pose(0) is None
