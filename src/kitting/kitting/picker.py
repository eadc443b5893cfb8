"""The kitting cycle: take the next tracked part, intercept it on the moving belt, carry it
to its class's slot, come back. Plain Python: the robot is any controller with the
MotionControllerClient methods (move_l, move_j, set_gripper, get_pose), the parts come
from ``observe`` (vision results, fed into a BeltTracker), the clock is injected.

One pick (all heights are of the magnet face, ``cell.gripper.tcp_length`` below tool0):

1. plan: the earliest intercept (``plan_intercept``) of the part inside the pick window,
   given the time the arm needs to get above it plus the descent time;
2. hover: MoveL to ``hover_height`` above the point where the descent must start, which is
   upstream of the intercept by the belt travel during the descent; magnet on;
3. wait for the start time (re-planned from the newest track), then descend diagonally,
   with the belt, onto the part's top (MoveL) and lift straight up;
4. carry: one straight MoveL from the lift point to ``transit_height`` above the slot (the
   lift point is high enough above the belt and the tray for a straight path; the path is
   checked); meanwhile the camera checks the pick: a part still seen on the belt where the
   track predicts it, in the images taken after the lift, was missed. Above the slot the
   cycle waits until ``verify_time`` has passed since the lift (the check's images); a
   missed part is retried while it is reachable, otherwise logged with the reason;
5. lower into the slot, magnet off, lift back to transit height: the next pick's approach
   starts from there.

Each pick's phases are timed (``kitting.cycle_phases``) and sent with its final event.

Evidence, never a silent success:

- a part is never picked on a pose older than ``max_pose_age`` s (its newest sighting):
  such a track waits for fresh sightings, and a descent about to start on one is deferred;
- a pick the camera could not confirm (no image since the lift, also after a second
  ``verify_time`` above the slot) is checked again before the release: by the images that
  came in meanwhile (late ones count), else by the gripper's part sensor (``part_present``:
  True, False or None when it has no reading). With neither, or with evidence against,
  the part is reported ``failed``, not ``placed``;
- after the release, a part still on the magnet (part sensor) or seen on the belt after
  the lift is reported ``failed``.

Kits: one part per slot. A slot released into is full until ``tray_swapped`` (the tray of
the finished kit was taken away); parts whose slot is full are left on the belt. Of the
parts that may be picked, the one that leaves the pick window soonest and can still be
reached goes first (earliest deadline first); a part that can no longer be reached is
``skipped``.

Every path is checked before it is sent: no point of the tool's magnet may come closer
than ``clearance`` to the belt or the tray except the grasp and release points themselves
(``check_segment``). The descent duration is learned from the measured moves, and so is
the approach: the reach-time estimate (``move_overhead``, ``tool_speed``) is scaled by the
largest ratio of measured to estimated approach time of the last five picks (a slower
controller, a loaded machine).

STOP, the server's latched stop and refusals come back as exceptions with a result code:
the cycle ends with a ``failed`` event; a held part stays on the magnet; ``recover`` (after
the latch is released) carries it to its slot.
"""

import copy
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from motion_common.params import Param, ParamSchema

from .cell import Cell
from .intercept import plan_intercept
from .parts import PART_CLASSES
from .tracking import BeltTracker, Observation, Track

PICKER_SCHEMA = ParamSchema(
    [
        Param(
            "pick_window",
            [-0.45, -0.08],
            "m",
            "x range along the belt where parts are picked (inside the camera's view, so a missed pick is seen)",
            length=2,
            low=-5.0,
            high=5.0,
        ),
        Param("hover_height", 0.08, "m", "magnet face above a part's top before the descent", low=0.01, high=0.5),
        Param(
            "transit_height", 0.15, "m", "magnet face above the belt plane between belt and tray", low=0.02, high=1.0
        ),
        Param("place_height", 0.015, "m", "part bottom above the slot floor when released", low=0.0, high=0.2),
        Param("grasp_gap", 0.002, "m", "magnet face above the part's top at the grasp point", low=-0.005, high=0.02),
        Param("wait_position", [-0.20, 0.55, 0.35], "m", "where tool0 waits for parts", length=3, low=-3.0, high=3.0),
        Param(
            "descent_time",
            0.7,
            "s",
            "first estimate of the descent move's duration (then measured)",
            low=0.05,
            high=10.0,
        ),
        Param(
            "tool_speed",
            0.6,
            "m/s",
            "average tool speed of the reach-time estimate (before it is scaled by the measured approaches)",
            low=0.01,
            high=5.0,
        ),
        Param(
            "move_overhead",
            0.15,
            "s",
            "fixed time per move of the reach-time estimate (accelerations, calls)",
            low=0.0,
            high=10.0,
        ),
        Param("plan_margin", 0.4, "s", "slack added to every intercept", low=0.0, high=10.0),
        Param("min_confidence", 0.5, "", "detections below this confidence are never picked", low=0.0, high=1.0),
        Param("min_hits", 3, "", "observations before a track is picked", low=1, high=100),
        Param("max_attempts", 3, "", "picks tried per part while it is reachable", low=1, high=20),
        Param(
            "verify_time",
            0.6,
            "s",
            "time after the lift in which a fresh sighting means a missed pick (the carry goes on meanwhile; "
            "the release waits for it)",
            low=0.0,
            high=10.0,
        ),
        Param(
            "max_pose_age",
            3.0,
            "s",
            "oldest sighting of a part a descent may start on (older: wait for fresh sightings); "
            "the arm hovering over a part may hide it for a second or two, and a 1 % belt speed error "
            "moves the prediction 1.5 mm in 3 s at 0.05 m/s",
            low=0.05,
            high=30.0,
        ),
        Param(
            "clearance",
            0.004,
            "m",
            "smallest distance from the magnet to the belt or tray on any path",
            low=0.0,
            high=0.2,
        ),
        Param(
            "tool_orientation",
            [1.0, 0.0, 0.0, 0.0],
            "",
            "tool0 quaternion (x, y, z, w) for picking: z down",
            length=4,
            low=-1.0,
            high=1.0,
        ),
    ]
)


@dataclass
class KittingEvent:
    """What happened to a tracked part."""

    track_id: int
    class_name: str
    event: str  # tracked | planned | picked | missed | placed | skipped | failed
    reason: str = ""
    position: np.ndarray | None = None
    time: float = 0.0
    verified: bool = True  # picked: the camera confirmed the part left the belt
    phases: dict | None = None  # the pick's final event: phase -> s (kitting.cycle_phases)


@dataclass
class Box:
    """An axis-aligned obstacle (belt or tray), m."""

    name: str
    low: np.ndarray
    high: np.ndarray

    def distance(self, point) -> float:
        """Distance from ``point`` to the box (0 inside)."""
        outside = np.maximum(np.maximum(self.low - point, point - self.high), 0.0)
        return float(np.linalg.norm(outside))


def cell_obstacles(cell: Cell) -> list[Box]:
    """The belt body and the tray plate as boxes (the tray's yaw taken as its bounding box)."""
    belt = cell.belt
    boxes = [
        Box(
            "belt",
            np.array([belt.x_start, belt.y - belt.width / 2, belt.height - belt.thickness]),
            np.array([belt.x_end, belt.y + belt.width / 2, belt.height]),
        )
    ]
    tray = cell.tray
    corners = np.array([[sx * tray.size[0] / 2, sy * tray.size[1] / 2] for sx in (-1, 1) for sy in (-1, 1)])
    c, s = math.cos(tray.yaw), math.sin(tray.yaw)
    corners = corners @ np.array([[c, s], [-s, c]]) + tray.position[:2]
    boxes.append(
        Box("tray", np.r_[corners.min(axis=0), tray.position[2] - 0.01], np.r_[corners.max(axis=0), tray.position[2]])
    )
    return boxes


def check_segment(
    start, end, obstacles: list[Box], clearance: float, allowed_end: float = 0.0, step: float = 0.005
) -> str:
    """'' when the straight segment start->end of the magnet face keeps ``clearance`` from
    every obstacle; else what it hits. The last ``allowed_end`` metres may come closer
    (the descent onto a part lying on the belt)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(end - start))
    count = max(2, int(math.ceil(length / step)) + 1)
    for k in range(count):
        fraction = k / (count - 1)
        if length * (1 - fraction) < allowed_end:
            break
        point = start + (end - start) * fraction
        for box in obstacles:
            if box.distance(point) < clearance:
                return (
                    f"path passes {box.distance(point) * 1000:.1f} mm from the {box.name} "
                    f"at {np.round(point, 3).tolist()}"
                )
    return ""


class PickAborted(Exception):
    """A pick ended early; ``reason`` says why, ``result`` is the controller's code if any."""

    def __init__(self, reason: str, result: int = 0):
        super().__init__(reason)
        self.reason, self.result = reason, result


class PickDeferred(PickAborted):
    """The part's pose is too old to descend on: nothing was touched, the magnet goes off and
    the part is tried again once it is seen afresh (while it is reachable)."""


class PickMissed(PickAborted):
    """The grasp missed the part (the arm reached the hover point too late, or the part is
    still on the belt after the lift): the pick is retried while the part is reachable, and
    the magnet stays on meanwhile (the part may be held after all)."""


@dataclass
class _PartRecord:
    attempts: int = 0
    done: bool = False


class KittingPicker:
    """Tracks parts and runs kitting cycles with ``controller``."""

    def __init__(
        self,
        cell: Cell,
        controller,
        params: dict | None = None,
        tracker_params: dict | None = None,
        clock: Callable[[], float] = time.time,
        sleep: Callable[[float], None] = time.sleep,
        on_event: Callable[[KittingEvent], None] = lambda event: None,
        source: str = "kitting parameters",
        part_present: Callable[[], bool | None] = lambda: None,
        on_tray: Callable[[dict], None] = lambda tray: None,
    ):
        self.params = PICKER_SCHEMA.validate(params or {}, source)
        if self.params["pick_window"][1] <= self.params["pick_window"][0]:
            raise ValueError(f"{source}: pick_window must be [x_min, x_max] with x_min < x_max")
        self.cell, self.controller = cell, controller
        self.tracker = BeltTracker(dict(tracker_params or {}, initial_speed=cell.belt.speed))
        self.clock, self.sleep, self.on_event = clock, sleep, on_event
        self.on_tray = on_tray  # called with tray_state() whenever a slot fills or the tray is swapped
        self.part_present = part_present  # the gripper's part sensor: True, False, None (no reading)
        self.obstacles = cell_obstacles(cell)
        self.descent_time = self.params["descent_time"]
        self.records: dict[int, _PartRecord] = {}
        self.holding: Track | None = None
        self.magnet_on = False
        self.orientation = list(self.params["tool_orientation"])
        self.cycle_times: deque[float] = deque(maxlen=1000)
        # measured / estimated approach time of the last picks: the reach-time estimate's scale
        self.approach_ratios: deque[float] = deque(maxlen=5)
        # observe() runs on the image callback's thread, the cycle on its own: the lock
        # keeps a Kalman update from interleaving with a plan reading the same track.
        self.lock = threading.Lock()
        self.recent = deque()  # (stamp, Observation) of the last 3 s: the miss check
        self.filled: set[str] = set()  # slots released into since the last tray swap
        # Orders tray changes with their on_tray calls (the cycle thread fills, a callback
        # swaps): the last state reported is always the tray's.
        self.tray_lock = threading.Lock()
        self.last_image = -math.inf  # stamp of the newest processed image, parts or not

    # -- perception --------------------------------------------------------------------------
    def observe(self, stamp: float, parts):
        """Feed one image's parts (objects with class_name, x, y, confidence) taken at ``stamp``."""
        observations = [
            Observation(p.class_name, p.x, p.y, p.confidence)
            for p in parts
            if p.confidence >= self.params["min_confidence"] and p.class_name in PART_CLASSES
        ]
        with self.lock:
            self.last_image = max(self.last_image, stamp)
            self.recent.extend((stamp, o) for o in observations)
            while self.recent and self.recent[0][0] < stamp - 3.0:
                self.recent.popleft()
            before = set(self.tracker.tracks)
            self.tracker.update(stamp, observations)
            new = [self.tracker.tracks[k] for k in set(self.tracker.tracks) - before]
        for track in new:
            self._emit(track, "tracked", position=np.r_[track.position, self.cell.belt.height])

    # -- geometry ----------------------------------------------------------------------------
    def _tool0(self, face) -> list[float]:
        """tool0 position for a magnet face at ``face`` (the tool points down)."""
        return (np.asarray(face, float) + [0.0, 0.0, self.cell.gripper.tcp_length]).tolist()

    def _face_now(self) -> np.ndarray:
        position, _ = self.controller.get_pose()
        return np.asarray(position, float) - [0.0, 0.0, self.cell.gripper.tcp_length]

    def _top(self, class_name: str) -> float:
        return self.cell.belt.height + PART_CLASSES[class_name].height

    def _travel_estimate(self, start, hover) -> float:
        """The parameters' estimate (s) of the move from ``start`` to ``hover``: two moves'
        overhead and the travel at tool_speed."""
        P = self.params
        return 2 * P["move_overhead"] + float(np.linalg.norm(np.asarray(hover) - start)) / P["tool_speed"]

    @property
    def approach_scale(self) -> float:
        """Measured / estimated approach time: the largest of the last picks' (1 before any)."""
        return max(self.approach_ratios, default=1.0)

    def reach_time(self, start, point) -> float:
        """Estimated time (s) from the magnet at ``start`` to hovering above ``point`` and
        descending onto it: the travel estimate scaled by the measured approaches, the
        descent."""
        hover = np.array([point[0], point[1], self.cell.belt.height + self.params["hover_height"]])
        return self.approach_scale * self._travel_estimate(start, hover) + self.descent_time

    # -- the cycle ---------------------------------------------------------------------------
    def tray_swapped(self):
        """The finished kit's tray was taken away: every slot is free again."""
        with self.tray_lock:
            with self.lock:
                self.filled.clear()
            self.on_tray(self.tray_state())

    def tray_state(self) -> dict:
        """The tray as the operator needs it: its slots' classes in order, those filled since
        the last swap, and whether the kit is complete (every slot filled: swap the tray)."""
        slots = [slot.part_class for slot in self.cell.tray.slots]
        with self.lock:
            filled = [name for name in slots if name in self.filled]
        return {"slots": slots, "filled": filled, "complete": len(filled) == len(slots)}

    def _slot_free(self, class_name: str) -> bool:
        return self.cell.tray.slot_for(class_name).part_class not in self.filled

    def deadline(self, track: Track) -> float:
        """When the part leaves the pick window (s, clock time; inf if it never does)."""
        vx = track.velocity[0]
        if vx <= 1e-9:
            return math.inf
        return track.t + (self.params["pick_window"][1] - track.position[0]) / vx

    def candidates(self) -> list[Track]:
        """Confirmed, freshly seen tracks not done yet whose slot is free, earliest
        deadline (leaving the pick window) first."""
        oldest = self.clock() - self.params["max_pose_age"]
        with self.lock:
            out = [
                copy.deepcopy(t)
                for t in self.tracker.tracks.values()
                if t.hits >= self.params["min_hits"]
                and t.last_seen >= oldest
                and not self.records.get(t.track_id, _PartRecord()).done
                and self._slot_free(t.class_name)
            ]
        return sorted(out, key=self.deadline)

    def run_once(self) -> KittingEvent | None:
        """Pick and place the next part if there is one; the final event, or None. Parts
        that can no longer be reached are skipped on the way to the first that can."""
        x_min, x_max = self.params["pick_window"]
        for track in self.candidates():
            record = self.records.setdefault(track.track_id, _PartRecord())
            now = self.clock()
            start = self._face_now()
            plan = plan_intercept(
                track.position,
                track.velocity,
                track.t,
                now,
                lambda point, start=start: self.reach_time(start, point),
                x_min,
                x_max,
                margin=self.params["plan_margin"],
            )
            if plan.ok:
                return self._run_pick(track, record, plan)
            record.done = True
            self._emit(track, "skipped", plan.reason)
        return None

    def _run_pick(self, track: Track, record: _PartRecord, plan) -> KittingEvent:
        now = self.clock()
        record.attempts += 1
        started = now
        try:
            event = self._pick_and_place(track, plan.time)
        except PickAborted as exc:
            if self.holding is None and self.magnet_on and exc.result:
                # Stopped with the magnet on: the part may hang from it. It stays on,
                # and the part is carried to its slot once the stop is released.
                self.holding = track
                record.done = True
                return self._emit(
                    track,
                    "failed",
                    f"{exc.reason}; the magnet stays on: the part goes to its slot once the stop is released",
                )
            if self.holding is None and not isinstance(exc, PickMissed):
                # Nothing held; after a suspected miss the magnet stays on instead (if
                # the part is held after all, it is never dropped onto the belt).
                self._release_quietly()
            if self.holding is None and not exc.result:
                self._clear_the_view()
            retry = isinstance(exc, (PickMissed, PickDeferred))
            if exc.result or record.attempts >= self.params["max_attempts"] or not retry:
                record.done = exc.result == 0 or self.holding is not None
                return self._emit(track, "failed", exc.reason)
            return self._emit(track, "missed", exc.reason)
        record.done = True
        self.cycle_times.append(self.clock() - started)
        return event

    def _move_l(self, face, allowed_end: float = 0.0, check_from=None):
        """MoveL of the magnet face to ``face`` after checking the path against the cell."""
        start = self._face_now() if check_from is None else check_from
        problem = check_segment(start, face, self.obstacles, self.params["clearance"], allowed_end)
        if problem:
            raise PickAborted(f"path refused: {problem}")
        try:
            self.controller.move_l(self._tool0(face), self.orientation)
        except Exception as exc:
            if not hasattr(exc, "result"):
                raise
            raise PickAborted(f"move refused or interrupted: {exc}", int(exc.result)) from None

    def _gripper(self, on: bool):
        try:
            self.controller.set_gripper(on)
            self.magnet_on = on
        except Exception as exc:
            if not hasattr(exc, "result"):
                raise
            raise PickAborted(f"gripper command failed: {exc}", int(exc.result)) from None

    def _release_quietly(self):
        try:
            self.controller.set_gripper(False)
            self.magnet_on = False
        except Exception:  # the controller is gone or latched: nothing is held anyway
            pass

    def _pick_and_place(self, track: Track, t_grasp: float) -> KittingEvent:
        P = self.params
        phases, lap = self._phase_timer()
        top = self._top(track.class_name)
        point = track.predict_position(t_grasp)
        velocity = track.velocity
        hover = np.r_[point - velocity * self.descent_time, top + P["hover_height"]]
        self._emit(track, "planned", f"intercept in {t_grasp - self.clock():.2f} s", np.r_[point, top])
        estimate = self._travel_estimate(self._face_now(), hover)
        self._rise_then_move(hover)
        took = lap("approach")
        self.approach_ratios.append(min(max(took / max(estimate, 0.05), 0.2), 5.0))
        self._gripper(True)
        # Start the descent so that it ends when the part arrives (newest estimate).
        with self.lock:
            latest = self.tracker.tracks.get(track.track_id, track)
            point = latest.predict_position(t_grasp)
        grasp = np.r_[point, top + P["grasp_gap"]]
        wait = t_grasp - self.descent_time - self.clock()
        if wait < -0.5 * self.descent_time:
            raise PickMissed("missed: the arm reached the hover point too late for this intercept")
        if wait > 0:
            self.sleep(wait)
        with self.lock:
            latest = self.tracker.tracks.get(track.track_id, latest)
        age = self.clock() - latest.last_seen
        if age > P["max_pose_age"]:
            raise PickDeferred(
                f"deferred: the part was last seen {age:.2f} s ago (max_pose_age {P['max_pose_age']:g} s)"
            )
        lap("wait")
        self._move_l(grasp, allowed_end=P["hover_height"] + 0.01, check_from=hover)
        took = lap("descent")
        # Learn the descent time (the driver's timing, the machine's load): smoothed.
        self.descent_time = 0.7 * self.descent_time + 0.3 * min(max(took, 0.05), 5.0)
        lift = grasp + [0.0, 0.0, P["hover_height"]]
        self._move_l(lift, check_from=grasp)
        lap("lift")
        lifted_at = self.clock()
        # The part is taken as held from here (a stop during the carry keeps it on the
        # magnet); the camera's miss check runs while the arm carries it away.
        self.holding = track
        self._move_to(self._above_slot(track.class_name))
        lap("carry")
        unverified = self._miss_check(latest, track.class_name, lifted_at)
        lap("check")
        self._emit(track, "picked", unverified, grasp, verified=not unverified)
        return self.place_held(
            check=(latest, lifted_at) if unverified else None, seen=(latest, lifted_at), phases=phases
        )

    def _phase_timer(self):
        """(phases, lap): ``lap(name)`` stores the time since the previous lap (or since the
        timer started) as phase ``name`` and returns it."""
        phases = {}
        mark = [self.clock()]

        def lap(name: str) -> float:
            now = self.clock()
            phases[name] = now - mark[0]
            mark[0] = now
            return phases[name]

        return phases, lap

    def _miss_check(self, track: Track, class_name: str, lifted_at: float) -> str:
        """After the carry: '' when the images taken since the lift show the part gone from
        the belt; the reason the pick is unverified when no image came (the release then
        looks for other evidence). Waits until ``verify_time`` has passed since the lift
        (and once more without an image: the vision may lag behind). A part still on the
        belt raises PickMissed (the magnet stays on: it may hold the part after all)."""
        P = self.params
        if P["verify_time"] <= 0:
            return ""
        left = lifted_at + P["verify_time"] - self.clock()
        if left > 0:
            self.sleep(left)
        if not self._image_since(lifted_at):
            self.sleep(P["verify_time"])
        if not self._image_since(lifted_at):
            # Without an image the miss check cannot run: carry on (the part is most
            # likely on the magnet) but say so, so that a campaign counts it apart.
            return "unverified: no camera image since the lift (is the camera registered?)"
        if self._still_on_belt(track, class_name, lifted_at):
            self.holding = None
            raise PickMissed("missed: the part is still on the belt after the lift")
        return ""

    def _image_since(self, since: float) -> bool:
        """Has an image taken after ``since`` been processed (with or without parts)?"""
        with self.lock:
            return self.last_image > since

    def _still_on_belt(self, track: Track, class_name: str, since: float, radius: float = 0.006) -> bool:
        """Was the part seen after ``since`` where the belt would have carried it? A gripped
        part hangs still under the magnet, seen ~2-3 cm from there by parallax, so a
        sighting within ``radius`` of the belt prediction means the grasp missed."""
        with self.lock:
            recent = [(t, o) for t, o in self.recent if t > since and o.class_name == class_name]
        return any(math.hypot(o.x - p[0], o.y - p[1]) < radius for t, o in recent for p in [track.predict_position(t)])

    def _above_slot(self, class_name: str) -> np.ndarray:
        """The magnet face at transit height above the slot of ``class_name``."""
        slot = self.cell.tray.slot_for(class_name)
        return np.r_[slot.center[:2], self.cell.belt.height + self.params["transit_height"]]

    def place_held(self, check=None, seen=None, phases=None) -> KittingEvent:
        """Carry the held part to its class's slot and release it there. ``check`` (track,
        lift time) for a pick the camera could not confirm: the evidence is looked at again
        above the slot, before the release. ``seen`` (track, lift time): after the release,
        a sighting on the belt since the lift means the part never came. ``phases`` (the
        pick's timed phases so far) gets the release's and goes with the final event."""
        P = self.params
        track = self.holding
        slot = self.cell.tray.slot_for(track.class_name)
        part = PART_CLASSES[track.class_name]
        floor = self.cell.tray.position[2]
        above = self._above_slot(track.class_name)
        release = np.r_[slot.center[:2], floor + P["place_height"] + part.height]
        if float(np.linalg.norm(self._face_now() - above)) > 1e-3:  # not there after the carry
            self._rise_then_move(above)
        began = self.clock()
        held, evidence = self._pick_evidence(*check) if check is not None else (True, "")
        self._move_l(release)
        self._gripper(False)
        self.holding = None
        with self.tray_lock:
            with self.lock:
                self.filled.add(slot.part_class)  # whatever landed there, the slot is taken
            self.on_tray(self.tray_state())
        self._move_l(above)
        if phases is not None:
            phases["release"] = self.clock() - began
        problem = "" if held else evidence
        if not problem and self.part_present() is True:
            problem = "the part is still on the magnet after the release"
        if not problem and seen is not None and self._still_on_belt(seen[0], track.class_name, seen[1]):
            problem = "the part was seen on the belt after the lift: it never came to the slot"
        if problem:
            return self._emit(track, "failed", f"not placed: {problem}", release, verified=False, phases=phases)
        return self._emit(
            track,
            "placed",
            f"slot {slot.part_class}" + (f" ({evidence})" if evidence else ""),
            release,
            phases=phases,
        )

    def _pick_evidence(self, track: Track, lifted_at: float) -> tuple[bool, str]:
        """Above the slot: (is the unconfirmed part on the magnet, by what evidence / why not)."""
        if self._image_since(lifted_at):
            if self._still_on_belt(track, track.class_name, lifted_at):
                return False, "the part is still on the belt: the pick missed"
            return True, "confirmed by the camera before the release"
        present = self.part_present()
        if present is True:
            return True, "confirmed by the gripper's part sensor"
        if present is False:
            return False, "the gripper's part sensor reads no part"
        return False, "no camera image since the lift and no gripper part sensor reading: no evidence the part is held"

    def _clear_the_view(self):
        """Back to the wait position after a pick that did not happen: over the belt the arm
        can stand between the camera and the markers, and with the registration gone no part
        is seen again (a cell once waited there for good). A refused or stopped move leaves
        the arm where it is; the stop is the operator's to handle."""
        try:
            self.go_to_wait()
        except PickAborted:
            pass

    def go_to_wait(self):
        """Tool to the wait position (MoveL at transit height first)."""
        P = self.params
        self._rise_then_move(np.asarray(P["wait_position"], float) - [0.0, 0.0, self.cell.gripper.tcp_length])

    def measure_descent(self) -> float:
        """Time (s) a descent takes on this controller now, measured at the wait position by
        one move down the descent's length (hover_height - grasp_gap) and back; it replaces
        the ``descent_time`` first estimate. The first pick is timed with it: at the belt's
        5 cm/s a descent 0.2 s longer than planned puts the magnet 1 cm behind the part,
        the grip radius."""
        P = self.params
        top = self._face_now()
        down = top - [0.0, 0.0, P["hover_height"] - P["grasp_gap"]]
        began = self.clock()
        self._move_l(down, check_from=top)
        took = self.clock() - began
        self._move_l(top, check_from=down)
        self.descent_time = min(max(took, 0.05), 5.0)
        return self.descent_time

    def _move_to(self, face):
        """MoveL of the magnet face to ``face`` in one straight move when the magnet is at
        least ``hover_height`` above the belt and the tray floor and the straight path keeps
        ``clearance`` (no stop on the way: the carry from the lift point); else straight up
        first (``_rise_then_move``)."""
        start = self._face_now()
        clear = max(self.cell.belt.height, self.cell.tray.position[2]) + self.params["hover_height"]
        if start[2] >= clear - 1e-3 and not check_segment(start, face, self.obstacles, self.params["clearance"]):
            self._move_l(face, check_from=start)
        else:
            self._rise_then_move(face)

    def _rise_then_move(self, face):
        """MoveL of the magnet face to ``face``, straight up to its height first when below it
        (never sideways low over the belt or the tray)."""
        start = self._face_now()
        if start[2] < face[2] - 1e-3:
            self._move_l(np.r_[start[:2], face[2]])
        self._move_l(face)

    def forget_finished(self):
        """Drop records of tracks the tracker has stopped (bounded memory)."""
        with self.lock:
            live = set(self.tracker.tracks)
        for track_id in [k for k in self.records if k not in live]:
            del self.records[track_id]

    def _emit(
        self, track: Track, event: str, reason: str = "", position=None, verified: bool = True, phases=None
    ) -> KittingEvent:
        item = KittingEvent(
            track.track_id,
            track.class_name,
            event,
            reason,
            None if position is None else np.asarray(position, float),
            self.clock(),
            verified,
            None if phases is None else dict(phases),
        )
        self.on_event(item)
        return item
