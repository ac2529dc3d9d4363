"""What a waiting Python client costs: CPU and wake-ups of `while True: t.wait(0.1);
t.mainloop()` reading a 60 Hz two-sensor tracker (`vrpn_Tracker_NULL Tracker0 2 60.0`) from
our vrpn_server on 127.0.0.1. Not a test: it prints figures for docs/PYTHON.md.

Run after `pip install .` and `cargo build --release --bin vrpn_server`:

    python benches/python_wait_bench.py [SECONDS] [--loop wait|asyncio|sleep]

The client measures itself over the window (after a 2 s warm-up): CPU time from
/proc/self/schedstat (time on a CPU, all threads of the process are one here), wake-ups as voluntary context switches from
/proc/self/status (each is one sleep that ended), and the poses its callback received.
`--loop asyncio` waits with `loop.add_reader(t.fileno(), t.mainloop)` instead; `--loop
sleep` is the README's `mainloop(); time.sleep(0.001)` loop, for comparison.
"""

import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SERVER = Path(os.environ.get("VRPN_BIN_DIR", ROOT / "target" / "release")) / "vrpn_server"

CLIENT = r"""
import asyncio, json, os, sys, time
import vrpn

name, seconds, mode = sys.argv[1], float(sys.argv[2]), sys.argv[3]

def cpu():
    # Time on a CPU in ns (schedstat: exact, unlike the tick-sampled utime and stime).
    return int(open("/proc/self/schedstat").read().split()[0]) / 1e9

def switches():
    v = n = 0
    for line in open("/proc/self/status"):
        if line.startswith("voluntary_ctxt_switches"):
            v = int(line.split()[1])
        elif line.startswith("nonvoluntary_ctxt_switches"):
            n = int(line.split()[1])
    return v, n

t = vrpn.TrackerRemote(name)
poses = [0]
t.on_pose(lambda p: poses.__setitem__(0, poses[0] + 1))
end_warm = time.monotonic() + 2.0
marks = {}

def mark(key):
    marks[key] = (time.monotonic(), cpu(), switches(), poses[0])

def done():
    now = time.monotonic()
    if "start" not in marks and now >= end_warm:
        mark("start")
    return "start" in marks and now >= marks["start"][0] + seconds

if mode == "wait":
    while not done():
        t.wait(0.1)
        t.mainloop()
elif mode == "sleep":
    while not done():
        t.mainloop()
        time.sleep(0.001)
else:
    async def main():
        loop = asyncio.get_running_loop()
        finished = loop.create_future()
        def ready():
            t.mainloop()
            if done() and not finished.done():
                finished.set_result(None)
        loop.add_reader(t.fileno(), ready)
        t.mainloop()
        while not finished.done():
            # Only to end the run on time: the reader does the work.
            await asyncio.wait([finished], timeout=0.5)
            if done() and not finished.done():
                finished.set_result(None)
        loop.remove_reader(t.fileno())
    asyncio.run(main())
mark("end")
(t0, c0, (v0, n0), p0), (t1, c1, (v1, n1), p1) = marks["start"], marks["end"]
dt = t1 - t0
print(json.dumps({"seconds": dt, "cpu_percent": 100 * (c1 - c0) / dt,
                  "wakeups_per_s": (v1 - v0) / dt, "preemptions_per_s": (n1 - n0) / dt,
                  "poses_per_s": (p1 - p0) / dt,
                  "wakeups_per_pose": (v1 - v0) / max(1, p1 - p0)}))
"""


def main():
    args = sys.argv[1:]
    mode = "wait"
    if "--loop" in args:
        i = args.index("--loop")
        mode = args[i + 1]
        del args[i : i + 2]
    seconds = float(args[0]) if args else 10.0
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "bench.cfg"
        cfg.write_text("vrpn_Tracker_NULL Tracker0 2 60.0\n")
        server = subprocess.Popen([str(SERVER), "-f", str(cfg), "0"], stdout=subprocess.PIPE, text=True)
        try:
            m = re.search(r"on port (\d+)", server.stdout.readline())
            if not m:
                raise SystemExit("vrpn_server did not report its port")
            name = f"Tracker0@127.0.0.1:{m.group(1)}"
            out = subprocess.run(
                [sys.executable, "-c", CLIENT, name, str(seconds), mode],
                capture_output=True, text=True, timeout=seconds + 60,
            )
            if out.returncode != 0:
                raise SystemExit(out.stderr)
            r = json.loads(out.stdout)
        finally:
            server.kill()
            server.wait()
    print(f"loop={mode}: {r['cpu_percent']:.2f}% CPU, {r['wakeups_per_s']:.1f} wake-ups/s "
          f"({r['wakeups_per_pose']:.2f} per pose), {r['poses_per_s']:.1f} poses/s, "
          f"{r['preemptions_per_s']:.1f} preemptions/s over {r['seconds']:.1f} s")


if __name__ == "__main__":
    main()
