"""The one declaration of every node of the kitting cell (see ``motion_common.interface``):
parameters with default, unit and range, and the topics and services each node uses, all
with relative names. No ROS import, no simulator import.
"""

from motion_common.interface import NodeInterface, Service, Topic
from motion_common.params import Param, ParamSchema

from .cell import DEFAULT_CELL
from .vision_pipeline import VISION_SCHEMA

__all__ = ["KITTING_CELL_SIM", "CAMERA_DRIVER", "VISION_NODE", "KITTING_NODE", "KITTING_TRIALS", "all_interfaces"]

_IMAGE = Topic("kitting/camera/image_raw", "sensor_msgs/Image", "the cell camera's images")
_INFO = Topic("kitting/camera/camera_info", "sensor_msgs/CameraInfo", "the cell camera's intrinsics")
_PARTS = Topic("kitting/object_poses", "kitting/PartPoseArray", "detected parts on the belt (the paper's /ObjectPose)")
_EVENTS = Topic("kitting/events", "kitting/KittingEvent", "picks, places, misses")
_READY = Topic("kitting/ready", "std_msgs/Bool", "the cell is registered and ready", latched=True)
_STATE = Topic("kitting_cell/state", "kitting/CellState", "the simulated cell's state")
_TRUTH = Topic("kitting_cell/ground_truth", "kitting/CellState", "the simulated parts' true poses")
_PART_PRESENT = Topic(
    "kitting/gripper/part_present",
    "std_msgs/Bool",
    "the gripper's part sensor (the simulated magnet's: a part is held); the evidence for a pick the camera "
    "could not confirm",
)
_TRAY_SWAPPED = Topic(
    "kitting/tray_swapped",
    "std_msgs/Empty",
    "the finished kit's tray was taken away: every slot is free again (one part per slot until then)",
)
_TRAY = Topic(
    "kitting/tray",
    "std_msgs/String",
    'the tray since the last swap, JSON: {"slots": [class, ...], "filled": [class, ...], "complete": bool}',
    latched=True,
)
_JOINTS = Topic("joint_states", "sensor_msgs/JointState", "the arm's measured joints (where the arm is in the image)")
_VISION_STATUS = Topic(
    "kitting/vision/status", "diagnostic_msgs/DiagnosticStatus", "registration and detection state", latched=True
)
_STOP_LATCHED = Topic("motion_controller/stop_latched", "std_msgs/Bool", "the server's latched stop")

_CELL_SIM_PARAMS = ParamSchema(
    [
        Param("cell", DEFAULT_CELL, "", "cell YAML (kitting/config/cell.yaml)"),
        Param(
            "physics_rate",
            100.0,
            "Hz",
            "how often the cell is brought up to the clock (physics steps 240 Hz)",
            low=10.0,
            high=1000.0,
        ),
        Param(
            "camera_rate",
            8.0,
            "Hz",
            "images per second (at most what the renderer manages, ~10 at 640x480)",
            low=0.1,
            high=60.0,
        ),
        Param("state_rate", 20.0, "Hz", "ground-truth publishing rate", low=0.1, high=1000.0),
        Param("supersample", 1, "", "render at this multiple and average down (anti-aliasing)", low=1, high=4),
        Param("frame_id", "kitting_camera", "", "frame of the images"),
        # A real camera's image (kitting.camera_effects); each can be turned off.
        Param("render_robot", True, "", "draw the arm and magnet (from joint_states): they hide parts and markers"),
        Param(
            "exposure_time",
            0.01,
            "s",
            "exposure of each image: the belt's parts are smeared over exposure x belt speed (0: sharp; "
            "a moving-belt camera keeps it short: 30 ms is 2 px at 0.065 m/s)",
            low=0.0,
            high=0.03,
        ),
        Param("exposure_drift", False, "", "vary gain, offset and gamma per image within their ranges (seeded)"),
        Param("gain_range", [0.8, 1.2], "", "exposure gain range of exposure_drift", length=2, low=0.1, high=4.0),
        Param(
            "offset_range",
            [-12.0, 12.0],
            "levels",
            "exposure offset range (of 0-255)",
            length=2,
            low=-100.0,
            high=100.0,
        ),
        Param("gamma_range", [0.85, 1.2], "", "exposure gamma range", length=2, low=0.2, high=5.0),
        Param("seed", 1, "", "random seed of exposure_drift"),
    ]
)

KITTING_CELL_SIM = NodeInterface(
    "kitting",
    "kitting_cell_sim",
    "The simulated cell: belt, parts, tray and camera (rendered in its own process), mirroring the arm's tool "
    "and gripper.",
    _CELL_SIM_PARAMS,
    publishes=(_IMAGE, _INFO, _STATE, _TRUTH, _PART_PRESENT),
    subscribes=(
        Topic("motion_controller/tool_pose", "geometry_msgs/PoseStamped", "the arm's tool"),
        Topic("motion_controller/gripper", "std_msgs/Bool", "the arm's gripper"),
        Topic(_JOINTS.name, _JOINTS.type, _JOINTS.doc, optional=True),
    ),
    serves=(
        Service("~spawn", "kitting/SpawnPart", "put a part on the belt"),
        Service("~set_conditions", "kitting/SetCellConditions", "lighting and camera perturbations"),
        Service("~clear", "std_srvs/Trigger", "remove every part"),
        Service("~clear_tray", "std_srvs/Trigger", "the tray swap: remove the parts lying in the tray"),
    ),
)

_CAMERA_DRIVER_PARAMS = ParamSchema(
    [
        Param("device", 0, low=0, doc="camera index (/dev/videoN), used when ~video and ~images are empty"),
        Param("video", "", doc="video FILE to play instead of a camera"),
        Param("images", "", doc="folder or glob of images to play instead of a camera"),
        Param("width", 640, "px", low=0, doc="requested camera width (0: the camera's default)"),
        Param("height", 480, "px", low=0, doc="requested camera height (0: the camera's default)"),
        Param("fps", 30.0, "Hz", low=0, doc="requested camera rate; rate of ~images; of a video without one"),
        Param("fourcc", "", doc="requested camera pixel format, e.g. MJPG (empty: the driver's default)"),
        Param("loop", False, doc="replay ~video / ~images at their end"),
        Param("frame_id", "kitting_camera_optical", doc="header.frame_id (the camera's optical frame)"),
        Param("image", "kitting/camera/image_raw", doc="Image topic; CameraInfo goes to camera_info beside it"),
        Param("intrinsics", "", doc="camera_info YAML written by calibrate_camera"),
        Param("camera_info_url", "", doc="the same as a URL (file:///x.yaml, package://pkg/x.yaml)"),
        Param("max_read_failures", 5, low=1, doc="failed reads in a row after which the camera counts as lost"),
        Param("backoff_initial_s", 0.25, "s", low=0, low_open=True, doc="first reopen delay"),
        Param("backoff_max_s", 5.0, "s", low=0, low_open=True, doc="longest reopen delay"),
        Param("backoff_factor", 2.0, low=1, doc="reopen delay growth per failed attempt"),
    ]
)

CAMERA_DRIVER = NodeInterface(
    "kitting",
    "camera_driver",
    "A real camera (or a video, or a folder of images) as the cell camera, with its calibrated CameraInfo.",
    _CAMERA_DRIVER_PARAMS,
    publishes=(_IMAGE, _INFO),
)

VISION_NODE = NodeInterface(
    "kitting",
    "vision_node",
    "Detects parts in the cell camera's images (classical or ONNX detector) and publishes their belt poses.",
    VISION_SCHEMA.merged(
        ParamSchema(
            [
                Param("cell", DEFAULT_CELL, doc="cell YAML"),
                Param("intrinsics", "", doc="camera_info YAML; empty: from the CameraInfo topic"),
                Param("detector_params", {}, doc="the detector's parameters"),
                Param(
                    "joint_state_max_age",
                    0.02,
                    "s",
                    "joint states this close to an image's stamp mask the arm in it (their union; at 100 Hz, 4-5)",
                    low=0.0,
                    high=10.0,
                ),
            ]
        )
    ),
    publishes=(
        _PARTS,
        _VISION_STATUS,
        Topic(
            "kitting/vision/annotated",
            "sensor_msgs/CompressedImage",
            "the camera image with the detections drawn, JPEG, at most 2 Hz (for the operator's dashboard)",
        ),
    ),
    subscribes=(
        _IMAGE,
        Topic(_INFO.name, _INFO.type, _INFO.doc, optional=True),
        Topic(_JOINTS.name, _JOINTS.type, _JOINTS.doc, optional=True),
    ),
)

KITTING_NODE = NodeInterface(
    "kitting",
    "kitting_node",
    "Picks the detected parts off the moving belt (intercept pick) and places them in the tray slots.",
    ParamSchema(
        [
            Param("cell", DEFAULT_CELL, doc="cell YAML"),
            Param("config", "", doc="kitting YAML: the picker's parameters (units inside)"),
            Param("slot_program", "", doc="a taught program whose waypoints become the tray slots"),
        ]
    ),
    publishes=(_EVENTS, _READY, _TRAY),
    subscribes=(
        _STOP_LATCHED,
        _PARTS,
        Topic(_PART_PRESENT.name, _PART_PRESENT.type, _PART_PRESENT.doc, optional=True),
        _TRAY_SWAPPED,
    ),
    calls=(Service("motion_controller", "motion_commander/commander", "the hardware interface"),),
)

KITTING_TRIALS = NodeInterface(
    "kitting",
    "kitting_trials",
    "A campaign of kitting trials on the simulated cell: feeds parts, scores each placement and writes "
    "kitting_summary.json.",
    ParamSchema(
        [
            Param("cell", DEFAULT_CELL, doc="cell YAML"),
            Param("trials", 6, "trials", "parts fed (without kit_order)", low=1, high=100000),
            Param("seed", 1, doc="random seed of classes, poses and perturbations"),
            Param("perturb", False, doc="perturb lighting and camera per trial"),
            Param(
                "kit_order",
                "",
                doc="kit order YAML (kitting.kits: the part classes of each kit); empty: kits of one part of each "
                "class, enough for trials parts",
            ),
            Param(
                "feed",
                "one_at_a_time",
                doc="one_at_a_time: the next part once the last one rests; continuous: a part every 60/rate s, "
                "several on the belt at once",
                choices=("one_at_a_time", "continuous"),
            ),
            Param("rate", 4.0, "parts/min", "arrival rate of feed continuous", low=0.1, high=120.0),
            Param("trial_timeout", 60.0, "s", "longest one trial may take", low=0.0, low_open=True),
            Param("ready_timeout", 120.0, "s", "wait for the cell to be ready", low=0.0, low_open=True),
            Param("output_dir", "output", doc="folder for kitting_summary.json"),
            Param("stay_up", False, doc="keep running after the campaign (the dashboard starts the next)"),
            Param(
                "end_session",
                False,
                doc="when done, stop the roslaunch that started this node as Ctrl-C does "
                "(a hand-started session ends without the REQUIRED banner)",
            ),
        ]
    ),
    publishes=(
        _TRAY_SWAPPED,
        Topic("kitting_trials/result", "std_msgs/String", "the campaign summary (JSON)", latched=True),
        Topic("kitting_trials/progress", "std_msgs/String", "trials done so far", latched=True),
    ),
    subscribes=(
        Topic("kitting_trials/stop", "std_msgs/Bool", "stop the campaign"),
        _READY,
        _STATE,
        _TRUTH,
        _PARTS,
        _EVENTS,
        _VISION_STATUS,
    ),
    calls=(
        Service("kitting_cell_sim/spawn", "kitting/SpawnPart", "feed a part"),
        Service("kitting_cell_sim/set_conditions", "kitting/SetCellConditions", "perturb the cell"),
        Service("kitting_cell_sim/clear_tray", "std_srvs/Trigger", "swap the tray of a finished kit"),
    ),
)


def all_interfaces():
    """Every node of this package."""
    return [KITTING_CELL_SIM, CAMERA_DRIVER, VISION_NODE, KITTING_NODE, KITTING_TRIALS]
