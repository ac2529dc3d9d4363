"""Float seconds at the edges: replay positions beyond any time saturate, NaN is refused, and a
report time a message cannot carry is a ValueError instead of a wrapped timestamp."""

import math

import pytest

import vrpn
from conftest import ROOT

GOLDEN_LOG = ROOT / "tests" / "fixtures" / "golden" / "tracker_udp_lob.out.vrpn"
POSES_IN_LOG = 410


def paused_replay():
    t = vrpn.TrackerRemote(f"Tracker0@file:{GOLDEN_LOG}")
    poses = []
    t.on_pose(poses.append)
    t.replay.rate = 0.0
    return t, poses


@pytest.mark.parametrize("far", [1e14, 1e300, math.inf])
def test_seek_and_play_to_far_beyond_the_log_saturate(far):
    t, poses = paused_replay()
    r = t.replay
    assert not r.seek(far), "past the end of the log"
    assert r.length < r.position <= 2**62 * 1e-6
    assert poses == []
    r.reset()
    r.play_to(far)
    assert len(poses) == POSES_IN_LOG
    assert r.eof


def test_nan_positions_are_refused_and_move_nothing():
    t, poses = paused_replay()
    r = t.replay
    assert r.seek(1.0)
    with pytest.raises(ValueError, match="nan"):
        r.seek(math.nan)
    with pytest.raises(ValueError, match="nan"):
        r.play_to(math.nan)
    assert abs(r.position - 1.0) < 1e-6
    assert poses == []


@pytest.mark.parametrize("bad", [1e300, -1.0, 2.0**32, math.inf, math.nan])
def test_report_times_a_message_cannot_carry_are_value_errors(bad):
    server = vrpn.Server(0, "127.0.0.1")
    tracker = vrpn.TrackerServer(server, "Tracker0")
    with pytest.raises(ValueError, match="time must be between 0 and 4294967295"):
        tracker.report_pose(0, (0, 0, 0), (0, 0, 0, 1), time=bad)
    buttons = vrpn.ButtonServer(server, "Button0")
    with pytest.raises(ValueError, match="time must be between"):
        buttons.report_changes(time=bad)
    text = vrpn.TextSender(server, "Text0")
    with pytest.raises(ValueError, match="time must be between"):
        text.send("hello", time=bad)
    # The edge itself is fine.
    tracker.report_pose(0, (0, 0, 0), (0, 0, 0, 1), time=4294967295.5)
