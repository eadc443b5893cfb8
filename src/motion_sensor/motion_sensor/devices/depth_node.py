"""ROS edge of the depth-camera hand devices: the shared device node wrapper
(``motion_sensor.devices.device_node.DeviceNode``) plus, for the topic device, the image and
CameraInfo subscribers that feed it; for the Kinect, the choice between the device and a
fakenect dump (``~fakenect_dump``) made before the wrapper is built.
"""

import rospy

from motion_common.ros_interface import subscriber
from motion_sensor.devices.depth_device import DepthMessage, DepthTopicDevice
from motion_sensor.devices.device_node import DeviceNode, spin_device_node
from motion_sensor.devices.kinect import FakenectKinectDevice, KinectDevice


def run_depth_node(node_name: str = "depth_hand_driver") -> None:
    """Hands from a depth image topic: subscribe, feed the device, stream its samples."""
    rospy.init_node(node_name)
    node = DeviceNode(DepthTopicDevice, node_name)
    device: DepthTopicDevice = node.device

    def on_info(msg):
        device.feed_info(msg.K, msg.width, msg.height)

    def on_image(msg):
        device.feed_image(
            DepthMessage(
                stamp=msg.header.stamp.to_sec(),
                encoding=msg.encoding,
                width=msg.width,
                height=msg.height,
                step=msg.step,
                data=msg.data,
                is_bigendian=bool(msg.is_bigendian),
            )
        )

    subscriber(node.interface, "camera/depth/camera_info", on_info, queue_size=1)
    # A 640x480 16UC1 image is 600 kB: a large buffer keeps rospy from queueing stale ones.
    subscriber(node.interface, "camera/depth/image_raw", on_image, queue_size=2, buff_size=1 << 24, tcp_nodelay=True)
    spin_device_node(node)


def run_kinect_node(node_name: str = "kinect_driver") -> None:
    """Hands from a Kinect v1 (libfreenect), or from a fakenect dump when ~fakenect_dump is set."""
    rospy.init_node(node_name)
    device_cls = FakenectKinectDevice if rospy.get_param("~fakenect_dump", "") else KinectDevice
    spin_device_node(DeviceNode(device_cls, node_name))
