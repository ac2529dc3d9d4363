"""mainloop() returns while callbacks are slower than the data (issue 28, item 1), and Ctrl-C
(here: _thread.interrupt_main) reaches the program after the callback that saw it, not after a
pass that never ends."""

import _thread
import threading
import time

import pytest

import vrpn
from conftest import pump

FAST = "vrpn_Tracker_NULL Tracker0 1 500.0\n"


def slow_tracker(server, tcp, sleep=0.01, for_seconds=4.0):
    """A remote whose pose callback sleeps `sleep` s during its first `for_seconds` s, so that
    a pass that never ended before would end (and the test fail) rather than hang."""
    where = f"tcp://127.0.0.1:{server.port}" if tcp else f"127.0.0.1:{server.port}"
    t = vrpn.TrackerRemote(f"Tracker0@{where}")
    t.on_notice(lambda n: None)
    begun = time.monotonic()
    poses = []

    def slow(p):
        poses.append(p)
        if time.monotonic() - begun < for_seconds:
            time.sleep(sleep)

    t.on_pose(slow)
    return t, poses


@pytest.mark.parametrize("tcp", [False, True])
def test_mainloop_returns_while_a_slow_callback_falls_behind(start_server, tcp):
    server = start_server(FAST)
    t, poses = slow_tracker(server, tcp)
    pump([t], lambda: poses, what="the first pose")
    worst, passes = 0.0, 0
    end = time.monotonic() + 1.5
    while time.monotonic() < end:
        start = time.monotonic()
        t.mainloop()
        worst = max(worst, time.monotonic() - start)
        passes += 1
    # A pass lasts about 5 ms plus at most three 10 ms callbacks (margin for a loaded
    # machine); the 500 poses a second keep coming all along.
    assert worst < 0.25, f"a pass took {worst:.3f} s"
    assert passes >= 10 and len(poses) >= 50, (passes, len(poses))


def test_ctrl_c_ends_mainloop_after_the_callback_that_saw_it(start_server):
    server = start_server(FAST)
    t, poses = slow_tracker(server, tcp=True)
    pump([t], lambda: poses, what="the first pose")
    interrupted = []

    def ctrl_c():
        time.sleep(0.3)
        interrupted.append(time.monotonic())
        _thread.interrupt_main()

    threading.Thread(target=ctrl_c, daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        end = time.monotonic() + 10
        while time.monotonic() < end:
            t.mainloop()
    late = time.monotonic() - interrupted[0]
    assert late < 1.0, f"KeyboardInterrupt came {late:.2f} s after Ctrl-C"
    # The remote is still usable afterwards.
    n = len(poses)
    pump([t], lambda: len(poses) > n, what="a pose after the interruption")
