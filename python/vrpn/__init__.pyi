"""Type stubs of the vrpn module (the classes are implemented in Rust)."""

from types import TracebackType
from typing import Callable, List, Literal, Optional, Sequence, Tuple, Type, TypeVar, final

__version__: str
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

_Vec3 = Tuple[float, float, float]
_Quat = Tuple[float, float, float, float]
_ConnectionStateName = Literal["connecting", "connected", "reconnecting", "listening"]
_EventName = Literal[
    "got_first_connection", "got_connection", "dropped_connection", "dropped_last_connection"
]
_TextSeverityName = Literal["normal", "warning", "error"]

class VrpnError(Exception):
    """Base class of the errors the vrpn module raises."""

class DeviceNameError(VrpnError):
    """A device name that cannot be parsed."""

class ResolveError(VrpnError):
    """A host name that does not resolve to an IPv4 address."""

class LogFileError(VrpnError):
    """A log file that cannot be read or written."""

class WrongThreadError(VrpnError):
    """A VRPN object used from a thread other than the one that created it."""

class ClosedError(VrpnError):
    """A VRPN object used after close()."""

class OutOfRangeError(VrpnError, IndexError):
    """An index a device does not have (a sensor, button, channel or dial)."""

class LimitError(VrpnError, ValueError):
    """A count outside what a VRPN device may have (sensors, buttons, channels, dials)."""

_Self = TypeVar("_Self")

# ----------------------------------------------------------------------------- reports

@final
class Pose:
    """A tracker pose report."""
    @property
    def sensor(self) -> int: ...
    @property
    def pos(self) -> _Vec3:
        """Position (x, y, z), metres, in the tracker's frame."""
    @property
    def quat(self) -> _Quat:
        """Orientation quaternion (x, y, z, w): rotates the tracker's axes onto the sensor's."""
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch (translated to the
        local clock when clock synchronisation is in effect)."""
    @property
    def sender_time(self) -> float:
        """The stamp exactly as the server wrote it (its own clock)."""
    @property
    def arrival(self) -> float:
        """Local wall clock (seconds since the epoch) of the mainloop() that read it:
        ``time.time() - arrival`` is the value's age."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class Velocity:
    """A tracker velocity report. Every vector is in the tracker's (room) frame."""
    @property
    def sensor(self) -> int: ...
    @property
    def vel(self) -> _Vec3:
        """Linear velocity (x, y, z), m/s, in the tracker's frame."""
    @property
    def vel_quat(self) -> _Quat:
        """Rotation (x, y, z, w) the sensor undergoes in ``vel_quat_dt`` seconds, in the
        tracker's frame: the orientation ``vel_quat_dt`` later is ``vel_quat * quat``."""
    @property
    def vel_quat_dt(self) -> float:
        """Seconds ``vel_quat`` spans."""
    @property
    def angular_velocity(self) -> _Vec3:
        """Angular velocity (x, y, z), rad/s, in the tracker's frame: the rotation vector
        (axis times angle) of ``vel_quat`` divided by ``vel_quat_dt``."""
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch (translated to the
        local clock when clock synchronisation is in effect)."""
    @property
    def sender_time(self) -> float:
        """The stamp exactly as the server wrote it (its own clock)."""
    @property
    def arrival(self) -> float:
        """Local wall clock (seconds since the epoch) of the mainloop() that read it:
        ``time.time() - arrival`` is the value's age."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class Acceleration:
    """A tracker acceleration report."""
    @property
    def sensor(self) -> int: ...
    @property
    def acc(self) -> _Vec3:
        """Linear acceleration (x, y, z), m/s², in the tracker's frame."""
    @property
    def acc_quat(self) -> _Quat:
        """Change of the velocity rotation over ``acc_quat_dt`` seconds (tracker's frame)."""
    @property
    def acc_quat_dt(self) -> float: ...
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch (translated to the
        local clock when clock synchronisation is in effect)."""
    @property
    def sender_time(self) -> float:
        """The stamp exactly as the server wrote it (its own clock)."""
    @property
    def arrival(self) -> float:
        """Local wall clock (seconds since the epoch) of the mainloop() that read it:
        ``time.time() - arrival`` is the value's age."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class ButtonChange:
    """One button was pressed or released."""
    @property
    def button(self) -> int: ...
    @property
    def state(self) -> int:
        """1 pressed, 0 released."""
    @property
    def pressed(self) -> bool: ...
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch (translated to the
        local clock when clock synchronisation is in effect)."""
    @property
    def sender_time(self) -> float:
        """The stamp exactly as the server wrote it (its own clock)."""
    @property
    def arrival(self) -> float:
        """Local wall clock (seconds since the epoch) of the mainloop() that read it:
        ``time.time() - arrival`` is the value's age."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class ButtonStates:
    """The state of every button."""
    @property
    def states(self) -> List[int]: ...
    @property
    def num_buttons(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def sender_time(self) -> float: ...
    @property
    def arrival(self) -> float: ...

@final
class AnalogReport:
    """Every channel's value."""
    @property
    def channels(self) -> List[float]: ...
    @property
    def num_channels(self) -> int: ...
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch (translated to the
        local clock when clock synchronisation is in effect)."""
    @property
    def sender_time(self) -> float:
        """The stamp exactly as the server wrote it (its own clock)."""
    @property
    def arrival(self) -> float:
        """Local wall clock (seconds since the epoch) of the mainloop() that read it:
        ``time.time() - arrival`` is the value's age."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class DialUpdate:
    """A dial turned."""
    @property
    def dial(self) -> int: ...
    @property
    def change(self) -> float:
        """Revolutions since the previous report."""
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch (translated to the
        local clock when clock synchronisation is in effect)."""
    @property
    def sender_time(self) -> float:
        """The stamp exactly as the server wrote it (its own clock)."""
    @property
    def arrival(self) -> float:
        """Local wall clock (seconds since the epoch) of the mainloop() that read it:
        ``time.time() - arrival`` is the value's age."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class TextMessage:
    """A text message from a device."""
    @property
    def text(self) -> str: ...
    @property
    def severity(self) -> Literal["normal", "warning", "error", "other"]: ...
    @property
    def level(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def sender_time(self) -> float: ...

@final
class Notice:
    """A diagnostic from a connection."""
    @property
    def severity(self) -> Literal["info", "warning", "error"]: ...
    @property
    def text(self) -> str: ...

# ----------------------------------------------------------------------------- clients

@final
class Replay:
    """Controls of a log replay (``remote.replay`` of a ``Device@file:PATH`` remote)."""
    rate: float
    """1.0 real time, 0 paused, 10 ten times faster, float("inf") as fast as possible."""
    def seek(self, secs: float) -> bool:
        """Moves to ``secs`` after the first message without delivering those in between."""
    def play_to(self, secs: float) -> None:
        """Delivers, now, every message up to ``secs`` after the first one."""
    def play_one(self) -> bool:
        """Delivers the next message now; False at the end of the log."""
    def reset(self) -> None:
        """Back to the start."""
    @property
    def eof(self) -> bool: ...
    @property
    def position(self) -> float:
        """Seconds since the first message."""
    @property
    def length(self) -> float:
        """Seconds between the first and the last message."""
    @property
    def start_time(self) -> Optional[float]: ...

class Remote:
    """Base class of the remotes: the connection, its state and events, ``mainloop()``."""
    def mainloop(self) -> None:
        """Reads what arrived and runs the callbacks; raises a callback's exception."""
    def wait(self, timeout: float) -> bool:
        """Sleeps (GIL released) until data arrives, work is due or ``timeout`` s pass."""
    def fileno(self) -> int:
        """The descriptor for asyncio's ``add_reader`` or ``select``: readable when data
        arrives or timed work is due. Raises ValueError for a replay."""
    @property
    def device(self) -> str: ...
    @property
    def connected(self) -> bool: ...
    @property
    def state(self) -> _ConnectionStateName: ...
    @property
    def closed(self) -> bool: ...
    @property
    def replay(self) -> Optional[Replay]: ...
    def on_event(self, event: _EventName, f: Callable[[], object]) -> int: ...
    def on_state_change(self, f: Callable[[_ConnectionStateName], object]) -> int: ...
    def on_notice(self, f: Callable[[Notice], object]) -> int: ...
    def on_peer_sender(self, f: Callable[[str], object]) -> int:
        """Calls ``f(name)`` with each device name the server describes, as it does."""
    @property
    def peer_senders(self) -> List[str]:
        """The device names the server has described so far."""
    def remove_callback(self, handle: int) -> None: ...
    def close(self) -> None:
        """Releases the remote now (its connection closes once no other remote uses it)."""
    def __enter__(self: _Self) -> _Self: ...
    def __exit__(
        self,
        ty: Optional[Type[BaseException]],
        value: Optional[BaseException],
        traceback: Optional[TracebackType],
    ) -> bool: ...

@final
class TrackerRemote(Remote):
    """Client of a tracker: ``TrackerRemote("Tracker0@host")``."""
    def __new__(cls, name: str) -> TrackerRemote: ...
    def on_pose(self, f: Callable[[Pose], object], sensor: Optional[int] = None) -> int: ...
    def on_velocity(self, f: Callable[[Velocity], object]) -> int: ...
    def on_acceleration(self, f: Callable[[Acceleration], object]) -> int: ...
    def pose(self, sensor: int = 0) -> Optional[Pose]:
        """The latest pose of ``sensor``, None until one arrived (kept after the server went
        away: check ``state`` or the pose's ``arrival``)."""
    def take_pose(self, sensor: int = 0) -> Optional[Pose]:
        """The latest pose if it arrived since the last ``take_pose(sensor)``, else None."""
    def velocity(self, sensor: int = 0) -> Optional[Velocity]: ...
    def take_velocity(self, sensor: int = 0) -> Optional[Velocity]: ...
    def acceleration(self, sensor: int = 0) -> Optional[Acceleration]: ...
    def take_acceleration(self, sensor: int = 0) -> Optional[Acceleration]: ...
    @property
    def sensor_count(self) -> int: ...
    def set_update_rate(self, hz: float) -> None: ...
    def reset_origin(self) -> None: ...

@final
class ButtonRemote(Remote):
    """Client of a button device: ``ButtonRemote("Button0@host")``."""
    def __new__(cls, name: str) -> ButtonRemote: ...
    def on_change(self, f: Callable[[ButtonChange], object]) -> int: ...
    def on_states(self, f: Callable[[ButtonStates], object]) -> int: ...
    def button_state(self, i: int) -> int:
        """1 pressed, 0 released (or unknown); ``OutOfRangeError`` beyond ``num_buttons``."""
    def pressed(self, i: int) -> bool: ...
    def take_presses(self, i: int) -> int:
        """Presses of button ``i`` since the last ``take_presses(i)``."""
    def last_change(self, i: int) -> Optional[ButtonChange]: ...
    def take_change(self, i: int) -> Optional[ButtonChange]: ...
    @property
    def num_buttons(self) -> int:
        """256 until the server's full-state report gives the count."""

@final
class AnalogRemote(Remote):
    """Client of an analog device: ``AnalogRemote("Analog0@host")``."""
    def __new__(cls, name: str) -> AnalogRemote: ...
    def on_report(self, f: Callable[[AnalogReport], object]) -> int: ...
    def latest(self) -> Optional[AnalogReport]: ...
    def take_report(self) -> Optional[AnalogReport]: ...
    def channel(self, i: int) -> float:
        """0.0 before the first report; ``OutOfRangeError`` beyond the reported count."""
    @property
    def num_channels(self) -> int: ...

@final
class DialRemote(Remote):
    """Client of a dial device: ``DialRemote("Dial0@host")``."""
    def __new__(cls, name: str) -> DialRemote: ...
    def on_update(self, f: Callable[[DialUpdate], object]) -> int: ...
    def last_update(self, i: int) -> Optional[DialUpdate]: ...
    def take_rotation(self, i: int) -> float:
        """Revolutions dial ``i`` turned since the last ``take_rotation(i)``."""

@final
class TextReceiver(Remote):
    """Receives a device's text messages: ``TextReceiver("Tracker0@host")``."""
    def __new__(cls, name: str) -> TextReceiver: ...
    def on_message(self, f: Callable[[TextMessage], object]) -> int: ...
    @property
    def received(self) -> int: ...

# ----------------------------------------------------------------------------- servers

@final
class Server:
    """A server connection: UDP and TCP on one port, for any number of clients."""
    def __new__(cls, port: int = 3883, nic: Optional[str] = None) -> Server: ...
    def mainloop(self) -> None: ...
    def wait(self, timeout: float) -> bool: ...
    def fileno(self) -> int: ...
    @property
    def port(self) -> Optional[int]: ...
    @property
    def connected(self) -> bool: ...
    @property
    def connected_peers(self) -> int: ...
    @property
    def state(self) -> _ConnectionStateName: ...
    @property
    def closed(self) -> bool: ...
    def on_event(self, event: _EventName, f: Callable[[], object]) -> int: ...
    def on_state_change(self, f: Callable[[_ConnectionStateName], object]) -> int: ...
    def on_notice(self, f: Callable[[Notice], object]) -> int: ...
    def on_peer_sender(self, f: Callable[[str], object]) -> int:
        """Calls ``f(name)`` with each sender name a client describes."""
    @property
    def peer_senders(self) -> List[str]: ...
    def remove_callback(self, handle: int) -> None: ...
    def close(self) -> None:
        """Releases the port and closes every device server made on this server, now."""
    def __enter__(self: _Self) -> _Self: ...
    def __exit__(
        self,
        ty: Optional[Type[BaseException]],
        value: Optional[BaseException],
        traceback: Optional[TracebackType],
    ) -> bool: ...

@final
class TrackerServer:
    """A tracker on a Server: ``TrackerServer(server, "Tracker0", sensors=1)``; 1 to 1024
    sensors (``LimitError`` otherwise), a name without '@' that no other tracker on the
    server has (``DeviceNameError`` otherwise)."""
    def __new__(cls, server: Server, name: str, sensors: int = 1) -> TrackerServer: ...
    def report_pose(
        self, sensor: int, pos: Sequence[float], quat: Sequence[float], time: Optional[float] = None
    ) -> None: ...
    def report_velocity(
        self,
        sensor: int,
        vel: Sequence[float],
        vel_quat: Sequence[float] = ...,
        dt: float = 1.0,
        time: Optional[float] = None,
    ) -> None: ...
    def send_text(self, text: str, severity: _TextSeverityName = "normal", level: int = 0) -> None: ...
    @property
    def num_sensors(self) -> int: ...
    def close(self) -> None: ...

@final
class ButtonServer:
    """Buttons on a Server: ``ButtonServer(server, "Button0", buttons=1)``; 1 to 256."""
    def __new__(cls, server: Server, name: str, buttons: int = 1) -> ButtonServer: ...
    def set_button(self, i: int, pressed: bool) -> None: ...
    def report_changes(self, time: Optional[float] = None) -> None: ...
    def report_states(self) -> None: ...
    @property
    def num_buttons(self) -> int: ...
    def close(self) -> None: ...

@final
class AnalogServer:
    """Analog channels on a Server: ``AnalogServer(server, "Analog0", channels=1)``; 1 to 128."""
    def __new__(cls, server: Server, name: str, channels: int = 1) -> AnalogServer: ...
    def set_channel(self, i: int, value: float) -> None: ...
    def report(
        self, values: Optional[Sequence[float]] = None, time: Optional[float] = None
    ) -> None: ...
    def report_changes(self, time: Optional[float] = None) -> bool: ...
    @property
    def num_channels(self) -> int: ...
    def close(self) -> None: ...

@final
class DialServer:
    """Dials on a Server: ``DialServer(server, "Dial0", dials=1)``; 1 to 128."""
    def __new__(cls, server: Server, name: str, dials: int = 1) -> DialServer: ...
    def report_rotation(self, i: int, revolutions: float, time: Optional[float] = None) -> None: ...
    @property
    def num_dials(self) -> int: ...
    def close(self) -> None: ...

@final
class TextSender:
    """Sends text messages as a device: ``TextSender(server, "Tracker0")``."""
    def __new__(cls, server: Server, name: str) -> TextSender: ...
    def send(
        self,
        text: str,
        severity: _TextSeverityName = "normal",
        level: int = 0,
        time: Optional[float] = None,
    ) -> None: ...
    def close(self) -> None: ...
