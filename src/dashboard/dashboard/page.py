"""The NiceGUI page (the operator's console): built once per browser tab, refreshed from
DashboardState snapshots by timers, never per message: the readings at refresh_s, the 3-D
view at scene_rate, the camera at camera_rate. Controls call the node's actions off the
event loop (run.io_bound), so a slow service never freezes the page. Panels belong to
applications (application.PANELS): those of another application are hidden. Elements carry
data-testid attributes for the browser test.

Above the fold at 1400 x 1000: the 3-D view, the hand/tool path plot and the joints (the
camera in kitting sessions).
"""

import time
from collections.abc import Callable

from nicegui import app, run, ui

from motion_sensor.sequencing.filters import FILTERS as FILTER_REGISTRY

from .access import HostOriginGuard, token_accepted
from .application import panels_for
from .controls import control_states
from .episodes import episode_rows, episode_status_text
from .readings import device_label, image_data_url, kit_score_text
from .status_style import STATUS_COLOURS, status_view
from .tray import tray_text

__all__ = ["DashboardPage", "serve"]

COLOURS = {"grey": "#9e9e9e", "green": "#2e7d32", "amber": "#f9a825", "orange": "#ef6c00", "red": "#c62828"}
FILTERS = list(FILTER_REGISTRY)  # the sequencer's filters, in its order
REASON_GROUPS = (
    ("engage", "disengage"),
    ("dry_run", "replay", "delete"),
    ("campaign_start", "campaign_end"),
    ("episode_start", "episode_stop", "episode_discard", "episode_success", "episode_failure"),
)
EPISODE_COLUMNS = ("episode", "task", "frames", "seconds", "outcome", "camera loss")
CARD_W = "width: 425px"
LINK_RADIUS_M = 0.035
JOINT_RADIUS_M = 0.045
EVENT_LINES = 60  # lines of the log on the page (the state keeps more)
STATUS_AXIS = [status.name for status in STATUS_COLOURS]  # the status chart's categories


def _fmt(value, digits=1, unit=""):
    if value is None or value != value:  # None or NaN (no samples yet)
        return "-"
    return f"{value:.{digits}f}{unit}"


def _tid(element, name: str):
    """Tag an element for the browser test."""
    return element.props(f'data-testid="{name}"')


class DashboardPage:
    """The widgets of one browser tab and their refresh."""

    def __init__(self, state, actions, params: dict):
        self.state = state
        self.actions = actions
        self.params = params
        self.reasons = {}
        self.buttons = {}
        self.selected_program = None
        self.program_rows_key = None
        self.chart_key = None
        self.inputs_seeded = False
        self.panels = {}  # panel name -> card, shown only for its applications
        self.robot_view = getattr(actions, "robot_view", None)
        self.scene_version = None
        self.trail_key = None
        self.camera_frame = None
        self.events_version = None
        self.series_key = None
        self.joint_rows = []

    # -- building ------------------------------------------------------------------------
    def build(self) -> None:
        ui.add_css(".dash-card { width: 370px; } .dash-key { color: #616161; min-width: 130px; }")
        ui.button.default_props("no-caps")  # labels as written: "Release", and STOP in capitals by itself
        with ui.header().classes("items-center bg-blue-grey-9 q-py-sm"):
            ui.label(self.params["title"]).classes("text-h6")
            self.status_badge = (
                _tid(ui.label("NO STATUS"), "teleop-status")
                .classes("text-h5 text-white q-px-md q-py-xs rounded-borders")
                .style("background-color:#9e9e9e")
            )
            ui.space()
            self.latched_label = _tid(ui.label(""), "latched").classes("text-subtitle1 text-red-3")
            self.buttons["release"] = _tid(ui.button("Release", on_click=self.on_release), "release").props(
                "color=white text-color=black"
            )
            self.reasons["release"] = ui.label("").classes("text-caption text-grey-4")
            # The one control whose label contains STOP: large, red, in the always-visible header.
            self.buttons["stop"] = (
                _tid(ui.button("STOP", on_click=self.on_stop), "stop")
                .props("color=red-10 size=xl unelevated")
                .classes("text-h4 q-px-xl")
            )
        with ui.row().classes("w-full q-px-sm q-pt-sm items-stretch"):
            self._scene_card()
            self._plot_card()
            self._camera_card()
            self._joints_card()
        with ui.row().classes("w-full q-px-sm items-stretch"):
            self._series_card()
            self._events_card()
        with ui.row().classes("w-full q-px-sm items-stretch"):
            self._input_card()
            self._teleop_card()
            self._robot_card()
            self._sequencer_card()
            self._programs_card()
            self._kitting_card()
            self._episodes_card()
        ui.label(
            "The STOP button is a software stop through the robot server, not a safety-rated emergency stop: "
            "keep the robot's own e-stop within reach."
        ).classes("q-pa-sm text-caption text-grey-8")
        ui.timer(self.params["refresh_s"], self.refresh)
        ui.timer(1.0 / self.params["scene_rate"], self.refresh_scene)
        ui.timer(1.0 / self.params["camera_rate"], self.refresh_camera)

    def _row(self, key: str, testid: str):
        with ui.row().classes("no-wrap q-gutter-x-sm"):
            ui.label(key).classes("dash-key")
            return _tid(ui.label("-"), testid)

    def _reason(self, name: str):
        self.reasons[name] = _tid(ui.label("").classes("text-caption text-orange-9"), f"reason-{name}")

    def _panel(self, name: str, style: str = ""):
        """A card that belongs to the panel ``name`` (hidden in other applications)."""
        card = _tid(ui.card(), f"panel-{name}").classes("dash-card q-pa-sm")
        if style:
            card.style(style)
        # Shown or hidden from the start, not from the first refresh: a page must never flash
        # (or, on a slow machine, show for a while) another application's panels.
        card.set_visibility(name in panels_for(self.state.get("application") or "teleop"))
        self.panels[name] = card
        return card

    def _scene_card(self):
        with self._panel("scene", CARD_W):
            ui.label("Robot (3-D, m; drag to turn)").classes("text-subtitle1 text-weight-bold")
            self.scene_info = _tid(ui.label("-"), "scene-info").classes("text-caption")
            with _tid(
                ui.scene(width=405, height=300, grid=(4, 20), background_color="#f5f5f5"), "robot-scene"
            ) as scene:
                self.scene = scene
                n = self.robot_view.dof + 1 if self.robot_view is not None else 0
                # Link i runs from frame point i to i + 1 (base, joints..., tool): cylinders of
                # height 1 along their y axis, placed, turned and stretched per refresh.
                self.link_objects = [
                    scene.cylinder(LINK_RADIUS_M, LINK_RADIUS_M, 1.0, 12).material("#607d8b").with_name(f"link_{i}")
                    for i in range(n)
                ]
                self.joint_objects = [
                    scene.sphere(JOINT_RADIUS_M, 12, 8).material("#37474f").with_name(f"joint_{i}") for i in range(n)
                ]
                self.target_object = scene.sphere(0.03, 12, 8).material("#e53935").with_name("target").visible(False)
                self.trail_object = scene.point_cloud([], point_size=0.012).material("#1e88e5").with_name("tool_path")
            scene.move_camera(x=0.35, y=-1.0, z=0.75, look_at_x=-0.4, look_at_z=0.25, duration=0)
            if self.robot_view is None:
                self.scene_info.set_text("no robot model (no ~urdf and no /robot_description): no arm drawn")

    def _camera_card(self):
        with self._panel("camera", CARD_W):
            ui.label("Kitting camera (detections drawn)").classes("text-subtitle1 text-weight-bold")
            self.camera_info = _tid(ui.label("no image yet (kitting/vision/annotated)"), "camera-info").classes(
                "text-caption"
            )
            self.camera_image = _tid(ui.interactive_image(), "camera-image").classes("w-full")

    def _joints_card(self):
        with self._panel("joints", CARD_W):
            ui.label("Joints (deg, bar: URDF limits)").classes("text-subtitle1 text-weight-bold")
            names = self.robot_view.joint_names if self.robot_view is not None else []
            for i, name in enumerate(names):
                with ui.row().classes("w-full items-center no-wrap q-gutter-x-sm"):
                    ui.label(name).classes("text-caption").style("width: 130px")
                    value = _tid(ui.label("-"), f"joint-{i}").classes("text-body2 text-right").style("width: 60px")
                    bar = ui.linear_progress(value=0.5, show_value=False, size="10px").classes("col")
                    limits = ui.label("").classes("text-caption text-grey-7").style("width: 90px")
                self.joint_rows.append((value, bar, limits))
            if not names:
                ui.label("no robot model: joint names and limits unknown").classes("text-caption")

    def _series_card(self):
        with self._panel("series", "width: 866px"):
            ui.label("Last minute: latency, tracking error, status").classes("text-subtitle1 text-weight-bold")
            self.series_chart = _tid(
                ui.echart(
                    {
                        "animation": False,
                        "legend": {"data": ["latency (ms)", "tracking error (mm)"], "top": 0},
                        "grid": {"left": 60, "right": 65, "top": 40, "bottom": 25},
                        "xAxis": {"type": "value", "name": "s", "max": 0},
                        "yAxis": [
                            {"type": "value", "scale": True, "axisLabel": {"formatter": "{value} ms"}},
                            {"type": "value", "scale": True, "axisLabel": {"formatter": "{value} mm"}},
                        ],
                        "series": [
                            {"name": "latency (ms)", "type": "line", "showSymbol": False, "data": []},
                            {
                                "name": "tracking error (mm)",
                                "type": "line",
                                "showSymbol": False,
                                "yAxisIndex": 1,
                                "data": [],
                            },
                        ],
                    }
                ),
                "series-chart",
            ).classes("w-full h-48")
            self.status_chart = _tid(
                ui.echart(
                    {
                        "animation": False,
                        "grid": {"left": 170, "right": 60, "top": 5, "bottom": 25},
                        "xAxis": {"type": "value", "name": "s", "max": 0},
                        "yAxis": {"type": "category", "data": STATUS_AXIS, "axisLabel": {"fontSize": 9}},
                        "series": [{"name": "status", "type": "line", "step": "end", "showSymbol": False, "data": []}],
                    }
                ),
                "status-chart",
            ).classes("w-full h-32")

    def _events_card(self):
        with self._panel("events", CARD_W):
            ui.label("Events (newest first)").classes("text-subtitle1 text-weight-bold")
            self.events_label = (
                _tid(ui.label("-"), "events")
                .classes("text-caption whitespace-pre font-mono")
                .style("max-height: 240px; overflow-y: auto")
            )

    def _input_card(self):
        with self._panel("input"):
            ui.label("Input").classes("text-subtitle1 text-weight-bold")
            self.device_label = self._row("device", "device")
            self.active_label = self._row("active input", "active-device")
            self.filter_label = self._row("active filter", "filter")
            self.hands_label = self._row("hands seen", "hands")
            self.gesture_label = self._row("last gesture", "gesture")
            self.teach_label = self._row("teach mode", "teach")

    def _teleop_card(self):
        with self._panel("teleop"):
            ui.label("Teleop").classes("text-subtitle1 text-weight-bold")
            self.mode_label = self._row("engage mode", "engage-mode")
            self.latency_label = self._row("latency p50 / p99", "latency")
            self.ratio_label = self._row("speed ratio", "speed-ratio")
            with ui.row():
                self.buttons["engage"] = _tid(ui.button("Engage", on_click=lambda: self.on_engage(True)), "engage")
                self.buttons["disengage"] = _tid(
                    ui.button("Disengage", on_click=lambda: self.on_engage(False)), "disengage"
                )
            self._reason("engage")  # one line for both when their reasons agree (see refresh)
            self._reason("disengage")
            with ui.row().classes("items-center"):
                # Text, not a number field: what the operator typed reaches the check as typed,
                # so "abc" or an empty field gets a message naming the range, not a silent None.
                self.ratio_input = _tid(ui.input("new speed ratio", value=""), "ratio-input").classes("w-32")
                self.buttons["speed_ratio"] = _tid(ui.button("Apply", on_click=self.on_ratio), "apply-ratio")
            self._reason("speed_ratio")
            self.ratio_message = _tid(ui.label("").classes("text-caption text-negative"), "ratio-message")
            with ui.row().classes("items-center"):
                self.filter_select = _tid(ui.select(FILTERS, label="filter", value=None), "filter-select").classes(
                    "w-32"
                )
                self.buttons["filter"] = _tid(ui.button("Switch", on_click=self.on_filter), "apply-filter")
            self._reason("filter")

    def _robot_card(self):
        with self._panel("robot"):
            ui.label("Robot").classes("text-subtitle1 text-weight-bold")
            self.driver_label = self._row("driver", "driver")
            self.fault_label = self._row("fault / protective", "fault")
            self.joints_label = self._row("joints (deg)", "joints")
            self.tool_label = self._row("tool xyz (mm)", "tool")
            self.tool_rpy_label = self._row("tool rpy (deg)", "tool-rpy")

    def _sequencer_card(self):
        with self._panel("sequencer"):
            ui.label("Sequencer").classes("text-subtitle1 text-weight-bold")
            self.frames_label = self._row("frames in / out", "frames")
            self.drops_label = _tid(ui.label("-"), "drops").classes("text-body2 whitespace-pre")

    def _plot_card(self):
        with self._panel("path", CARD_W):
            with ui.row().classes("items-center"):
                ui.label("Hand vs tool path (top view, mm)").classes("text-subtitle1 text-weight-bold")
                ui.button("Clear", on_click=self.state.clear_paths).props("flat dense")
            self.chart = (
                _tid(
                    ui.echart(
                        {
                            "animation": False,
                            "legend": {"data": ["hand (mapped)", "tool"]},
                            "xAxis": {"type": "value", "name": "x", "scale": True},
                            "yAxis": {"type": "value", "name": "y", "scale": True},
                            "series": [
                                {"name": "hand (mapped)", "type": "line", "showSymbol": False, "data": []},
                                {"name": "tool", "type": "line", "showSymbol": False, "data": []},
                            ],
                        }
                    ),
                    "path-plot",
                )
                .classes("w-full")
                .style("height: 320px")
            )

    def _programs_card(self):
        with self._panel("programs"):
            with ui.row().classes("items-center"):
                ui.label("Teach programs").classes("text-subtitle1 text-weight-bold")
                ui.button("Refresh", on_click=self.refresh_programs).props("flat dense")
            self.program_select = _tid(
                ui.select({}, label="program", on_change=self.on_program_selected), "program-select"
            ).classes("w-64")
            with ui.row():
                self.buttons["dry_run"] = _tid(ui.button("Dry run", on_click=lambda: self.on_run(True)), "dry-run")
                self.buttons["replay"] = _tid(ui.button("Replay", on_click=lambda: self.on_run(False)), "replay")
                self.buttons["delete"] = _tid(
                    ui.button("Delete", on_click=self.on_delete).props("color=grey-8"), "delete"
                )
            for name in ("dry_run", "replay", "delete"):
                self._reason(name)
            self.program_log = (
                _tid(ui.label(""), "program-log")
                .classes("text-caption whitespace-pre font-mono")
                .style("max-height: 12em; overflow-y: auto")
            )

    def _kitting_card(self):
        with self._panel("kitting"):
            ui.label("Kitting campaign").classes("text-subtitle1 text-weight-bold")
            with ui.row().classes("items-center"):
                self.trials_input = ui.number(
                    "trials", value=self.params["campaign_trials"], min=1, max=1000, step=1, format="%d"
                ).classes("w-24")
                self.perturb_box = ui.checkbox("perturb")
            with ui.row():
                self.buttons["campaign_start"] = _tid(
                    ui.button("Start campaign", on_click=self.on_campaign_start), "campaign-start"
                )
                self.buttons["campaign_end"] = _tid(
                    ui.button("End campaign", on_click=self.on_campaign_end), "campaign-end"
                )
            self._reason("campaign_start")
            self._reason("campaign_end")
            self.campaign_label = _tid(ui.label("-"), "campaign").classes("text-body2")
            with ui.row().classes("items-center"):
                self.tray_label = _tid(ui.label(tray_text(None)), "tray").classes("text-body2")
                self.buttons["tray_swapped"] = _tid(
                    ui.button("Tray swapped", on_click=self.on_tray_swapped), "tray-swapped"
                )
            self._reason("tray_swapped")
            self.class_table = _tid(
                ui.table(
                    columns=[
                        {"name": c, "label": c, "field": c}
                        for c in ("class", "trials", "detected", "classified", "picked", "placed", "pose p95 mm")
                    ],
                    rows=[],
                    row_key="class",
                ).props("dense flat"),
                "class-table",
            )

    def _episodes_card(self):
        with self._panel("episodes", "width: 520px"):
            ui.label("Recorded episodes (LeRobot dataset)").classes("text-subtitle1 text-weight-bold")
            self.episode_label = _tid(ui.label("-"), "episode-status").classes("text-body2")
            with ui.row():
                for key, text, word in (
                    ("episode_start", "Start", "start"),
                    ("episode_stop", "Save", "stop"),  # "STOP" is the e-stop's label alone
                    ("episode_discard", "Discard", "discard"),
                    ("episode_success", "Success", "success"),
                    ("episode_failure", "Failure", "failure"),
                ):
                    self.buttons[key] = _tid(
                        ui.button(text, on_click=lambda w=word: self.on_episode(w)), key.replace("_", "-")
                    )
            for key in ("episode_start", "episode_stop", "episode_discard", "episode_success", "episode_failure"):
                self._reason(key)
            self.episode_rows_key = None
            self.episode_table = _tid(
                ui.table(
                    columns=[{"name": c, "label": c, "field": c} for c in EPISODE_COLUMNS],
                    rows=[],
                    row_key="episode",
                )
                .props("dense flat virtual-scroll")
                .style("max-height: 260px"),
                "episode-table",
            )

    # -- refresh -------------------------------------------------------------------------
    def refresh(self) -> None:
        """Copy a snapshot into the widgets (runs on the page's timer)."""
        snap = self.state.snapshot()
        values, ages = snap["values"], snap["ages"]
        stale = self.params["stale_after_s"]

        def fresh(key):
            return key in values and ages.get(key, 1e9) <= stale

        name, colour = status_view(values.get("status"))
        self.status_badge.set_text(name)
        self.status_badge.style(f"background-color:{COLOURS[colour]}")
        self.latched_label.set_text("stop latched" if values.get("stop_latched") else "")
        application = values.get("application") or "teleop"
        shown = panels_for(application)
        for name, card in self.panels.items():
            card.set_visibility(name in shown)
        self.device_label.set_text(device_label(values.get("launch_device", ""), values.get("device"), application))
        self.active_label.set_text(values.get("device") or "-")
        self.filter_label.set_text(values.get("filter") or "-")
        hands = values.get("hands")
        self.hands_label.set_text(
            "-"
            if hands is None
            else f"{hands['num']} {', '.join(hands['types'])}" + ("" if fresh("hands") else " (stale)")
        )
        gesture = values.get("gesture")
        self.gesture_label.set_text(
            "-" if gesture is None else f"{gesture['name']} ({gesture['confidence']:.2f}), {ages['gesture']:.0f} s ago"
        )
        self.teach_label.set_text(values.get("teach_feedback") or "-")
        self.mode_label.set_text(values.get("engage_mode") or "-")
        latency = snap["latency_ms"]
        self.latency_label.set_text(
            "-" if latency is None else f"{latency[0]:.2f} / {latency[1]:.2f} ms ({latency[2]} commands)"
        )
        self.ratio_label.set_text(_fmt(values.get("speed_ratio"), 2))
        driver = values.get("driver")
        if driver is None:
            self.driver_label.set_text("-")
            self.fault_label.set_text("-")
        else:
            self.driver_label.set_text(
                ("connected" if driver["connected"] else "NOT connected") + ("" if fresh("driver") else " (stale)")
            )
            self.fault_label.set_text(
                f"{driver['fault'] or 'no fault'} / {'PROTECTIVE STOP' if driver['protective_stop'] else 'no'}"
            )
        joints = values.get("joints")
        self.joints_label.set_text("-" if joints is None else " ".join(f"{j:.1f}" for j in joints))
        tool = values.get("tool")
        self.tool_label.set_text("-" if tool is None else " ".join(f"{v:.1f}" for v in tool["xyz_mm"]))
        self.tool_rpy_label.set_text("-" if tool is None else " ".join(f"{v:.1f}" for v in tool["rpy_deg"]))
        seq = values.get("sequencer")
        if seq is not None:
            self.frames_label.set_text(f"{seq.get('frames_in', '-')} / {seq.get('frames_out', '-')}")
            drops = seq.get("drops") or {}
            self.drops_label.set_text("\n".join(f"{k}: {v}" for k, v in drops.items() if v) or "no drops")
        self._refresh_plot(snap["paths"])
        self._refresh_series(snap["series"])
        if snap["events_version"] != self.events_version:
            self.events_version = snap["events_version"]
            self.events_label.set_text("\n".join(snap["events"][:EVENT_LINES]) or "-")
        self._refresh_jobs(values)
        self._refresh_episodes(values)
        jobs = self.actions.jobs()
        states = control_states(
            values, program_job=jobs["program"], campaign_job=jobs["campaign"], selected_program=self.selected_program
        )
        for key, button in self.buttons.items():
            button.set_enabled(states[key].enabled)
            if key in self.reasons:
                self.reasons[key].set_text(states[key].reason)
        for group in REASON_GROUPS:  # a reason shared by neighbouring buttons is shown once
            shown = []
            for key in group:
                if states[key].reason in shown:
                    self.reasons[key].set_text("")
                shown.append(states[key].reason)
        # The inputs start at the live values once they are known (not a made-up default).
        if not self.inputs_seeded and values.get("speed_ratio") is not None and values.get("filter"):
            self.inputs_seeded = True
            self.ratio_input.set_value(f"{values['speed_ratio']:.2f}")
            if values["filter"] in FILTERS:
                self.filter_select.set_value(values["filter"])
        self.ratio_input.set_enabled(states["speed_ratio"].enabled)
        self.filter_select.set_enabled(states["filter"].enabled)

    def _refresh_episodes(self, values):
        self.episode_label.set_text(episode_status_text(values.get("episodes_status")))
        rows = episode_rows(values.get("episodes") or [])
        key = tuple(tuple(r.values()) for r in rows)
        if key != self.episode_rows_key:
            self.episode_rows_key = key
            self.episode_table.rows = rows
            self.episode_table.update()

    def _refresh_plot(self, paths):
        key = tuple((len(p), tuple(p[-1]) if p else None) for p in paths.values())
        if key == self.chart_key:
            return
        self.chart_key = key
        self.chart.options["series"][0]["data"] = paths["hand"]
        self.chart.options["series"][1]["data"] = paths["tool"]
        self.chart.update()

    def _refresh_series(self, series):
        # Redraw when a series gained or lost a sample (the x axis is relative to now, so
        # the values themselves change every refresh).
        key = tuple((len(points), tuple(points[-1][1:]) if points else None) for points in series.values())
        if key == self.series_key:
            return
        self.series_key = key
        self.series_chart.options["series"][0]["data"] = series["latency_ms"]
        self.series_chart.options["series"][1]["data"] = series["tracking_mm"]
        self.series_chart.update()
        status = [[t, status_view(code)[0]] for t, code in series["status"]]
        if status:  # the step line reaches now
            status.append([0.0, status[-1][1]])
        self.status_chart.options["series"][0]["data"] = status
        self.status_chart.update()

    def refresh_scene(self) -> None:
        """The 3-D view (its own timer, scene_rate): the arm at the latest joints through
        the URDF's forward kinematics, the hand target and the tool path."""
        pose = self.state.robot_pose()
        view = self.robot_view
        if view is not None and pose["joint_state"] is not None and pose["joint_version"] != self.scene_version:
            self.scene_version = pose["joint_version"]
            joints = view.model_order(*pose["joint_state"])
            if joints is None:
                self.scene_info.set_text(f"joint_states lacks some of {', '.join(view.joint_names)}")
            else:
                self._draw_arm(view, joints)
        target = pose["target"]
        if target is not None:
            self.target_object.move(*target).visible(True)
        trail = pose["tool_path"]
        key = (len(trail), tuple(trail[-1]) if trail else None)
        if key != self.trail_key:
            self.trail_key = key
            self.trail_object.set_points(trail)

    def _draw_arm(self, view, joints):
        points = view.frame_points(joints)
        for obj, point in zip(self.joint_objects, points[:-1], strict=True):
            obj.move(*point)
        for obj, segment in zip(self.link_objects, view.segments(joints), strict=True):
            obj.move(*segment.center).rotate_R(segment.rotation).scale(1.0, max(segment.length, 1e-3), 1.0)
            obj.visible(segment.length > 0.0)
        tool = points[-1]
        self.scene_info.set_text(
            f"tool at {1000 * tool[0]:.0f} {1000 * tool[1]:.0f} {1000 * tool[2]:.0f} mm; "
            "grey: links, red: hand target, blue: tool path"
        )
        for (value, bar, limits), reading in zip(self.joint_rows, view.readings(joints), strict=True):
            value.set_text(f"{reading.degrees:.1f}")
            bar.set_value(reading.fraction)
            bar.props(f"color={'red' if reading.near_limit else 'primary'}")
            limits.set_text(f"{reading.lower_deg:.0f}..{reading.upper_deg:.0f}")

    def refresh_camera(self) -> None:
        """The kitting camera's newest annotated frame (its own timer, camera_rate)."""
        if "camera" not in panels_for(self.state.get("application") or "teleop"):
            return
        frame = self.state.camera()
        if frame is None or frame[0] == self.camera_frame:
            return
        self.camera_frame = frame[0]
        url = image_data_url(frame[2], frame[1])
        if url is None:
            self.camera_info.set_text(f"frame {frame[0]}: format {frame[1]!r} cannot be shown")
            return
        self.camera_image.set_source(url)
        self.camera_info.set_text(f"frame {frame[0]} ({len(frame[2]) // 1024} kB {frame[1]})")

    def _refresh_jobs(self, values):
        self.program_log.set_text("\n".join(self.actions.job_lines("program")[-12:]))
        progress = values.get("campaign_result") or values.get("campaign_progress")
        campaign_lines = self.actions.job_lines("campaign")
        status = campaign_lines[-1] if campaign_lines else "-"
        if values.get("campaign_result"):
            result = values["campaign_result"]
            status = (
                f"done: {result.get('successes', '?')}/{result.get('trials', '?')} placed{kit_score_text(result)}"
                if "error" not in result
                else f"error: {result['error']}"
            )
        elif progress and kit_score_text(progress):
            status = f"{status}{kit_score_text(progress)}"
        self.campaign_label.set_text(status)
        self.tray_label.set_text(tray_text(values.get("tray")))
        if progress and "per_class" in progress:
            rows = [
                {
                    "class": name,
                    **{k: row[k] for k in ("trials", "detected", "classified", "picked", "placed")},
                    "pose p95 mm": _fmt(row.get("pose_error_mm_p95"), 2),
                }
                for name, row in progress["per_class"].items()
            ]
            if rows != self.class_table.rows:
                self.class_table.rows = rows
                self.class_table.update()

    def refresh_programs(self) -> None:
        """Re-read the programs folder into the select."""
        options = {}
        for info in self.actions.programs():
            detail = f"{info.waypoints} waypoints, {info.robot}" if not info.error else "unreadable"
            options[info.name] = f"{info.name} ({detail})"
        self.program_select.set_options(
            options, value=self.selected_program if self.selected_program in options else None
        )

    # -- actions -------------------------------------------------------------------------
    async def on_stop(self):
        clicked = time.monotonic()
        message = await run.io_bound(self.actions.stop)
        ui.notify(f"{message} ({1000 * (time.monotonic() - clicked):.0f} ms)", type="negative")

    async def on_release(self):
        ui.notify(await run.io_bound(self.actions.release))

    async def on_engage(self, on: bool):
        ui.notify(await run.io_bound(self.actions.engage, on))

    async def on_ratio(self):
        decision = self.actions.check_speed_ratio(self.ratio_input.value)
        if not decision.ok:
            self.ratio_message.set_text(decision.message)
            ui.notify(f"speed ratio refused: {decision.message}", type="warning")
            return
        self.ratio_message.set_text("")
        if decision.confirm:
            with ui.dialog() as dialog, ui.card():
                _tid(ui.label(decision.message), "confirm-text")
                with ui.row():
                    _tid(ui.button("Apply", on_click=lambda: dialog.submit(True)), "confirm-yes").props(
                        "color=negative"
                    )
                    _tid(ui.button("Cancel", on_click=lambda: dialog.submit(False)), "confirm-no")
            if not await dialog:
                ui.notify("speed ratio unchanged")
                return
        ui.notify(await run.io_bound(self.actions.set_speed_ratio, decision.value))

    async def on_filter(self):
        if not self.filter_select.value:
            ui.notify("choose a filter first", type="warning")
            return
        ui.notify(await run.io_bound(self.actions.set_filter, self.filter_select.value))

    def on_program_selected(self, event):
        self.selected_program = event.value

    async def on_run(self, dry_run: bool):
        ui.notify(await run.io_bound(self.actions.run_program, self.selected_program, dry_run))

    async def on_delete(self):
        name = self.selected_program
        with ui.dialog() as dialog, ui.card():
            ui.label(f"Delete program {name}? This cannot be undone.")
            with ui.row():
                ui.button("Delete", on_click=lambda: dialog.submit(True)).props("color=negative")
                ui.button("Cancel", on_click=lambda: dialog.submit(False))
        if await dialog:
            ui.notify(self.actions.delete_program(name))
            self.selected_program = None
            self.refresh_programs()

    async def on_campaign_start(self):
        ui.notify(
            await run.io_bound(
                self.actions.start_campaign, int(self.trials_input.value or 1), bool(self.perturb_box.value)
            )
        )

    async def on_campaign_end(self):
        ui.notify(await run.io_bound(self.actions.end_campaign))

    async def on_tray_swapped(self):
        ui.notify(await run.io_bound(self.actions.tray_swapped))

    async def on_episode(self, word: str):
        ui.notify(await run.io_bound(self.actions.episode_command, word))


def serve(state, actions, params: dict, on_started: Callable[[], None] = None, extra_hosts=()) -> None:
    """Serve the page until the server is told to stop (SIGINT, or app.shutdown()). Every
    request, the page's socket.io connection included, first passes the Host/Origin guard
    (``extra_hosts``: names besides loopback and ``host`` that this server answers to)."""
    app.add_middleware(HostOriginGuard, host=params["host"], extra_hosts=tuple(extra_hosts))

    @ui.page("/")
    def index(token: str = ""):
        if not token_accepted(params["token"], token):
            ui.label("Access token missing or wrong: open http://HOST:PORT/?token=<the dashboard_token>.")
            return
        page = DashboardPage(state, actions, params)
        page.build()
        page.refresh_programs()

    if on_started is not None:
        app.on_startup(on_started)
    ui.run(
        host=params["host"],
        port=int(params["port"]),
        title=params["title"],
        show=False,
        reload=False,
        show_welcome_message=False,
        favicon="🤖",
        uvicorn_logging_level="warning",
    )
