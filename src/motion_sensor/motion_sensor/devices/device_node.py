"""The one ROS node wrapper of every hand device (a ROS edge: it imports rospy, the
device classes do not). A device executable is three lines:

    from motion_sensor.devices.device_node import run_device_node
    from motion_sensor.devices.leap_client import LeapDevice
    run_device_node(LeapDevice, "leap_driver")

Its interface is ``device_interface.device_interface(device_cls, node_name)``: the
device's parameters merged with WRAPPER_PARAMS (a bad or unknown key stops the node naming
the file, the key and the valid keys) and the topics below, all relative. It waits until
the session is ready (with ``~wait_for_ready``, True on ``session_ready``;
``~min_subscribers`` on ``motion_sensor/raw_hand``; then ``~start_delay``), streams through
a DeviceRunner (reconnect with backoff, bad samples dropped and counted), publishes
``motion_sensor/raw_hand``, the device's Bool outputs (latched), counters on
``diagnostics``, and for a finite device a latched ``~finished`` (False at start, True at
the end, then the node exits).
"""

import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from std_msgs.msg import Bool

from motion_common.errors import ParameterError
from motion_common.ros_interface import load_params, publisher, subscriber
from motion_common.startup_heap import freeze_startup_heap
from motion_sensor.devices.device import Backoff, DeviceRunner, HandDevice, wait_until_ready
from motion_sensor.devices.device_interface import WRAPPER_PARAMS, device_interface, node_schema  # noqa: F401 (re-export)
from motion_sensor.errors import MotionSensorError
from motion_sensor.ros_conversions import sample_to_msg, skeleton_to_msg


class DeviceNode:
    """ROS wiring of one HandDevice through a DeviceRunner."""

    def __init__(self, device_cls, node_name: str):
        self.node_name = node_name
        self.interface = device_interface(device_cls, node_name)
        self.config = load_params(self.interface)
        try:
            self.device: HandDevice = device_cls(self.config, clock=rospy.get_time, sleep=rospy.sleep)
        except (MotionSensorError, ParameterError, OSError) as exc:
            rospy.logfatal("%s: %s", node_name, exc)
            raise SystemExit(1) from None
        self.device.info = lambda text: rospy.loginfo("%s: %s", node_name, text)
        self.device.warn = lambda text: rospy.logwarn_throttle(5.0, f"{node_name}: {text}")
        # queue_size None is rospy's synchronous publish: the device thread does the socket
        # write itself. Hand frames are small and the device thread has nothing else to do,
        # so the queue's thread hand-off would only add latency.
        self.publisher = publisher(
            self.interface, "motion_sensor/raw_hand", queue_size=self.config["queue_size"] or None, tcp_nodelay=True
        )
        self.skeleton_publisher = None
        if device_cls.publishes_skeletons:
            self.skeleton_publisher = publisher(self.interface, "motion_sensor/raw_hand_skeleton", queue_size=10)
        self.bool_pubs = {
            key: publisher(self.interface, topic, queue_size=1) for key, topic in device_cls.bool_outputs.items()
        }
        self.finished_pub = None
        if device_cls.finite:
            self.finished_pub = publisher(self.interface, "~finished", queue_size=1)
            self.finished_pub.publish(Bool(False))
        self.diag_pub = publisher(self.interface, "diagnostics", queue_size=5)
        self.ready = False
        self.state = "starting"
        if self.config["wait_for_ready"]:
            self.ready_sub = subscriber(self.interface, "session_ready", self._on_ready, queue_size=1)
        backoff = Backoff(
            self.config["backoff_initial_s"],
            self.config["backoff_factor"],
            max(self.config["backoff_max_s"], self.config["backoff_initial_s"]),
        )
        self.runner = DeviceRunner(
            self.device,
            self._publish,
            rospy.is_shutdown,
            backoff,
            publish_bool=lambda key, value: self.bool_pubs[key].publish(Bool(value)),
        )
        rospy.Timer(rospy.Duration(self.config["diagnostics_period_s"]), self.publish_diagnostics)
        rospy.on_shutdown(self.device.stop)

    def _on_ready(self, msg):
        self.ready = bool(msg.data)

    def _publish(self, sample):
        msg = sample_to_msg(sample)
        msg.header.stamp = rospy.Time.now() if self.device.stamp_on_publish else rospy.Time.from_sec(sample.stamp)
        self.publisher.publish(msg)
        if self.skeleton_publisher is not None:
            # After the palm frame, with its stamp: the sequencer pairs the two by stamp.
            for skeleton in sample.skeletons:
                if skeleton.problem() is None:
                    self.skeleton_publisher.publish(skeleton_to_msg(skeleton, msg.header))
                else:
                    self.device.counters["invalid_skeletons"] += 1

    def wait_until_ready(self) -> bool:
        """Block until the session is ready to receive the stream."""
        conditions = []
        if self.config["wait_for_ready"]:
            conditions.append((f"True on {self.ready_sub.resolved_name}", lambda: self.ready))
        wanted = self.config["min_subscribers"]
        if wanted > 0:
            conditions.append(
                (
                    f"{wanted} subscriber(s) of {self.publisher.resolved_name}",
                    lambda: self.publisher.get_num_connections() >= wanted,
                )
            )
        self.state = "waiting for the session to be ready"
        ready = wait_until_ready(
            conditions,
            rospy.is_shutdown,
            rospy.get_time,
            rospy.sleep,
            lambda text: rospy.loginfo("%s: %s", self.node_name, text),
        )
        if ready and self.config["start_delay"] > 0:
            rospy.sleep(self.config["start_delay"])
        return ready and not rospy.is_shutdown()

    def spin(self) -> None:
        """Wait for readiness, stream, and for a finite device report the end and return."""
        try:
            if not self.wait_until_ready():
                return
            self.state = "streaming"
            rospy.loginfo(
                "%s: streaming %s to %s", self.node_name, self.device.describe(), self.publisher.resolved_name
            )
            finished = self.runner.run()
        except MotionSensorError as exc:
            rospy.logfatal("%s: %s", self.node_name, exc)
            raise SystemExit(1) from None
        finally:
            self.device.shutdown()
        if finished:
            self.state = "finished"
            rospy.loginfo(
                "%s: %s done, %d samples published",
                self.node_name,
                self.device.describe(),
                self.device.counters["published"],
            )
            self.publish_diagnostics(None)
            if self.finished_pub is not None:
                self.finished_pub.publish(Bool(True))
                rospy.sleep(0.5)  # let the latched message reach late subscribers before exiting

    def publish_diagnostics(self, _event):
        counters = dict(self.device.counters)
        status = DiagnosticStatus(name=f"motion_sensor: {self.node_name}", hardware_id=self.device.name)
        if self.device.connected or self.state == "finished":
            status.level = DiagnosticStatus.OK
            status.message = (
                f"{self.device.describe()}: {counters.get('published', 0)} published, "
                f"{counters.get('rejected', 0)} rejected, {counters.get('invalid_samples', 0)} invalid"
            )
        else:
            status.level = DiagnosticStatus.WARN
            problem = self.runner.last_problem
            status.message = (
                f"{self.device.describe()}: not connected" + (f" ({problem})" if problem else "")
                if self.state == "streaming"
                else f"{self.device.describe()}: {self.state}"
            )
        status.values = [KeyValue(key=str(k), value=str(v)) for k, v in sorted(counters.items())]
        array = DiagnosticArray(status=[status])
        array.header.stamp = rospy.Time.now()
        self.diag_pub.publish(array)


def run_device_node(device_cls, node_name: str) -> None:
    """The whole life of a device node: init, parameters, readiness, stream, exit."""
    rospy.init_node(node_name)
    node = DeviceNode(device_cls, node_name)
    freeze_startup_heap()
    spin_device_node(node)


def spin_device_node(node: DeviceNode) -> None:
    """Run the device's stream; if it returns before the source has finished (a device
    fed by subscriber callbacks), keep the node spinning until ROS shuts down."""
    try:
        node.spin()
        if not node.runner.finished and not rospy.is_shutdown():
            rospy.spin()
    except rospy.ROSInterruptException:
        pass
