"""Type stubs of the vrpn module (the classes are implemented in Rust)."""

from types import TracebackType
from typing import Callable, Generic, List, Literal, Optional, Sequence, Tuple, Type, TypeVar, final

__version__: str
__all__ = [
    "Acceleration",
    "AnalogOutputRemote",
    "AnalogOutputRequest",
    "AnalogOutputServer",
    "AnalogRemote",
    "AnalogReport",
    "AnalogServer",
    "ButtonChange",
    "ButtonRemote",
    "ButtonServer",
    "ButtonStates",
    "ClosedError",
    "CustomEffect",
    "DeviceNameError",
    "DialRemote",
    "DialServer",
    "DialUpdate",
    "ForceDeviceRemote",
    "ForceDeviceServer",
    "ForceErrorReport",
    "ForceFieldRequest",
    "ForceReport",
    "ImagerChannel",
    "ImagerDescription",
    "ImagerDiscarded",
    "ImagerFrame",
    "ImagerRegion",
    "ImagerRemote",
    "ImagerServer",
    "LimitError",
    "LogFileError",
    "MutexRemote",
    "MutexServer",
    "Notice",
    "OutOfRangeError",
    "PlaneRequest",
    "PeerMutex",
    "Pose",
    "PoserRemote",
    "PoserRequest",
    "PoserServer",
    "Remote",
    "Replay",
    "ResolveError",
    "ScpReport",
    "Server",
    "SharedChange",
    "SharedFloat64",
    "SharedInt32",
    "SharedString",
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
_T = TypeVar("_T")

# ----------------------------------------------------------------------------- reports

class _Stamped:
    """The stamps a report carries (stub only: not a class of the module)."""
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

class _Report(_Stamped):
    """A report of one sensor, button, dial or analog device (stub only)."""
    @property
    def seq(self) -> int:
        """1 for the first report of its sensor/button/dial this remote received, then 2, ...:
        the same ``seq`` twice means nothing new arrived."""

@final
class Pose(_Report):
    """A tracker pose report."""
    @property
    def sensor(self) -> int: ...
    @property
    def pos(self) -> _Vec3:
        """Position (x, y, z), metres, in the tracker's frame."""
    @property
    def quat(self) -> _Quat:
        """Orientation quaternion (x, y, z, w): rotates the tracker's axes onto the sensor's."""

@final
class Velocity(_Report):
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

@final
class Acceleration(_Report):
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

@final
class ButtonChange(_Report):
    """One button was pressed or released."""
    @property
    def button(self) -> int: ...
    @property
    def state(self) -> int:
        """1 pressed, 0 released."""
    @property
    def pressed(self) -> bool: ...

@final
class ButtonStates(_Stamped):
    """The state of every button."""
    @property
    def states(self) -> List[int]: ...
    @property
    def num_buttons(self) -> int: ...

@final
class AnalogReport(_Report):
    """Every channel's value."""
    @property
    def channels(self) -> List[float]: ...
    @property
    def num_channels(self) -> int: ...

@final
class DialUpdate(_Report):
    """A dial turned."""
    @property
    def dial(self) -> int: ...
    @property
    def change(self) -> float:
        """Revolutions since the previous report."""

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

class _Polled:
    """An object with its own connection, polled by its ``mainloop()``; ``with`` closes it
    (stub only: not a class of the module)."""
    def mainloop(self) -> None:
        """Reads what arrived and runs the callbacks; raises a callback's exception."""
    def wait(self, timeout: float) -> bool:
        """Sleeps (GIL released) until data arrives, work is due or ``timeout`` s pass."""
    def fileno(self) -> int:
        """The descriptor for asyncio's ``add_reader`` or ``select``: readable when data
        arrives or timed work is due."""
    def remove_callback(self, handle: int) -> None: ...
    def close(self) -> None: ...
    def __enter__(self: _Self) -> _Self: ...
    def __exit__(
        self,
        ty: Optional[Type[BaseException]],
        value: Optional[BaseException],
        traceback: Optional[TracebackType],
    ) -> bool: ...

class _Connected(_Polled):
    """A remote's or a server's connection: its state and events (stub only)."""
    @property
    def connected(self) -> bool: ...
    @property
    def state(self) -> _ConnectionStateName: ...
    @property
    def closed(self) -> bool: ...
    def on_event(self, event: _EventName, f: Callable[[], object]) -> int: ...
    def on_state_change(self, f: Callable[[_ConnectionStateName], object]) -> int: ...
    def on_notice(self, f: Callable[[Notice], object]) -> int: ...
    @property
    def peer_senders(self) -> List[str]:
        """The device names the other side has described so far."""

class Remote(_Connected):
    """Base class of the remotes: the connection, its state and events, ``mainloop()``."""
    def fileno(self) -> int:
        """The descriptor for asyncio's ``add_reader`` or ``select``: readable when data
        arrives or timed work is due. Raises ValueError for a replay."""
    @property
    def device(self) -> str: ...
    @property
    def replay(self) -> Optional[Replay]: ...
    def on_peer_sender(self, f: Callable[[str], object]) -> int:
        """Calls ``f(name)`` with each device name the server describes, as it does."""
    def close(self) -> None:
        """Releases the remote now (its connection closes once no other remote uses it)."""

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
class Server(_Connected):
    """A server connection: UDP and TCP on one port, for any number of clients."""
    def __new__(cls, port: int = 3883, nic: Optional[str] = None) -> Server: ...
    @property
    def port(self) -> Optional[int]: ...
    @property
    def connected_peers(self) -> int: ...
    def on_peer_sender(self, f: Callable[[str], object]) -> int:
        """Calls ``f(name)`` with each sender name a client describes."""
    def close(self) -> None:
        """Releases the port and closes every device server made on this server, now."""

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

# ------------------------------------------------------ devices a client drives (both sides)

@final
class AnalogOutputRequest:
    """The output values after a client's request (``AnalogOutputServer.on_request``)."""
    @property
    def time(self) -> float: ...
    @property
    def channels(self) -> List[float]: ...

@final
class PoserRequest:
    """A pose a client asked for (``PoserServer.on_pose``, ``on_relative_pose``)."""
    @property
    def time(self) -> float: ...
    @property
    def pos(self) -> _Vec3: ...
    @property
    def quat(self) -> _Quat: ...

@final
class ForceReport:
    """A force the device reports (``ForceDeviceRemote.on_force``)."""
    @property
    def time(self) -> float: ...
    @property
    def force(self) -> _Vec3: ...

@final
class ScpReport:
    """A surface contact point (``ForceDeviceRemote.on_scp``)."""
    @property
    def time(self) -> float: ...
    @property
    def pos(self) -> _Vec3: ...
    @property
    def quat(self) -> _Quat: ...

@final
class ForceErrorReport:
    """An error the force device reports (``ForceDeviceRemote.on_error``)."""
    @property
    def time(self) -> float: ...
    @property
    def code(self) -> int: ...

@final
class ForceFieldRequest:
    """A force field a client sent (``ForceDeviceServer.on_force_field``)."""
    @property
    def time(self) -> float: ...
    @property
    def origin(self) -> _Vec3: ...
    @property
    def force(self) -> _Vec3: ...
    @property
    def jacobian(self) -> List[List[float]]: ...
    @property
    def radius(self) -> float: ...
    @property
    def stops(self) -> bool: ...

@final
class PlaneRequest:
    """A surface plane a client sent (``ForceDeviceServer.on_plane``)."""
    @property
    def time(self) -> float: ...
    @property
    def plane(self) -> _Quat: ...
    @property
    def kspring(self) -> float: ...
    @property
    def kdamp(self) -> float: ...
    @property
    def fdyn(self) -> float: ...
    @property
    def fstat(self) -> float: ...

@final
class CustomEffect:
    """A custom effect a client sent (``ForceDeviceServer.on_custom_effect``)."""
    @property
    def time(self) -> float: ...
    @property
    def effect_id(self) -> int: ...
    @property
    def params(self) -> List[float]: ...

@final
class AnalogOutputRemote(Remote):
    """Client of an analog output device: ``AnalogOutputRemote("Out0@host")``."""
    def __new__(cls, name: str) -> AnalogOutputRemote: ...
    def request_change_channel_value(self, channel: int, value: float) -> None: ...
    def request_change_channels(self, values: Sequence[float]) -> None: ...
    @property
    def num_channels(self) -> int: ...
    def on_num_channels(self, f: Callable[[int], object]) -> int: ...

@final
class PoserRemote(Remote):
    """Client of a poser: ``PoserRemote("Poser0@host")``."""
    def __new__(cls, name: str) -> PoserRemote: ...
    def request_pose(
        self, pos: Sequence[float], quat: Sequence[float] = ..., time: Optional[float] = None
    ) -> None: ...
    def request_pose_relative(
        self, dpos: Sequence[float], dquat: Sequence[float] = ..., time: Optional[float] = None
    ) -> None: ...
    def request_pose_velocity(
        self,
        vel: Sequence[float],
        quat: Sequence[float] = ...,
        dt: float = 1.0,
        time: Optional[float] = None,
    ) -> None: ...

@final
class ForceDeviceRemote(Remote):
    """Client of a force device: ``ForceDeviceRemote("Phantom0@host")``."""
    def __new__(cls, name: str) -> ForceDeviceRemote: ...
    def on_force(self, f: Callable[[ForceReport], object]) -> int: ...
    def on_scp(self, f: Callable[[ScpReport], object]) -> int: ...
    def on_error(self, f: Callable[[ForceErrorReport], object]) -> int: ...
    def send_force_field(
        self,
        origin: Sequence[float],
        force: Sequence[float],
        jacobian: Sequence[Sequence[float]],
        radius: float,
    ) -> None: ...
    def stop_force_field(self) -> None: ...
    def start_surface(
        self,
        plane: Sequence[float],
        kspring: float = 0.0,
        kdamp: float = 0.0,
        fdyn: float = 0.0,
        fstat: float = 0.0,
        plane_index: int = 0,
        recovery_cycles: int = 0,
    ) -> None: ...
    def send_custom_effect(self, effect_id: int, params: Sequence[float]) -> None: ...
    def stop_effect(self) -> None: ...

@final
class AnalogOutputServer:
    """Analog outputs on a Server: ``AnalogOutputServer(server, "Out0", channels=1)``; 1 to
    128 channels. Clients' requests set its values."""
    def __new__(cls, server: Server, name: str, channels: int = 1) -> AnalogOutputServer: ...
    def on_request(self, f: Callable[[AnalogOutputRequest], object]) -> int: ...
    def remove_callback(self, id: int) -> bool: ...
    def values(self) -> List[float]: ...
    def report_num_channels(self) -> None: ...
    def close(self) -> None: ...

@final
class PoserServer:
    """A poser on a Server: ``PoserServer(server, "Poser0")``."""
    def __new__(cls, server: Server, name: str) -> PoserServer: ...
    def on_pose(self, f: Callable[[PoserRequest], object]) -> int: ...
    def on_relative_pose(self, f: Callable[[PoserRequest], object]) -> int: ...
    def remove_callback(self, id: int) -> bool: ...
    def pose(self) -> PoserRequest: ...
    def close(self) -> None: ...

@final
class ForceDeviceServer:
    """A force device on a Server: ``ForceDeviceServer(server, "Phantom0")``."""
    def __new__(cls, server: Server, name: str) -> ForceDeviceServer: ...
    def report_force(self, force: Sequence[float], time: Optional[float] = None) -> None: ...
    def report_scp(
        self, pos: Sequence[float], quat: Sequence[float] = ..., time: Optional[float] = None
    ) -> None: ...
    def send_error(self, code: int) -> None: ...
    def on_force_field(self, f: Callable[[ForceFieldRequest], object]) -> int: ...
    def on_plane(self, f: Callable[[PlaneRequest], object]) -> int: ...
    def on_custom_effect(self, f: Callable[[CustomEffect], object]) -> int: ...
    def on_request(self, f: Callable[[str, float], object]) -> int: ...
    def remove_callback(self, id: int) -> bool: ...
    def close(self) -> None: ...
# ----------------------------------------------------------------------------- imager

_ValueTypeName = Literal["u8", "u16", "u12in16", "f32"]

@final
class ImagerRegion:
    """One region of one channel (copied out of the message)."""
    @property
    def channel(self) -> int: ...
    @property
    def columns(self) -> Tuple[int, int]:
        """(first, last) column, inclusive."""
    @property
    def rows(self) -> Tuple[int, int]: ...
    @property
    def depths(self) -> Tuple[int, int]: ...
    @property
    def value_type(self) -> _ValueTypeName: ...
    @property
    def data(self) -> bytes:
        """The pixels, little-endian, columns fastest, then rows, then depths."""
    def values(self) -> List[float]:
        """The pixels as numbers (ints, or floats for "f32")."""
    def __len__(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def sender_time(self) -> float: ...
    @property
    def arrival(self) -> float: ...

@final
class ImagerChannel:
    """One channel of an imager's description."""
    @property
    def name(self) -> str: ...
    @property
    def units(self) -> str: ...
    @property
    def min_val(self) -> float: ...
    @property
    def max_val(self) -> float: ...
    @property
    def scale(self) -> float:
        """Physical value = raw × scale + offset."""
    @property
    def offset(self) -> float: ...

@final
class ImagerDescription:
    """An imager's size and channel count."""
    @property
    def cols(self) -> int: ...
    @property
    def rows(self) -> int: ...
    @property
    def depth(self) -> int: ...
    @property
    def channels(self) -> int: ...
    @property
    def time(self) -> float: ...

@final
class ImagerFrame:
    """A begin-frame or end-frame."""
    @property
    def columns(self) -> Tuple[int, int]: ...
    @property
    def rows(self) -> Tuple[int, int]: ...
    @property
    def depths(self) -> Tuple[int, int]: ...
    @property
    def seq(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def arrival(self) -> float: ...

@final
class ImagerDiscarded:
    """A discarded-frames notice."""
    @property
    def count(self) -> int:
        """Frames dropped (0: some, count unknown)."""
    @property
    def time(self) -> float: ...

@final
class ImagerServer:
    """An imager on a Server: ``ImagerServer(server, "Cam0", cols, rows, depth=1)``."""
    def __new__(cls, server: Server, name: str, cols: int, rows: int, depth: int = 1) -> ImagerServer: ...
    def add_channel(
        self,
        name: str,
        units: str = "",
        min_val: float = 0.0,
        max_val: float = 255.0,
        scale: float = 1.0,
        offset: float = 0.0,
    ) -> int: ...
    def send_begin_frame(
        self,
        c_min: int,
        c_max: int,
        r_min: int,
        r_max: int,
        d_min: int = 0,
        d_max: int = 0,
        time: Optional[float] = None,
    ) -> bool: ...
    def send_end_frame(
        self,
        c_min: int,
        c_max: int,
        r_min: int,
        r_max: int,
        d_min: int = 0,
        d_max: int = 0,
        time: Optional[float] = None,
    ) -> bool: ...
    def send_region(
        self,
        channel: int,
        c_min: int,
        c_max: int,
        r_min: int,
        r_max: int,
        data: bytes,
        value_type: Literal["u8", "u16", "f32"] = "u8",
        d_min: int = 0,
        d_max: int = 0,
        time: Optional[float] = None,
    ) -> bool:
        """``data``: the region's pixels packed, columns fastest, little-endian."""
    @property
    def frames_to_send(self) -> int: ...
    def close(self) -> None: ...

@final
class ImagerRemote(Remote):
    """Client of an imager: ``ImagerRemote("TestImage@host")``."""
    def __new__(cls, name: str) -> ImagerRemote: ...
    def on_region(self, f: Callable[[ImagerRegion], object]) -> int: ...
    def on_description(self, f: Callable[[ImagerDescription], object]) -> int: ...
    def on_begin_frame(self, f: Callable[[ImagerFrame], object]) -> int: ...
    def on_end_frame(self, f: Callable[[ImagerFrame], object]) -> int: ...
    def on_discarded_frames(self, f: Callable[[ImagerDiscarded], object]) -> int: ...
    def throttle_sender(self, frames: int) -> None:
        """At most ``frames`` more frames; negative lifts the limit."""
    @property
    def description(self) -> Optional[ImagerDescription]: ...
    def channel(self, i: int) -> Optional[ImagerChannel]: ...
    def channel_index(self, name: str) -> Optional[int]: ...
    def take_end_frame(self) -> Optional[ImagerFrame]:
        """The newest end-frame if it arrived since the last call, else None."""
    @property
    def regions_received(self) -> int: ...
    @property
    def frames_discarded(self) -> int: ...

# ----------------------------------------------------------------------------- mutex

_MutexStateName = Literal["available", "requesting", "ours", "held_remotely"]

class _Mutex(_Polled):
    """A mutex participant: a client of a server's mutex or a peer (stub only)."""
    def request(self) -> None:
        """Asks for the lock (denied at once when it is not available)."""
    def release(self) -> None: ...
    @property
    def state(self) -> _MutexStateName: ...
    @property
    def is_available(self) -> bool: ...
    @property
    def is_held_locally(self) -> bool: ...
    @property
    def is_held_remotely(self) -> bool: ...
    def on_granted(self, f: Callable[[], object]) -> int: ...
    def on_denied(self, f: Callable[[], object]) -> int: ...
    def on_taken(self, f: Callable[[], object]) -> int: ...
    def on_released(self, f: Callable[[], object]) -> int: ...

@final
class MutexRemote(_Mutex):
    """A client of a server's mutex: ``MutexRemote("lock@host")``."""
    def __new__(cls, name: str) -> MutexRemote: ...
    @property
    def index(self) -> Optional[int]: ...
    def set_request_timeout(self, timeout: Optional[float]) -> None:
        """After ``timeout`` s without an answer a request counts as denied."""

@final
class PeerMutex(_Mutex):
    """A peer of a serverless mutex: ``PeerMutex("lock", port=0, nic=None)``."""
    def __new__(cls, name: str, port: int = 0, nic: Optional[str] = None) -> PeerMutex: ...
    def add_peer(self, station: str) -> None:
        """Adds the peer serving at "host:port"."""
    @property
    def port(self) -> int: ...
    @property
    def num_peers(self) -> int: ...
    @property
    def peers_connected(self) -> bool: ...

@final
class MutexServer:
    """A mutex served on a Server: ``MutexServer(server, "lock")``."""
    def __new__(cls, server: Server, name: str) -> MutexServer: ...
    @property
    def is_held(self) -> bool: ...
    @property
    def holder(self) -> Optional[int]: ...
    def close(self) -> None: ...

# ----------------------------------------------------------------------------- shared objects

_PolicyName = Literal["accept", "deny_remote", "deny_local"]

@final
class SharedChange:
    """A change of a shared value."""
    @property
    def value(self) -> object: ...
    @property
    def when(self) -> float: ...
    @property
    def is_local(self) -> bool: ...

class _Shared(_Polled, Generic[_T]):
    """A shared value of type ``_T`` (stub only: SharedInt32, SharedFloat64, SharedString)."""
    @property
    def value(self) -> _T: ...
    @property
    def last_update(self) -> float: ...
    def set(self, value: _T, when: Optional[float] = None) -> None: ...
    @property
    def is_serializer(self) -> bool: ...
    def become_serializer(self) -> None: ...
    def set_policy(self, name: _PolicyName) -> None: ...
    def set_policy_callback(self, f: Callable[[_T, float], object]) -> int: ...
    def on_change(self, f: Callable[[SharedChange], object]) -> int: ...
    def on_deferred_update(self, f: Callable[[], object]) -> int: ...

@final
class SharedInt32(_Shared[int]):
    """A shared int32: ``SharedInt32("name@host", value)`` on a client,
    ``SharedInt32.server(server, "name", value)`` on a server."""
    def __new__(
        cls, name: str, value: int = 0, serialized: bool = False,
        ignore_old: bool = False, ignore_idempotent: bool = False,
    ) -> SharedInt32: ...
    @staticmethod
    def server(
        server: Server, name: str, value: int = 0, serialized: bool = False,
        ignore_old: bool = False, ignore_idempotent: bool = False,
    ) -> SharedInt32: ...

@final
class SharedFloat64(_Shared[float]):
    """A shared float64 (see SharedInt32)."""
    def __new__(
        cls, name: str, value: float = 0.0, serialized: bool = False,
        ignore_old: bool = False, ignore_idempotent: bool = False,
    ) -> SharedFloat64: ...
    @staticmethod
    def server(
        server: Server, name: str, value: float = 0.0, serialized: bool = False,
        ignore_old: bool = False, ignore_idempotent: bool = False,
    ) -> SharedFloat64: ...

@final
class SharedString(_Shared[str]):
    """A shared string (see SharedInt32)."""
    def __new__(
        cls, name: str, value: str = "", serialized: bool = False,
        ignore_old: bool = False, ignore_idempotent: bool = False,
    ) -> SharedString: ...
    @staticmethod
    def server(
        server: Server, name: str, value: str = "", serialized: bool = False,
        ignore_old: bool = False, ignore_idempotent: bool = False,
    ) -> SharedString: ...
