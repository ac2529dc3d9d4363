"""Analog_Output, Poser and ForceDevice from Python, both sides, over 127.0.0.1: a remote's
requests reach the server's callbacks with their values, and the server's reports reach
the remote."""

import math

import pytest

import vrpn
from conftest import pump

HALF = math.sqrt(0.5)


def connected(server, remote):
    pump([server, remote], lambda: server.connected and remote.connected, what="connection")


def test_analog_output_requests_and_channel_count():
    server = vrpn.Server(0)
    out = vrpn.AnalogOutputServer(server, "Out0", channels=3)
    seen = []
    out.on_request(lambda r: seen.append(r.channels))
    remote = vrpn.AnalogOutputRemote(f"Out0@127.0.0.1:{server.port}")
    counts = []
    remote.on_num_channels(counts.append)
    connected(server, remote)
    # The server announces its count to each new client.
    pump([server, remote], lambda: remote.num_channels == 3, what="channel count")
    assert counts and counts[-1] == 3
    remote.request_change_channels([0.25, -0.5])
    pump([server, remote], lambda: len(seen) >= 1, what="request")
    assert seen[-1] == [0.25, -0.5, 0.0]
    remote.request_change_channel_value(2, 7.0)
    pump([server, remote], lambda: len(seen) >= 2, what="second request")
    assert out.values() == [0.25, -0.5, 7.0]
    with pytest.raises(vrpn.LimitError):
        vrpn.AnalogOutputServer(server, "Out1", channels=129)
    with pytest.raises(vrpn.DeviceNameError):
        vrpn.AnalogOutputServer(server, "Out0", channels=1)
    out.close()
    server.close()


def test_poser_absolute_and_relative_requests():
    server = vrpn.Server(0)
    poser = vrpn.PoserServer(server, "Poser0")
    absolute, relative = [], []
    poser.on_pose(absolute.append)
    poser.on_relative_pose(relative.append)
    remote = vrpn.PoserRemote(f"Poser0@127.0.0.1:{server.port}")
    connected(server, remote)
    remote.request_pose((0.5, 0.25, -0.125), (0.0, 0.0, HALF, HALF))
    pump([server, remote], lambda: absolute, what="absolute pose")
    assert absolute[0].pos == (0.5, 0.25, -0.125)
    assert absolute[0].quat == pytest.approx((0.0, 0.0, HALF, HALF))
    # Relative, as C++ does it: the remote adds the step to the pose it last asked for and
    # sends the sum (what the callback sees), which the server adds to its own pose, then
    # clamps to its workspace.
    remote.request_pose_relative((0.1, 0.0, 0.0))
    pump([server, remote], lambda: relative, what="relative pose")
    assert relative[0].pos == pytest.approx((0.6, 0.25, -0.125))
    assert poser.pose().pos == pytest.approx((1.0, 0.5, -0.25))
    server.close()


def test_force_device_both_ways():
    server = vrpn.Server(0)
    force = vrpn.ForceDeviceServer(server, "Phantom0")
    fields, planes, effects, requests = [], [], [], []
    force.on_force_field(fields.append)
    force.on_plane(planes.append)
    force.on_custom_effect(effects.append)
    force.on_request(lambda name, t: requests.append(name))
    remote = vrpn.ForceDeviceRemote(f"Phantom0@127.0.0.1:{server.port}")
    forces, scps, errors = [], [], []
    remote.on_force(forces.append)
    remote.on_scp(scps.append)
    remote.on_error(errors.append)
    connected(server, remote)
    remote.send_force_field((0.0, 0.1, 0.0), (1.0, 0.0, 0.0), ((-1, 0, 0), (0, -1, 0), (0, 0, -1)), 0.5)
    remote.start_surface((0.0, 1.0, 0.0, -0.25), kspring=0.75)
    remote.send_custom_effect(7, [1.5, 2.5])
    remote.stop_force_field()
    pump([server, remote], lambda: len(fields) >= 2 and planes and effects, what="requests")
    # The field goes LOW_LATENCY (UDP), the stop RELIABLE (TCP): either may come first.
    field = next(f for f in fields if not f.stops)
    assert field.origin == pytest.approx((0.0, 0.1, 0.0))
    assert field.jacobian[2] == [0.0, 0.0, -1.0]
    assert field.radius == 0.5
    assert any(f.stops for f in fields)
    assert planes[0].plane == pytest.approx((0.0, 1.0, 0.0, -0.25)) and planes[0].kspring == 0.75
    assert effects[0].effect_id == 7 and effects[0].params == [1.5, 2.5]
    assert requests == []
    force.report_force((0.5, -1.0, 2.0))
    force.report_scp((0.1, 0.2, 0.3), (0.0, 0.0, 0.0, 1.0))
    force.send_error(3)
    pump([server, remote], lambda: forces and scps and errors, what="reports")
    assert forces[0].force == (0.5, -1.0, 2.0)
    assert scps[0].pos == pytest.approx((0.1, 0.2, 0.3))
    assert errors[0].code == 3
    server.close()


def test_a_server_callback_that_raises_is_raised_by_mainloop():
    server = vrpn.Server(0)
    poser = vrpn.PoserServer(server, "Poser0")

    def boom(_):
        raise RuntimeError("from the callback")

    key = poser.on_pose(boom)
    remote = vrpn.PoserRemote(f"Poser0@127.0.0.1:{server.port}")
    connected(server, remote)
    remote.request_pose((1.0, 2.0, 3.0))
    with pytest.raises(RuntimeError, match="from the callback"):
        pump([server, remote], lambda: False, timeout=5, what="the exception")
    assert poser.remove_callback(key)
    with pytest.raises(ValueError):
        poser.remove_callback(key)
    server.close()
