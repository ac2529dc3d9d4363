"""Helpers of the Python tests: the crate's programs as child processes on 127.0.0.1 (port 0,
stopped by their PID), and a pump that runs mainloop() until a condition holds."""

import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BIN_DIR = Path(os.environ.get("VRPN_BIN_DIR", ROOT / "target" / "release"))


def program(name):
    path = BIN_DIR / name
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo build --release --bin {name}` first")
    return str(path)


class Child:
    """A program we started; `stop()` kills it by its PID and reaps it."""

    def __init__(self, args, **kw):
        self.proc = subprocess.Popen(
            args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw
        )
        self.pid = self.proc.pid
        self.stderr = []

    def drain(self, first_line=False):
        """Reads stdout (after the first line when asked) and stderr in threads, so the child
        never blocks on a full pipe. Returns the first line."""
        line = self.proc.stdout.readline() if first_line else ""
        threading.Thread(target=self.proc.stdout.read, daemon=True).start()
        threading.Thread(target=lambda: self.stderr.append(self.proc.stderr.read()), daemon=True).start()
        return line

    def collect(self):
        """Reads stdout and stderr in threads while the caller runs its loop; `wait()` then
        returns (stdout, stderr)."""
        out, err = [], []
        self._readers = [
            threading.Thread(target=lambda: out.append(self.proc.stdout.read()), daemon=True),
            threading.Thread(target=lambda: err.append(self.proc.stderr.read()), daemon=True),
        ]
        for r in self._readers:
            r.start()
        self._collected = (out, err)

    def wait(self, timeout):
        self.proc.wait(timeout=timeout)
        for r in self._readers:
            r.join(timeout)
        out, err = self._collected
        return "".join(out), "".join(err)

    def stop(self):
        if self.proc.poll() is None:
            os.kill(self.pid, signal.SIGKILL)
        self.proc.wait(timeout=10)


class VrpnServer(Child):
    """target/release/vrpn_server on a configuration text; `port` is read from its first line."""

    def __init__(self, cfg_path, port=0):
        super().__init__([program("vrpn_server"), "-f", str(cfg_path), str(port)])
        line = self.drain(first_line=True)
        m = re.search(r"on port (\d+)", line)
        if not m:
            self.stop()
            raise AssertionError(f"vrpn_server did not report its port: {line!r}")
        self.port = int(m.group(1))


@pytest.fixture
def start_server(tmp_path):
    """start_server(cfg_text, port=0) -> VrpnServer; every server is stopped at the end."""
    started = []

    def start(cfg, port=0):
        path = tmp_path / f"vrpn-{len(started)}.cfg"
        path.write_text(cfg)
        s = VrpnServer(path, port)
        started.append(s)
        return s

    yield start
    for s in started:
        s.stop()


def pump(objects, until, timeout=5.0, what="the condition"):
    """Runs mainloop() of each object until `until()` is true; fails after `timeout` s."""
    end = time.monotonic() + timeout
    while not until():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        for o in objects:
            o.mainloop()
        time.sleep(0.001)
