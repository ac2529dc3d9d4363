"""VRPN, the Virtual-Reality Peripheral Network: clients and servers for trackers, buttons,
analogs, dials and text, wire-compatible with C++ VRPN 07.x.

Open a device by name, register callbacks, call ``mainloop()`` often::

    import time, vrpn
    t = vrpn.TrackerRemote("Tracker0@localhost")
    t.on_pose(lambda p: print(p.sensor, p.pos, p.quat))
    while True:
        t.mainloop()
        time.sleep(0.001)

Every object belongs to the thread that created it. See docs/PYTHON.md in the source.
"""

from ._vrpn import (
    Acceleration,
    AnalogRemote,
    AnalogReport,
    AnalogServer,
    ButtonChange,
    ButtonRemote,
    ButtonServer,
    ButtonStates,
    ClosedError,
    DeviceNameError,
    DialRemote,
    DialServer,
    DialUpdate,
    LimitError,
    LogFileError,
    Notice,
    OutOfRangeError,
    Pose,
    Remote,
    Replay,
    ResolveError,
    Server,
    TextMessage,
    TextReceiver,
    TextSender,
    TrackerRemote,
    TrackerServer,
    Velocity,
    VrpnError,
    WrongThreadError,
    __version__,
)

__all__ = [
    "Acceleration",
    "AnalogRemote",
    "AnalogReport",
    "AnalogServer",
    "ButtonChange",
    "ButtonRemote",
    "ButtonServer",
    "ButtonStates",
    "ClosedError",
    "DeviceNameError",
    "DialRemote",
    "DialServer",
    "DialUpdate",
    "LimitError",
    "LogFileError",
    "Notice",
    "OutOfRangeError",
    "Pose",
    "Remote",
    "Replay",
    "ResolveError",
    "Server",
    "TextMessage",
    "TextReceiver",
    "TextSender",
    "TrackerRemote",
    "TrackerServer",
    "Velocity",
    "VrpnError",
    "WrongThreadError",
    "__version__",
]
