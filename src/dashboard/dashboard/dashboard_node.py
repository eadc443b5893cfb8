"""The dashboard's ROS edge: subscribers feed DashboardState, actions call the core's and
the server's services, and the NiceGUI server runs in the same process.

rospy is initialised with disable_signals=True: uvicorn owns SIGINT (roslaunch's shutdown),
stops serving, and then this node shuts rospy down and ends its child jobs. A rospy
shutdown from elsewhere (rosnode kill) stops the web server in turn.
"""

import json
import os
import tempfile
import threading

import numpy as np
import rospy
import rosservice
from std_msgs.msg import Bool, Empty, Float64, String

from dashboard.interfaces import DASHBOARD
from motion_commander.config import TELEOP_PARAMETERS
from motion_common.errors import ParameterError, RobotModelError
from motion_common.ros_interface import publisher, service_proxy, subscriber
from motion_common.ros_params import load_private_params

from . import programs as program_files
from .access import check_access_config, load_token
from .application import detect_application
from .config import DASHBOARD_PARAMETERS
from .controls import check_speed_ratio
from .episodes import parse_episode_message
from .jobs import Job, campaign_command, campaign_summary, run_program_command
from .readings import campaign_line, driver_status, kitting_event_line, sequencer_counters, tool_reading
from .state import DashboardState
from .tray import parse_tray, tray_text

LATCH_SERVICE = "motion_controller/latch_stop"
SPAWN_SERVICE = "kitting_cell_sim/spawn"


class DashboardNode:
    """Subscriptions into the state, and the actions the page's controls call."""

    def __init__(self, params):
        self.params = params
        self.state = DashboardState(
            path_points=params["path_points"],
            path_interval_s=params["path_interval_s"],
            latency_window=params["latency_window"],
            series_points=params["series_points"],
            series_interval_s=params["series_interval_s"],
            events=params["events"],
        )
        self.robot_view = load_robot_view(params["urdf"])
        auto = params["application"] == "auto"
        self.state.update(application=None if auto else params["application"], launch_device=params["device"])
        self.jobs_lock = threading.Lock()
        self._jobs = {"program": None, "campaign": None}
        self.fallback_estop = False
        self.programs_dir = os.path.abspath(params["programs_dir"])
        self.output_dir = os.path.abspath(params["output_dir"])
        self.engage_pub = publisher(DASHBOARD, "motion_commander/engage", queue_size=1)
        self.estop_pub = publisher(DASHBOARD, "motion_commander/estop", queue_size=1)
        self.ratio_pub = publisher(DASHBOARD, "motion_commander/set_speed_ratio", queue_size=1)
        self.filter_pub = publisher(DASHBOARD, "motion_sensor/set_filter", queue_size=1)
        self.campaign_stop_pub = publisher(DASHBOARD, "kitting_trials/stop", queue_size=1)
        self.tray_swapped_pub = publisher(DASHBOARD, "kitting/tray_swapped", queue_size=1)
        self.episode_pub = publisher(DASHBOARD, "episodes/command", queue_size=5)
        self.latch = service_proxy(DASHBOARD, LATCH_SERVICE)
        s = self.state

        def subscribe(name, callback, **kwargs):
            return subscriber(DASHBOARD, name, callback, **kwargs)

        subscribe("motion_commander/status", lambda m: s.set_status(m.data), queue_size=10)
        subscribe("motion_controller/stop_latched", self.on_stop_latched, queue_size=5)
        subscribe("motion_commander/speed_ratio", lambda m: s.set("speed_ratio", float(m.data)), queue_size=5)
        subscribe("motion_sensor/filter", lambda m: s.set("filter", m.data), queue_size=5)
        subscribe("motion_sensor/active_device", lambda m: s.set("device", m.data), queue_size=5)
        subscribe("motion_sensor/raw_hand", self.on_hand, queue_size=1)
        subscribe("motion_sensor/gesture", self.on_gesture, queue_size=10)
        subscribe("teach/feedback", lambda m: s.set("teach_feedback", m.data), queue_size=10)
        subscribe("motion_commander/latency", lambda m: s.add_latency(m.driver), queue_size=100)
        subscribe("joint_states", self.on_joints, queue_size=1)
        subscribe("motion_controller/tool_pose", self.on_tool, queue_size=1)
        subscribe("motion_commander/target", self.on_target, queue_size=10)
        subscribe("diagnostics", self.on_diagnostics, queue_size=10)
        subscribe("motion_controller/status", self.on_driver, queue_size=5)
        subscribe("episodes/status", lambda m: self.on_episode_message("episodes_status", m, dict), queue_size=5)
        subscribe("episodes/list", lambda m: self.on_episode_message("episodes", m, list), queue_size=5)
        subscribe("kitting_trials/progress", lambda m: self.on_campaign("campaign_progress", m), queue_size=5)
        subscribe("kitting_trials/result", lambda m: self.on_campaign("campaign_result", m), queue_size=5)
        subscribe("kitting/events", self.on_kitting_event, queue_size=20)
        subscribe("kitting/tray", self.on_tray, queue_size=5)
        # One frame at a time, the newest: a slow page never queues camera frames.
        subscribe("kitting/vision/annotated", self.on_camera, queue_size=1, buff_size=2**22)
        self.poll(None)
        self.poll_timer = rospy.Timer(rospy.Duration(1.0), self.poll)

    # -- inputs ----------------------------------------------------------------------------
    def on_hand(self, msg):
        self.state.set("hands", {"num": int(msg.hands_num), "types": list(msg.hand_type)})

    def on_gesture(self, msg):
        self.state.set("gesture", {"name": msg.name, "confidence": float(msg.confidence)})
        self.state.log("gesture", f"{msg.name} ({float(msg.confidence):.2f})")

    def on_stop_latched(self, msg):
        latched = bool(msg.data)
        self.state.set_watched("stop_latched", latched, "stop", "stop latched" if latched else "stop released")

    def on_joints(self, msg):
        # Copies only: forward kinematics runs on the page's timer, never per message.
        self.state.set("joints", [float(np.degrees(v)) for v in msg.position])
        self.state.set_joints(msg.name, msg.position)

    def on_tool(self, msg):
        p, o = msg.pose.position, msg.pose.orientation
        self.state.set("tool", tool_reading((p.x, p.y, p.z), (o.x, o.y, o.z, o.w)))
        self.state.add_tool(msg.header.stamp.to_sec(), (p.x, p.y, p.z))

    def on_target(self, msg):
        p = msg.pose.position
        self.state.add_target(msg.header.stamp.to_sec(), (p.x, p.y, p.z))

    def on_kitting_event(self, msg):
        if msg.event != "tracked":  # every part is tracked many times a second: not news
            self.state.log("kitting", kitting_event_line(msg.event, msg.class_name, msg.track_id, msg.reason))

    def on_camera(self, msg):
        self.state.set_camera(msg.format, msg.data)

    def on_diagnostics(self, msg):
        for status in msg.status:
            if status.hardware_id == "sequencer":
                self.state.set("sequencer", sequencer_counters((kv.key, kv.value) for kv in status.values))

    def on_driver(self, msg):
        driver = driver_status([(kv.key, kv.value) for kv in msg.values], msg.message, msg.level)
        problem = driver["fault"] or ("protective stop" if driver["protective_stop"] else "")
        self.state.set("driver", driver)
        # The reading changes with every message; the log gets a line only when the fault does.
        self.state.set_watched("driver_problem", problem, "driver", problem or "no fault")

    def on_tray(self, msg):
        tray, reason = parse_tray(msg.data)
        if tray is None:
            rospy.logwarn_throttle(10.0, "dashboard: kitting/tray refused: %s", reason)
            return
        if tray["complete"] and not (self.state.get("tray") or {}).get("complete"):
            self.state.log("kitting", tray_text(tray))
        self.state.set("tray", tray)

    def on_campaign(self, key, msg):
        try:
            data = json.loads(msg.data)
        except ValueError as exc:
            rospy.logwarn_throttle(10.0, "dashboard: unreadable %s ignored: %s", key, exc)
            return
        self.state.set(key, data)
        self.state.log("campaign", campaign_line(key, data))

    def poll(self, _event):
        """Once a second: which services exist, the core's engage mode, unless the launch
        named it the application (from the topics published now), and whether a kitting
        node still publishes the tray."""
        self.state.update(server_up=_service_exists(LATCH_SERVICE), kitting_cell=_service_exists(SPAWN_SERVICE))
        mode = self.params["engage_mode"] or rospy.get_param("motion_commander/engage", "")
        self.state.set("engage_mode", mode)
        try:
            topics = [name for name, _ in rospy.get_published_topics()]
        except Exception:  # noqa: BLE001 - the master may be gone during shutdown: keep the last answer
            return
        if self.params["application"] == "auto":
            self.state.set("application", detect_application(topics))
        if self.state.get("tray") is not None and rospy.resolve_name("kitting/tray") not in topics:
            self.state.set("tray", None)  # the kitting node is gone: its latched tray is stale

    # -- actions (called by the page, off its event loop) ----------------------------------------
    def stop(self) -> str:
        """Latch the server's stop: teleop, programs and the kitting cell all halt."""
        try:
            answer = self.latch(True)
            if answer.success:
                return "STOP latched: " + answer.message
            return "STOP refused by the server: " + answer.message
        except (rospy.ServiceException, rospy.ROSException) as exc:
            # No server to latch: at least halt teleop through the core's own e-stop.
            self.fallback_estop = True
            self.estop_pub.publish(Bool(True))
            return f"robot server unreachable ({exc}): teleop e-stop sent instead"

    def release(self) -> str:
        """Release the latched stop (teleop needs a fresh engage afterwards)."""
        if self.fallback_estop:
            self.estop_pub.publish(Bool(False))
            self.fallback_estop = False
        try:
            answer = self.latch(False)
            return ("released: " if answer.success else "release refused: ") + answer.message
        except (rospy.ServiceException, rospy.ROSException) as exc:
            return f"release failed: robot server unreachable ({exc})"

    def engage(self, on: bool) -> str:
        """The button clutch (engage:=button)."""
        self.engage_pub.publish(Bool(bool(on)))
        return "engage requested" if on else "disengage requested"

    def check_speed_ratio(self, text):
        """The page's typed ratio against the core's declared range and the ratio in force
        (controls.check_speed_ratio); a refusal goes to the event log."""
        param = TELEOP_PARAMETERS.params["speed_ratio"]
        decision = check_speed_ratio(text, self.state.get("speed_ratio"), param.low, param.high, param.low_open)
        if not decision.ok:
            self.state.log("refused", f"speed ratio: {decision.message}")
        return decision

    def set_speed_ratio(self, ratio) -> str:
        """Ask the core for a new ratio (checked again here: the last word before the
        topic); /motion_commander/speed_ratio confirms it."""
        param = TELEOP_PARAMETERS.params["speed_ratio"]
        decision = check_speed_ratio(ratio, None, param.low, param.high, param.low_open)
        if not decision.ok:
            self.state.log("refused", f"speed ratio: {decision.message}")
            return f"refused: {decision.message}"
        self.ratio_pub.publish(Float64(decision.value))
        self.state.log("operator", f"speed ratio {decision.value:.2f} requested")
        return f"speed ratio {decision.value:.2f} requested"

    def set_filter(self, name: str) -> str:
        """Ask the sequencer to switch filter; /motion_sensor/filter confirms it."""
        self.filter_pub.publish(String(name))
        return f"filter {name} requested"

    def programs(self):
        """The programs folder's listing."""
        return program_files.list_programs(self.programs_dir)

    def run_program(self, name: str, dry_run: bool) -> str:
        """Dry-run or replay a program with motion_apps' run_program."""
        try:
            path = program_files.program_path(self.programs_dir, name)
        except ValueError as exc:
            return str(exc)
        command = run_program_command(path, dry_run, self.params["scene"])
        return self._start("program", command, f"{'dry run' if dry_run else 'replay'} of {name} started")

    def delete_program(self, name: str) -> str:
        """Delete a program file."""
        return program_files.delete_program(self.programs_dir, name) or f"{name} deleted"

    def start_campaign(self, trials: int, perturb: bool) -> str:
        """Feed the simulated cell ``trials`` parts (kitting_trials); figures arrive per trial."""
        self.state.update(campaign_progress=None, campaign_result=None)
        try:
            command = campaign_command(trials, 1, perturb, self.output_dir)
        except ValueError as exc:
            return str(exc)
        return self._start("campaign", command, f"campaign of {trials} trials started", self.on_campaign_exit)

    def tray_swapped(self) -> str:
        """Tell the kitting node the finished kit's tray was taken away: every slot is free."""
        self.tray_swapped_pub.publish(Empty())
        return "tray swapped: every slot is free again"

    def end_campaign(self) -> str:
        """Ask the campaign to end after reporting the trials so far."""
        self.campaign_stop_pub.publish(Bool(True))
        return "campaign end requested: it reports the trials so far"

    def on_episode_message(self, key, msg, kind):
        value, reason = parse_episode_message(msg.data, kind)
        if value is None:
            rospy.logwarn_throttle(10.0, "dashboard: %s refused: %s", key, reason)
            return
        self.state.set(key, value)

    def episode_command(self, word: str) -> str:
        """Start, stop, discard, or mark the episode (the recorder answers on episodes/status)."""
        self.episode_pub.publish(String(word))
        return f"episode: {word} sent to the recorder"

    def on_campaign_exit(self, job):
        if self.state.get("campaign_result") is None:
            path = os.path.join(self.output_dir, "kitting_summary.json")
            self.state.set("campaign_result", campaign_summary(path, job.started, job.exit_code))

    def _start(self, kind, command, started, on_exit=None) -> str:
        with self.jobs_lock:
            job = self._jobs[kind]
            if job is not None and job.running:
                return f"a {kind} job is already running"
            try:
                self._jobs[kind] = Job(kind, command, on_exit=on_exit)
            except OSError as exc:
                return f"could not start {command[0]}: {exc}"
        return started

    def jobs(self):
        """kind -> running."""
        with self.jobs_lock:
            return {kind: job is not None and job.running for kind, job in self._jobs.items()}

    def job_lines(self, kind):
        """The output of the last job of that kind."""
        with self.jobs_lock:
            job = self._jobs[kind]
        return [] if job is None else job.lines()

    def shutdown(self):
        """End running jobs (SIGINT, as roslaunch would)."""
        with self.jobs_lock:
            jobs = [job for job in self._jobs.values() if job is not None]
        for job in jobs:
            job.stop(timeout=5.0)


def load_robot_view(urdf_path: str):
    """The robot model of the 3-D view from ``urdf_path``, or from the session's
    /robot_description when empty; None (and a warning) when neither gives one: the page
    then shows the view's reason instead of an arm."""
    from .robot_view import RobotView

    try:
        if urdf_path:
            return RobotView(urdf_path)
        text = rospy.get_param("/robot_description", "")
        if not text:
            rospy.logwarn("dashboard: no ~urdf and no /robot_description: the 3-D view shows no arm")
            return None
        # RobotKinematics reads a file: the description goes through a private temporary one.
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", encoding="utf-8", delete=False) as stream:
            stream.write(text)
        try:
            return RobotView(stream.name)
        finally:
            os.unlink(stream.name)
    except RobotModelError as exc:
        rospy.logwarn("dashboard: the 3-D view shows no arm: %s", exc)
        return None


def machine_names(host: str) -> list:
    """This machine's name and addresses when serving every interface (0.0.0.0 or ::): the
    names a browser on the network puts in the Host header."""
    if host not in ("0.0.0.0", "::"):
        return []
    import socket

    names = {socket.gethostname(), socket.getfqdn()}
    try:
        names |= {info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None)}
    except OSError:
        pass
    return sorted(names)


def _service_exists(name: str) -> bool:
    try:
        return rosservice.get_service_uri(rospy.resolve_name(name)) is not None
    except Exception:  # noqa: BLE001 - the master may be gone during shutdown; treat as absent
        return False


def main():
    """Run the dashboard node until SIGINT or a ROS shutdown."""
    rospy.init_node("dashboard", disable_signals=True)
    params = load_private_params(DASHBOARD_PARAMETERS, "dashboard")
    try:
        params["token"] = load_token(params["token"], params["token_file"])
        check_access_config(params["host"], params["token"])
    except ParameterError as exc:
        rospy.logfatal("dashboard: %s", exc)
        raise SystemExit(1) from None
    node = DashboardNode(params)
    from nicegui import app

    from .page import serve

    rospy.on_shutdown(app.shutdown)
    url = f"http://{params['host']}:{params['port']}/" + ("?token=<token>" if params["token"] else "")
    try:
        serve(
            node.state,
            node,
            params,
            on_started=lambda: rospy.loginfo("dashboard: serving %s", url),
            extra_hosts=params["allowed_hosts"] + machine_names(params["host"]),
        )
    except KeyboardInterrupt:
        pass  # uvicorn re-raises the SIGINT it handled (roslaunch's shutdown): a normal end
    finally:
        node.shutdown()
        rospy.signal_shutdown("dashboard stopped")
