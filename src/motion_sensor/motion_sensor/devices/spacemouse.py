"""3Dconnexion SpaceMouse over HID (hidapi): report decoding, rate-to-pose integration and a
reconnecting reader, and SpaceMouseDevice, the SpaceMouse as a HandDevice (no rospy here;
nodes/spacemouse_driver runs it through motion_sensor.devices.device_node).

A SpaceMouse is a rate device: the cap's deflection says how fast to move, not where the
hand is. The rest of the stack expects hand poses (hand.msg), so RateIntegrator turns the
deflections into the pose of a virtual hand that moves at the commanded speeds, inside a
bounded box. The teleop mapping is relative (it takes the pose at engage as reference), so
the virtual hand's absolute place does not matter.

HID reports (3Dconnexion's multi-axis controller protocol): report 1 carries translation
x, y, z as little-endian int16 (newer receivers send rotation in the same report, 13 bytes
in all), report 2 rotation rx, ry, rz, report 3 the button bitmap; other reports (LEDs,
battery) are ignored. HID axes: x right, y toward the user, z down; they are turned into
REP 103 axes of the device frame (x away from the user, y left, z up).
"""

import importlib
import struct
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import Backoff, HandDevice, reconnect_loop
from motion_sensor.errors import DeviceUnavailable, EndOfStream, MotionSensorError
from motion_sensor.hand_sample import HandSample

# (vendor id, product id) -> model, as listed by the spacenavd project; any other device is
# given with vendor_id/product_id.
KNOWN_DEVICES = {
    (0x046D, 0xC626): "SpaceNavigator",
    (0x046D, 0xC627): "SpaceExplorer",
    (0x046D, 0xC628): "SpaceNavigator for Notebooks",
    (0x046D, 0xC629): "SpacePilot Pro",
    (0x046D, 0xC62B): "SpaceMouse Pro",
    (0x046D, 0xC62E): "SpaceMouse Wireless (cable)",
    (0x046D, 0xC62F): "SpaceMouse Wireless (receiver)",
    (0x046D, 0xC631): "SpaceMouse Pro Wireless (cable)",
    (0x046D, 0xC632): "SpaceMouse Pro Wireless (receiver)",
    (0x256F, 0xC62E): "SpaceMouse Wireless (cable)",
    (0x256F, 0xC62F): "SpaceMouse Wireless (receiver)",
    (0x256F, 0xC631): "SpaceMouse Pro Wireless (cable)",
    (0x256F, 0xC632): "SpaceMouse Pro Wireless (receiver)",
    (0x256F, 0xC633): "SpaceMouse Enterprise",
    (0x256F, 0xC635): "SpaceMouse Compact",
    (0x256F, 0xC652): "3Dconnexion Universal Receiver",
}

# HID (x right, y toward the user, z down) -> REP 103 (x away from the user, y left, z up).
# A proper rotation (det +1), so it maps angular rates the same way as translations.
HID_TO_REP103 = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])

TRANSLATION_REPORT, ROTATION_REPORT, BUTTON_REPORT = 1, 2, 3
HID_BACKENDS = {"hidraw": "hidraw", "libusb": "hid"}  # backend -> hidapi's Python module


@dataclass
class SpaceMouseState:
    """The latest deflections (raw HID counts, HID axes) and buttons (bit i = button i)."""

    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    buttons: int = 0

    def button(self, index: int) -> bool:
        """Whether button ``index`` (0 = the left one) is held."""
        return bool(self.buttons >> index & 1)


class SpaceMouseDecoder:
    """Decodes HID input reports into a SpaceMouseState.

    ``feed`` returns True when the report changed the state, False for a report of another
    kind (LEDs, battery); a malformed report raises MotionSensorError and leaves the state
    as it was.
    """

    def __init__(self):
        self.state = SpaceMouseState()

    def feed(self, report: Sequence[int]) -> bool:
        """Apply one report (report id first, as hidapi returns it)."""
        data = bytes(report)
        if not data:
            raise MotionSensorError("empty HID report")
        kind = data[0]
        if kind == TRANSLATION_REPORT:
            if len(data) not in (7, 13):
                raise MotionSensorError(f"translation report of {len(data)} bytes; expected 7 or 13")
            values = struct.unpack("<3h", data[1:7])
            self.state.translation = np.array(values, dtype=float)
            if len(data) == 13:  # receivers send rotation in the same report
                self.state.rotation = np.array(struct.unpack("<3h", data[7:13]), dtype=float)
            return True
        if kind == ROTATION_REPORT:
            if len(data) != 7:
                raise MotionSensorError(f"rotation report of {len(data)} bytes; expected 7")
            self.state.rotation = np.array(struct.unpack("<3h", data[1:7]), dtype=float)
            return True
        if kind == BUTTON_REPORT:
            if len(data) < 2:
                raise MotionSensorError("button report without a bitmap")
            self.state.buttons = int.from_bytes(data[1:], "little")
            return True
        return False


#: How deflections become motion: the one declaration of these parameters, shared by the
#: SpaceMouse node's schema and ``RateConfig``.
RATE_PARAMS = ParamSchema(
    [
        Param("full_scale_counts", 350.0, unit="counts", low=0, low_open=True, doc="HID counts at the cap's end stop"),
        Param("deadzone", 0.08, unit="fraction of full scale", low=0, high=0.99, doc="ignored around the centre"),
        Param("response_exponent", 2.0, low=0, low_open=True, high=5, doc="1 linear; 2 finer control near centre"),
        Param("max_speed_mps", 0.15, unit="m/s", low=0, low_open=True, high=2, doc="speed at full deflection"),
        Param(
            "max_angular_speed_rps",
            0.8,
            unit="rad/s",
            low=0,
            low_open=True,
            high=10,
            doc="turn rate at full deflection",
        ),
        Param("workspace_half_size_m", 0.3, unit="m", low=0, low_open=True, high=5, doc="box around the start"),
        Param("start_position_m", [0.0, 0.0, 0.2], unit="m", length=3, doc="virtual hand start"),
        Param("max_step_s", 0.05, unit="s", low=0, low_open=True, high=1, doc="longest integrated gap"),
        Param(
            "hold_timeout_s",
            0.25,
            unit="s",
            low=0,
            low_open=True,
            high=5,
            doc="a deflection not repeated this long counts as released",
        ),
        Param(
            "axis_signs",
            [1, 1, 1, 1, 1, 1],
            length=6,
            item_kind=int,
            low=-1,
            high=1,
            doc="x y z rx ry rz in REP 103: 1 or -1",
        ),
    ]
)


@dataclass
class RateConfig:
    """How deflections become motion; defaults, units and ranges are ``RATE_PARAMS``."""

    full_scale_counts: float = RATE_PARAMS.field("full_scale_counts")
    deadzone: float = RATE_PARAMS.field("deadzone")
    response_exponent: float = RATE_PARAMS.field("response_exponent")
    max_speed_mps: float = RATE_PARAMS.field("max_speed_mps")
    max_angular_speed_rps: float = RATE_PARAMS.field("max_angular_speed_rps")
    workspace_half_size_m: float = RATE_PARAMS.field("workspace_half_size_m")
    start_position_m: tuple = RATE_PARAMS.field("start_position_m")
    max_step_s: float = RATE_PARAMS.field("max_step_s")
    hold_timeout_s: float = RATE_PARAMS.field("hold_timeout_s")
    axis_signs: tuple = RATE_PARAMS.field("axis_signs")

    def __post_init__(self):
        self.validate()

    def validate(self) -> "RateConfig":
        """Raise MotionSensorError naming the first bad value (the declared ranges; and
        each axis sign is 1 or -1, which a range cannot say)."""
        try:
            RATE_PARAMS.check_fields(self, "spacemouse")
        except ParameterError as exc:
            raise MotionSensorError(str(exc)) from None
        if any(sign not in (1, -1) for sign in self.axis_signs):
            raise MotionSensorError(f"spacemouse axis_signs must be six values of 1 or -1, got {self.axis_signs!r}")
        return self


class RateIntegrator:
    """Integrates SpaceMouse deflections into the pose of a virtual hand.

    ``update(now, state, report_age)`` advances the pose by the rates held since the last
    call. The rates are zero when the deflection is inside the dead zone, or when the
    device has not re-reported it for ``hold_timeout_s`` (a SpaceMouse repeats a held
    deflection; silence means it was unplugged or the radio dropped, and a stuck rate
    would drive the hand away).
    """

    def __init__(self, config: RateConfig = None):
        self.config = (config or RateConfig()).validate()
        self._signs = np.array(self.config.axis_signs, dtype=float)
        self.reset()

    def reset(self) -> None:
        """Back to the start pose, at rest."""
        self._start = np.array(self.config.start_position_m, dtype=float)
        self.position = self._start.copy()
        self.rotation = Rotation.identity()
        self._last = None
        self.velocity = np.zeros(3)
        self.angular_velocity = np.zeros(3)

    def _shape(self, counts: np.ndarray) -> np.ndarray:
        """Deflection counts -> rate fraction in [-1, 1], dead zone and response curve applied."""
        c = self.config
        fraction = np.clip(counts / c.full_scale_counts, -1.0, 1.0)
        live = np.maximum(np.abs(fraction) - c.deadzone, 0.0) / (1.0 - c.deadzone)
        return np.sign(fraction) * live**c.response_exponent

    def rates(self, state: SpaceMouseState, report_age: float):
        """(linear m/s, angular rad/s) in REP 103 axes for a state reported ``report_age`` s ago."""
        if not report_age <= self.config.hold_timeout_s:  # also catches NaN
            return np.zeros(3), np.zeros(3)
        linear = HID_TO_REP103 @ self._shape(np.asarray(state.translation, float)) * self.config.max_speed_mps
        angular = HID_TO_REP103 @ self._shape(np.asarray(state.rotation, float)) * self.config.max_angular_speed_rps
        return linear * self._signs[:3], angular * self._signs[3:]

    def update(self, now: float, state: SpaceMouseState, report_age: float):
        """Advance to ``now`` (s) with the rates of ``state``; return (position, quaternion xyzw)."""
        if self._last is None:
            self._last = now
        if now <= self._last:
            return self.position.copy(), self.rotation.as_quat()
        dt = min(now - self._last, self.config.max_step_s)
        self._last = now
        self.velocity, self.angular_velocity = self.rates(state, report_age)
        half = self.config.workspace_half_size_m
        self.position = np.clip(self.position + self.velocity * dt, self._start - half, self._start + half)
        # Angular rates are about the device's fixed axes, so the increment multiplies on the left.
        self.rotation = Rotation.from_rotvec(self.angular_velocity * dt) * self.rotation
        return self.position.copy(), self.rotation.as_quat()


def find_device(hid_module, vendor_id: int | None = None, product_id: int | None = None):
    """(vendor id, product id, name) of the first SpaceMouse hidapi lists, or None.

    With ``vendor_id`` and ``product_id`` that device is looked for; otherwise any of
    KNOWN_DEVICES.
    """
    for info in hid_module.enumerate():
        key = (info["vendor_id"], info["product_id"])
        if vendor_id is not None and product_id is not None:
            if key == (vendor_id, product_id):
                return key[0], key[1], info.get("product_string") or "SpaceMouse"
        elif key in KNOWN_DEVICES:
            return key[0], key[1], KNOWN_DEVICES[key]
    return None


class SpaceMouseReader:
    """Reads HID reports from a SpaceMouse through hidapi, reconnecting with backoff.

    ``on_report(report, received_time)`` gets every input report, ``on_connect(name)`` each
    opened device, ``on_problem(text)`` every connection problem. ``hid_module`` is hidapi's
    ``hid`` module (a stand-in in tests). ``run`` blocks until ``stop``.
    """

    def __init__(
        self,
        on_report: Callable,
        on_problem: Callable = None,
        vendor_id: int | None = None,
        product_id: int | None = None,
        hid_module=None,
        backoff: Backoff = None,
        clock: Callable[[], float] = time.time,
        read_timeout_ms: int = 50,
        on_connect: Callable = None,
        backend: str = "hidraw",
    ):
        if hid_module is None:
            if backend not in HID_BACKENDS:
                raise MotionSensorError(f"unknown HID backend {backend!r}; choose one of {sorted(HID_BACKENDS)}")
            # Imported here so that decoding and the tests need no HID library.
            hid_module = importlib.import_module(HID_BACKENDS[backend])
        self.hid = hid_module
        self.on_report = on_report
        self.on_problem = on_problem or (lambda text: None)
        self.on_connect = on_connect or (lambda name: None)
        self.vendor_id, self.product_id = vendor_id, product_id
        self.backoff = backoff or Backoff()
        self.clock = clock
        self.read_timeout_ms = int(read_timeout_ms)
        self.counters = Counter()
        self.device_name = ""
        self._device = None
        self._stop = threading.Event()

    def stop(self) -> None:
        """Make ``run`` return."""
        self._stop.set()

    def _find(self):
        found = find_device(self.hid, self.vendor_id, self.product_id)
        if found is None:
            wanted = (
                f"{self.vendor_id:04x}:{self.product_id:04x}" if self.vendor_id is not None else "any known SpaceMouse"
            )
            raise OSError(f"no HID device {wanted}: is it plugged in, and readable? {UDEV_HINT}")
        return found

    def open(self) -> None:
        """Open the first matching device (OSError when there is none or it cannot be opened)."""
        vendor, product, name = self._find()
        device = self.hid.device()
        device.open(vendor, product)
        self._device = device
        self.device_name = name
        self.on_connect(self.device_name)

    def read_report(self, timeout_ms: int = None):
        """The next input report (a list of ints), or None after ``timeout_ms`` without one;
        OSError/ValueError when the device is gone."""
        if self._device is None:
            raise OSError("SpaceMouse not open")
        report = self._device.read(64, self.read_timeout_ms if timeout_ms is None else timeout_ms)
        if not report:
            return None
        self.counters["hid_reports"] += 1
        return report

    def close(self) -> None:
        """Close the device (if open)."""
        device, self._device = self._device, None
        if device is not None:
            device.close()

    def run(self) -> None:
        """Read until stopped; reconnect with backoff after any HID error."""
        reconnect_loop(
            self._session, self._stop.is_set, self.backoff, self._stop.wait, self._on_error, retry=(OSError, ValueError)
        )

    def _on_error(self, exc, delay) -> None:
        self.counters["connection_errors"] += 1
        self.on_problem(f"SpaceMouse: {exc}; retrying")

    def _session(self) -> None:
        try:
            self.open()
            self.counters["connections"] += 1
            self.backoff.reset()
            while not self._stop.is_set():
                report = self.read_report()
                if report:
                    self.on_report(report, self.clock())
        finally:
            self.close()


def read_report_log(path: str):
    """[(seconds, report bytes)] from a report log: lines "SECONDS HEX", '#' comments.

    Report logs replay a SpaceMouse without the device (spacemouse_driver ~report_log), and
    ``~record_reports`` writes them from a real one.
    """
    rows = []
    with open(path, encoding="utf-8") as fh:
        for number, line in enumerate(fh, 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            try:
                stamp, text = line.split()
                rows.append((float(stamp), bytes.fromhex(text)))
            except ValueError:
                raise MotionSensorError(f"{path}:{number}: expected 'SECONDS HEXBYTES', got {line!r}") from None
    if any(b[0] < a[0] for a, b in zip(rows, rows[1:])):
        raise MotionSensorError(f"{path}: times must not go backwards")
    return rows


def format_report_line(seconds: float, report: Sequence[int]) -> str:
    """One report-log line (see read_report_log)."""
    return f"{seconds:.4f} {bytes(report).hex()}\n"


def rate_config(config: dict) -> RateConfig:
    """The RateConfig of a validated SpaceMouseDevice config."""
    return RateConfig(
        **{
            name: tuple(config[name]) if isinstance(config[name], list) else config[name]
            for name in RateConfig.__dataclass_fields__
        }
    )


#: What a user without read access to the device needs (the first vendor id is 3Dconnexion's,
#: the second Logitech's, for older models).
UDEV_HINT = (
    'Non-root access needs a udev rule: put KERNEL=="hidraw*", ATTRS{idVendor}=="256f", MODE="0666" '
    "(and the same line with 046d) in /etc/udev/rules.d/99-spacemouse.rules, then replug the device"
)

#: After a report log's last report, the virtual hand is published this long (its
#: deflection then counts as released, so it comes to rest) before the stream ends.
LOG_TAIL_S = 0.5


class SpaceMouseDevice(HandDevice):
    """A SpaceMouse as a HandDevice: polled at ``rate_hz``, each poll drains the HID reports
    (or, with ``report_log``, the log's reports due by now, at their recorded timing from
    the moment the stream starts), integrates the deflections into the virtual hand and
    returns its pose stamped now. The ``engage_button``'s state goes to
    /motion_commander/engage at the first report and at every change. Malformed reports are
    dropped and counted (``rejected``), reports of other kinds counted as ``ignored``.
    Nothing is published while no device is open (nor before a log's first report).

    A report log ends the stream (``EndOfStream``, so the session ends as with any
    recording) ``hold_timeout_s`` + LOG_TAIL_S after its last report, with the clutch
    released. With no device found for ``device_wait_s`` from the start, the node stops
    with the udev hint rather than retrying forever (0: wait for ever)."""

    name = "spacemouse"
    default_frame_id = "spacemouse"
    bool_outputs = {"engage": "motion_commander/engage"}
    finite = True  # a report log ends (EndOfStream); a device never does
    params = RATE_PARAMS.merged(
        ParamSchema(
            [
                Param(
                    "rate_hz", 100.0, unit="Hz", low=0, low_open=True, high=1000, doc="virtual hand poses per second"
                ),
                Param("engage_button", 0, low=-1, high=31, doc="button held = engage; -1 none"),
                Param("hand_type", "right", choices=("right", "left"), doc="hand.msg hand_type it stands in for"),
                Param("vendor_id", -1, low=-1, high=0xFFFF, doc="USB vendor id; -1 the first known SpaceMouse"),
                Param("product_id", -1, low=-1, high=0xFFFF, doc="USB product id; -1 the first known SpaceMouse"),
                Param("hid_backend", "hidraw", choices=tuple(sorted(HID_BACKENDS)), doc="hidapi backend"),
                Param("report_log", "", doc="replay this report log (lines 'SECONDS HEX') instead of a device"),
                Param("record_reports", "", doc="write every report to this log"),
                Param(
                    "device_wait_s",
                    10.0,
                    "s",
                    "give up (and stop the node) when no device appears for this long from the start; 0: wait for ever",
                    low=0.0,
                    high=86400.0,
                ),
            ]
        )
    )

    def __init__(self, config, hid_module=None, **kw):
        super().__init__(config, **kw)
        self.rate_hz = self.config["rate_hz"]
        self.integrator = RateIntegrator(rate_config(self.config))
        self.hand_type = self.config["hand_type"]
        self.engage_button = self.config["engage_button"]
        self.report_log = self.config["report_log"]
        self.decoder = SpaceMouseDecoder()
        self.engaged = None
        self.last_report = None
        self._record = None
        self._rows, self._next_row, self._log_start = None, 0, None
        self._log_done_at = None
        self._first_open_try = None
        self._ever_opened = False
        self.reader = None
        if not self.report_log:
            vendor, product = self.config["vendor_id"], self.config["product_id"]
            self.reader = SpaceMouseReader(
                None,
                clock=self.clock,
                hid_module=hid_module,
                vendor_id=None if vendor < 0 else vendor,
                product_id=None if product < 0 else product,
                backend=self.config["hid_backend"],
            )
            self.counters = self.reader.counters

    def describe(self) -> str:
        if self.reader is None:
            return f"replay of {self.report_log}"
        return self.reader.device_name or "SpaceMouse"

    def open(self) -> None:
        self.decoder = SpaceMouseDecoder()  # a re-plugged device starts at rest
        self.last_report = None
        if self.reader is not None:
            now = self.clock()
            if self._first_open_try is None:
                self._first_open_try = now
            try:
                self.reader.open()
            except OSError as exc:
                waited = now - self._first_open_try
                wait = self.config["device_wait_s"]
                if not self._ever_opened and wait > 0 and waited >= wait:
                    raise MotionSensorError(
                        f"no SpaceMouse found in {waited:.0f} s ({exc}). device_wait_s:=0 waits for ever; "
                        "spacemouse_log:=FILE replays a report log instead"
                    ) from None
                raise
            self._ever_opened = True
            self.info(f"{self.reader.device_name} open")
            return
        if self._rows is None:
            try:
                self._rows = read_report_log(self.report_log)
            except OSError as exc:
                raise MotionSensorError(f"cannot replay report_log {self.report_log}: {exc}") from None
            self.info(f"replaying {len(self._rows)} reports from {self.report_log}")
        self._log_start = self.clock() - (self._rows[0][0] if self._rows else 0.0)

    def _due_reports(self, now):
        """(report, received) pairs available now."""
        if self.reader is None:
            while self._next_row < len(self._rows) and self._log_start + self._rows[self._next_row][0] <= now:
                seconds, report = self._rows[self._next_row]
                self._next_row += 1
                if self._next_row == len(self._rows):
                    self.info("report log done")
                    self._log_done_at = self._log_start + seconds
                yield list(report), self._log_start + seconds
            return
        for _ in range(64):  # at most a poll's worth; the rest waits for the next poll
            try:
                report = self.reader.read_report(timeout_ms=1)
            except (OSError, ValueError) as exc:  # hidapi raises OSError/IOError on unplug
                raise DeviceUnavailable(f"SpaceMouse: {exc}") from None
            if not report:
                return
            yield report, now

    def on_report(self, report, received: float) -> None:
        """Apply one HID report (decode, count, record, engage button)."""
        try:
            changed = self.decoder.feed(report)
        except MotionSensorError as exc:
            self.counters["rejected"] += 1
            self.warn(f"report dropped: {exc}")
            return
        self.counters["reports" if changed else "ignored"] += 1
        if changed:
            self.last_report = received
        if self.config["record_reports"]:
            if self._record is None:
                self._record = open(self.config["record_reports"], "w", encoding="utf-8")
            self._record.write(format_report_line(received, report))
        if self.engage_button >= 0:
            pressed = self.decoder.state.button(self.engage_button)
            if pressed != self.engaged:
                self.engaged = pressed
                self.emit("engage", pressed)

    def read(self, now):
        for report, received in self._due_reports(now):
            self.on_report(report, received)
        if self._log_done_at is not None and now - self._log_done_at > self.config["hold_timeout_s"] + LOG_TAIL_S:
            if self.engaged:
                self.engaged = False
                self.emit("engage", False)
            raise EndOfStream("report log replayed")
        if self.reader is None and self.last_report is None:
            return None  # a log publishes from its first report on, as a device from its opening
        age = float("inf") if self.last_report is None else now - self.last_report
        position, orientation = self.integrator.update(now, self.decoder.state, age)
        self.counters["samples"] += 1
        return HandSample(
            stamp=now,
            position=position,
            orientation=orientation,
            hands_num=1,
            hand_types=(self.hand_type,),
            frame_id=self.frame_id,
            device="spacemouse",
        )

    def close(self) -> None:
        if self.reader is not None:
            self.reader.close()

    def shutdown(self) -> None:
        if self._record is not None:
            self._record.close()
            self._record = None
