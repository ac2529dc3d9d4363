"""Costs of the Python module per call, measured on 127.0.0.1 with a Python server and a
Python TrackerRemote in one process (run: python benches/python_bench.py after
`pip install .`). Not a test: it prints figures for docs/PYTHON.md.

- report_pose: one TrackerServer.report_pose() call (Python -> Rust, packs one message).
- receive, no callback: remote.mainloop() time per report read and decoded, no Python called.
- receive + callback: the same with a Python callback that counts (the difference is the
  report -> callback cost: building the Pose object and calling the function).
- receive + callback reading pos: the callback also reads p.pos (a tuple is built).
- pose(0): one latest-state poll.
- idle mainloop(): one mainloop() pass with nothing to read.
"""

import statistics
import time

import vrpn

BATCH = 100
ROUNDS = 300


def per_call(f, n):
    t0 = time.perf_counter()
    for _ in range(n):
        f()
    return (time.perf_counter() - t0) / n


def main():
    server = vrpn.Server(0)
    tracker = vrpn.TrackerServer(server, "Tracker0")
    remote = vrpn.TrackerRemote(f"Tracker0@127.0.0.1:{server.port}")
    end = time.monotonic() + 10
    while not (server.connected and remote.connected):
        if time.monotonic() > end:
            raise SystemExit("no connection")
        server.mainloop()
        remote.mainloop()
        time.sleep(0.001)
    # Let the UDP channel come up, so reports take the low-latency path as in real use.
    for _ in range(200):
        server.mainloop()
        remote.mainloop()
        time.sleep(0.001)

    seq = [0]
    pos, quat = (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0)

    def receive(count):
        """Seconds of remote.mainloop() per report: each round sends BATCH reports, waits
        for them to arrive, and times the one pass that reads them; `count()` tells how many
        reports the remote has seen (it is called outside the timed pass). Returns the median
        over the rounds (the machine is shared: the median ignores rounds another process
        interrupted) and the reports read in timed passes."""
        per_report = []
        got = 0
        for _ in range(ROUNDS):
            before = count()
            for _ in range(BATCH):
                seq[0] += 1
                tracker.report_pose(0, pos, quat, time=float(seq[0]))
            server.mainloop()
            time.sleep(0.003)
            t0 = time.perf_counter()
            remote.mainloop()
            spent = time.perf_counter() - t0
            n = count() - before
            if n:
                per_report.append(spent / n)
                got += n
            deadline = time.monotonic() + 1.0
            while count() < before + BATCH and time.monotonic() < deadline:
                remote.mainloop()
        return statistics.median(per_report), got

    results = []

    def report_once():
        seq[0] += 1
        tracker.report_pose(0, pos, quat, time=float(seq[0]))

    results.append(("report_pose()", per_call(report_once, 20000)))
    for _ in range(50):
        server.mainloop()
        remote.mainloop()
        time.sleep(0.001)

    polled = [0]

    def by_poll():
        p = remote.pose(0)
        return int(p.time) - start[0] if p else 0

    start = [seq[0]]
    cost, got = receive(by_poll)
    results.append((f"receive, no callback ({got} reports)", cost))

    n = [0]

    def counting(p):
        n[0] += 1

    h = remote.on_pose(counting)
    cost_cb, got = receive(lambda: n[0])
    results.append((f"receive + counting callback ({got} reports)", cost_cb))
    remote.remove_callback(h)

    def reading(p):
        n[0] += 1
        p.pos

    remote.on_pose(reading)
    cost_read, got = receive(lambda: n[0])
    results.append((f"receive + callback reading p.pos ({got} reports)", cost_read))

    results.append(("pose(0) poll", per_call(lambda: remote.pose(0), 200000)))
    polled[0] = per_call(remote.mainloop, 50000)
    results.append(("idle mainloop()", polled[0]))

    for name, secs in results:
        print(f"{name:45s} {secs * 1e9:8.0f} ns")
    print(f"{'report -> callback (difference)':45s} {(cost_cb - cost) * 1e9:8.0f} ns")


if __name__ == "__main__":
    main()
