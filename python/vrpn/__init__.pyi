"""Type stubs of the vrpn module (the classes are implemented in Rust)."""

from typing import Callable, List, Literal, Optional, Sequence, Tuple, final

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
    "DeviceNameError",
    "DialRemote",
    "DialServer",
    "DialUpdate",
    "LogFileError",
    "Notice",
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

# ----------------------------------------------------------------------------- reports

@final
class Pose:
    """A tracker pose report."""
    @property
    def sensor(self) -> int: ...
    @property
    def pos(self) -> _Vec3:
        """Position (x, y, z), metres."""
    @property
    def quat(self) -> _Quat:
        """Orientation quaternion (x, y, z, w)."""
    @property
    def time(self) -> float:
        """Time the server stamped on the report, seconds since the epoch."""

@final
class Velocity:
    """A tracker velocity report."""
    @property
    def sensor(self) -> int: ...
    @property
    def vel(self) -> _Vec3: ...
    @property
    def vel_quat(self) -> _Quat: ...
    @property
    def vel_quat_dt(self) -> float: ...
    @property
    def angular_velocity(self) -> _Vec3:
        """Rad/s, as a rotation vector."""
    @property
    def time(self) -> float: ...

@final
class Acceleration:
    """A tracker acceleration report."""
    @property
    def sensor(self) -> int: ...
    @property
    def acc(self) -> _Vec3: ...
    @property
    def acc_quat(self) -> _Quat: ...
    @property
    def acc_quat_dt(self) -> float: ...
    @property
    def time(self) -> float: ...

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
    def time(self) -> float: ...

@final
class ButtonStates:
    """The state of every button."""
    @property
    def states(self) -> List[int]: ...
    @property
    def num_buttons(self) -> int: ...
    @property
    def time(self) -> float: ...

@final
class AnalogReport:
    """Every channel's value."""
    @property
    def channels(self) -> List[float]: ...
    @property
    def num_channels(self) -> int: ...
    @property
    def time(self) -> float: ...

@final
class DialUpdate:
    """A dial turned."""
    @property
    def dial(self) -> int: ...
    @property
    def change(self) -> float:
        """Revolutions since the previous report."""
    @property
    def time(self) -> float: ...

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
    def replay(self) -> Optional[Replay]: ...
    def on_event(self, event: _EventName, f: Callable[[], object]) -> int: ...
    def on_state_change(self, f: Callable[[_ConnectionStateName], object]) -> int: ...
    def on_notice(self, f: Callable[[Notice], object]) -> int: ...
    def remove_callback(self, handle: int) -> None: ...

@final
class TrackerRemote(Remote):
    """Client of a tracker: ``TrackerRemote("Tracker0@host")``."""
    def __new__(cls, name: str) -> TrackerRemote: ...
    def on_pose(self, f: Callable[[Pose], object], sensor: Optional[int] = None) -> int: ...
    def on_velocity(self, f: Callable[[Velocity], object]) -> int: ...
    def on_acceleration(self, f: Callable[[Acceleration], object]) -> int: ...
    def pose(self, sensor: int = 0) -> Optional[Pose]:
        """The latest pose of ``sensor``, None until one arrived."""
    def velocity(self, sensor: int = 0) -> Optional[Velocity]: ...
    def acceleration(self, sensor: int = 0) -> Optional[Acceleration]: ...
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
    def button_state(self, i: int) -> int: ...
    def pressed(self, i: int) -> bool: ...
    @property
    def num_buttons(self) -> int: ...

@final
class AnalogRemote(Remote):
    """Client of an analog device: ``AnalogRemote("Analog0@host")``."""
    def __new__(cls, name: str) -> AnalogRemote: ...
    def on_report(self, f: Callable[[AnalogReport], object]) -> int: ...
    def latest(self) -> Optional[AnalogReport]: ...
    def channel(self, i: int) -> float: ...
    @property
    def num_channels(self) -> int: ...

@final
class DialRemote(Remote):
    """Client of a dial device: ``DialRemote("Dial0@host")``."""
    def __new__(cls, name: str) -> DialRemote: ...
    def on_update(self, f: Callable[[DialUpdate], object]) -> int: ...

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
    def on_event(self, event: _EventName, f: Callable[[], object]) -> int: ...
    def on_state_change(self, f: Callable[[_ConnectionStateName], object]) -> int: ...
    def on_notice(self, f: Callable[[Notice], object]) -> int: ...
    def remove_callback(self, handle: int) -> None: ...

@final
class TrackerServer:
    """A tracker on a Server: ``TrackerServer(server, "Tracker0", sensors=1)``."""
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

@final
class ButtonServer:
    """Buttons on a Server: ``ButtonServer(server, "Button0", buttons=1)``."""
    def __new__(cls, server: Server, name: str, buttons: int = 1) -> ButtonServer: ...
    def set_button(self, i: int, pressed: bool) -> None: ...
    def report_changes(self, time: Optional[float] = None) -> None: ...
    def report_states(self) -> None: ...
    @property
    def num_buttons(self) -> int: ...

@final
class AnalogServer:
    """Analog channels on a Server: ``AnalogServer(server, "Analog0", channels=1)``."""
    def __new__(cls, server: Server, name: str, channels: int = 1) -> AnalogServer: ...
    def set_channel(self, i: int, value: float) -> None: ...
    def report(
        self, values: Optional[Sequence[float]] = None, time: Optional[float] = None
    ) -> None: ...
    def report_changes(self, time: Optional[float] = None) -> bool: ...
    @property
    def num_channels(self) -> int: ...

@final
class DialServer:
    """Dials on a Server: ``DialServer(server, "Dial0", dials=1)``."""
    def __new__(cls, server: Server, name: str, dials: int = 1) -> DialServer: ...
    def report_rotation(self, i: int, revolutions: float, time: Optional[float] = None) -> None: ...
    @property
    def num_dials(self) -> int: ...

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
