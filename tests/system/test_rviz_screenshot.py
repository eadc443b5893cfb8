"""RViz shows the robot: launch/teleop.rviz on a virtual X server, the arm standing at its
start pose, grabbed from the screen and written to docs/rviz.png.

The test starts its own master on a free port, robot_state_publisher with the URDF, a
publisher of what a session publishes, the arm at its start pose (this file, run with
--publish), Xvfb with its screen in a file (-fbdir: the screen is read straight from it as an
XWD image, so no screenshot tool is needed) and rviz with launch/teleop.rviz. It passes
when the 3D view shows the arm's colours (the grey joint drums and their blue caps) in its
middle and no display shows a warning; only then is docs/rviz.png replaced (atomically,
and only when the picture changed).

rviz and Xvfb are test-only Debian packages (`scripts/setup --test` installs them); without
them the test is skipped with that reason, or fails when the CI variable is set. Sources
catkin_ws/devel/setup.bash itself. About 10-20 s. Run with the ROS lock held:
  flock /tmp/ros.lock .venv/bin/python -m pytest tests/system/test_rviz_screenshot.py
Another robot's picture, for a look (not written to docs):
  flock /tmp/ros.lock .venv/bin/python tests/system/test_rviz_screenshot.py --shot tx90 /tmp/tx90.png
"""

import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SETUP = os.path.join(ROOT, "catkin_ws", "devel", "setup.bash")
PYTHON = os.path.join(ROOT, ".venv", "bin", "python")
RVIZ_CONFIG = os.path.join(ROOT, "src", "motion_bringup", "launch", "teleop.rviz")
URDF_DIR = os.path.join(ROOT, "src", "motion_common", "urdf")
POSES_DIR = os.path.join(ROOT, "src", "motion_common", "config", "robots")
SCREENSHOT = os.path.join(ROOT, "docs", "rviz.png")
WIDTH, HEIGHT = 1280, 800  # the window size teleop.rviz asks for
TIMEOUT_S = 30.0  # rviz drawing with Mesa's software OpenGL on a loaded 2-core machine
# Fewest arm pixels in the middle of the 3D view: grey drums and blue caps (the UR5e at its
# start pose, as teleop.rviz frames it, shows several times these).
MIN_GREY, MIN_BLUE = 1000, 300
# The displays' icons show a few orange pixels; a warning's icon and name some 200.
MAX_WARNING_PIXELS = 40

# Runs argv with the workspace sourced (setup.bash reads the caller's arguments, so they
# are hidden while it runs).
_WRAPPER = 'a=("$@"); set --; source "' + SETUP + '"; exec "${a[@]}"'


# -- the screen, read from Xvfb's frame-buffer file ----------------------------------------
def read_xwd(path):
    """RGB array (height, width, 3) of an XWD image of depth 24/32 (Xvfb's -fbdir screen)."""
    with open(path, "rb") as fh:
        data = fh.read()
    # XWD header: 25 big-endian CARD32 (X11's XWDFileHeader), the window name, a colour map.
    fields = struct.unpack(">25I", data[:100])
    header_size, _, _, depth, width, height = fields[:6]
    byte_order, bits_per_pixel, bytes_per_line = fields[7], fields[11], fields[12]
    masks, ncolors = fields[14:17], fields[19]
    if bits_per_pixel != 32 or depth < 24:
        raise ValueError(f"{path}: {bits_per_pixel} bits per pixel, depth {depth}; expected 32 and 24")
    start = header_size + 12 * ncolors
    rows = np.frombuffer(data, dtype=">u4" if byte_order else "<u4", count=height * bytes_per_line // 4, offset=start)
    pixels = rows.reshape(height, bytes_per_line // 4)[:, :width].astype(np.uint32)
    channels = []
    for mask in masks:
        shift = (mask & -mask).bit_length() - 1
        channels.append(((pixels & mask) >> shift).astype(np.uint8))
    return np.dstack(channels)


def robot_pixels(rgb):
    """(grey, blue) pixel counts of the arm in the middle of the 3D view (right of the
    Displays panel): lit light-grey drums, and the blue joint caps. RViz's background
    (48, 48, 48) and grid lines (about 160 grey at half alpha) count as neither."""
    h, w, _ = rgb.shape
    middle = rgb[int(0.15 * h) : int(0.85 * h), int(0.4 * w) : int(0.9 * w)].astype(int)
    r, g, b = middle[..., 0], middle[..., 1], middle[..., 2]
    grey = (np.minimum(np.minimum(r, g), b) > 170) & (np.maximum(np.maximum(r, g), b) - np.minimum(r, b) < 30)
    blue = (b > 110) & (b - r > 50) & (g > r)
    return int(grey.sum()), int(blue.sum())


def warning_pixels(rgb):
    """Orange pixels in the Displays panel's tree: RViz marks a display whose status is a
    warning (such as TF's "No transform from [hand] to frame [world]") with an orange icon
    and name. The displays' own icons give a few antialiased ones."""
    h, w, _ = rgb.shape
    tree = rgb[int(0.1 * h) : int(0.33 * h), : int(0.27 * w)].astype(int)
    r, g, b = tree[..., 0], tree[..., 1], tree[..., 2]
    return int(((r > 190) & (g > 90) & (g < 190) & (b < 90) & (r - g > 50)).sum())


def not_blank(rgb):
    """True when the picture has real content: many colours, no one colour filling it."""
    flat = rgb.reshape(-1, 3)
    _, counts = np.unique(flat[:: max(1, len(flat) // 50000)], axis=0, return_counts=True)
    return len(counts) > 50 and counts.max() < 0.9 * counts.sum()


# Two grabs of the same scene differ in RViz's frame-rate readout and in a few pixels where
# the tool frame's and the target's axes coincide; a real change of the view moves far more.
SAME_PICTURE_MAX_PIXELS = 1000


def same_picture(old, new):
    """True when two screens differ in at most SAME_PICTURE_MAX_PIXELS pixels."""
    return old.shape == new.shape and int(np.any(old != new, axis=2).sum()) <= SAME_PICTURE_MAX_PIXELS


def write_png_atomic(rgb, path):
    """Write ``rgb`` as a PNG at ``path`` through a temporary file and os.replace; leave the
    file alone when it already shows the same picture (a rerun changes nothing in git)."""
    from PIL import Image

    if os.path.exists(path):
        try:
            with Image.open(path) as old:
                if same_picture(np.asarray(old.convert("RGB")), rgb):
                    return False
        except OSError:
            pass
    folder = os.path.dirname(path)
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            Image.fromarray(rgb).save(fh, format="PNG", optimize=True)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise
    return True


# -- the ROS side --------------------------------------------------------------------------
def start_pose(robot):
    import yaml

    with open(os.path.join(POSES_DIR, f"{robot}.yaml"), encoding="utf-8") as fh:
        return [float(v) for v in yaml.safe_load(fh)["initial_joints"]]


def publish(robot):
    """--publish: what a teleop session publishes at 10 Hz, the arm held at its start pose:
    /joint_states (the driver), the tool pose on /robot_pose and /motion_commander/target
    (the core), and the sequencer's hand frame, "leap" -> "hand", which no registration
    joins to the robot here (the frame that made the former whole-tree TF display warn)."""
    sys.path.insert(0, os.path.join(ROOT, "src", "motion_common"))
    import rospy
    import tf2_ros
    from geometry_msgs.msg import PoseStamped, TransformStamped
    from sensor_msgs.msg import JointState

    from motion_common.kinematics import RobotKinematics

    kinematics = RobotKinematics(os.path.join(URDF_DIR, f"{robot}.urdf"))
    joints = start_pose(robot)
    position, orientation = kinematics.forward_pose(joints)
    rospy.init_node("screenshot_joint_states", anonymous=True)
    joint_pub = rospy.Publisher("joint_states", JointState, queue_size=1)
    pose_pubs = [rospy.Publisher(name, PoseStamped, queue_size=1) for name in ("robot_pose", "motion_commander/target")]
    hand_tf = tf2_ros.TransformBroadcaster()
    rate = rospy.Rate(10)
    while not rospy.is_shutdown():
        stamp = rospy.Time.now()
        joint_pub.publish(JointState(name=kinematics.joint_names, position=joints, header=rospy.Header(stamp=stamp)))
        pose = PoseStamped(header=rospy.Header(stamp=stamp, frame_id="base_link"))
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = (float(v) for v in position)
        q = pose.pose.orientation
        q.x, q.y, q.z, q.w = (float(v) for v in orientation)
        for pub in pose_pubs:
            pub.publish(pose)
        hand = TransformStamped(header=rospy.Header(stamp=stamp, frame_id="leap"), child_frame_id="hand")
        hand.transform.translation.z, hand.transform.rotation.w = 0.2, 1.0
        hand_tf.sendTransform(hand)
        rate.sleep()


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Session:
    """Xvfb, a master, robot_state_publisher, the pose publisher and rviz; everything it
    started is stopped on exit (each in its own process group)."""

    def __init__(self, robot, log_dir):
        self.robot, self.log_dir, self.procs = robot, log_dir, []
        self.fb_dir = tempfile.mkdtemp(prefix="xvfb-", dir=log_dir)

    def _start(self, name, argv, env=None, **kwargs):
        log = open(os.path.join(self.log_dir, name + ".log"), "wb")
        proc = subprocess.Popen(argv, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True, **kwargs)
        log.close()
        self.procs.append((name, proc))
        return proc

    def log_tail(self, name, lines=30):
        try:
            with open(os.path.join(self.log_dir, name + ".log"), encoding="utf-8", errors="replace") as fh:
                return "".join(fh.readlines()[-lines:])
        except OSError:
            return ""

    def __enter__(self):
        # Xvfb picks a free display itself and writes its number on the pipe (-displayfd).
        read_end, write_end = os.pipe()
        argv = ["Xvfb", "-displayfd", str(write_end), "-screen", "0", f"{WIDTH}x{HEIGHT}x24"]
        self._start("xvfb", argv + ["-fbdir", self.fb_dir, "-nolisten", "tcp", "-nocursor"], pass_fds=(write_end,))
        os.close(write_end)
        with os.fdopen(read_end) as pipe:
            display = pipe.readline().strip()
        if not display:
            raise RuntimeError("Xvfb did not start:\n" + self.log_tail("xvfb"))
        port = _free_port()
        env = dict(
            os.environ,
            DISPLAY=f":{display}",
            ROS_MASTER_URI=f"http://127.0.0.1:{port}",
            ROS_IP="127.0.0.1",
            ROS_HOME=os.path.join(self.log_dir, "ros"),
        )
        env.pop("ROS_HOSTNAME", None)
        ros = ["bash", "-c", _WRAPPER, "ros"]
        self._start("master", ros + ["rosmaster", "--core", "-p", str(port)], env)
        with open(os.path.join(URDF_DIR, f"{self.robot}.urdf"), encoding="utf-8") as fh:
            self._set_param(env["ROS_MASTER_URI"], "/robot_description", fh.read())
        self._start("robot_state_publisher", ros + ["rosrun", "robot_state_publisher", "robot_state_publisher"], env)
        self._start("publisher", ros + [PYTHON, os.path.abspath(__file__), "--publish", self.robot], env)
        self._start("rviz", ros + ["rviz", "-d", RVIZ_CONFIG], env)
        return self

    @staticmethod
    def _set_param(master, name, value):
        import xmlrpc.client

        proxy = xmlrpc.client.ServerProxy(master)
        deadline = time.monotonic() + 15.0
        while True:
            try:
                proxy.setParam("/rviz_screenshot_test", name, value)
                return
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)  # the master is still starting

    def screen(self):
        return read_xwd(os.path.join(self.fb_dir, "Xvfb_screen0"))

    def wait_for_robot(self, timeout=TIMEOUT_S, ur_colours=True):
        """The screen once the arm is drawn and two grabs 0.5 s apart agree (rviz has
        finished loading), or the last grab at the timeout; and the pixel counts. Without
        ``ur_colours`` (another maker's arm) any steady, non-blank screen counts as drawn."""
        deadline, last = time.monotonic() + timeout, None
        while True:
            rgb = self.screen()
            counts = robot_pixels(rgb)
            drawn = counts[0] > MIN_GREY and counts[1] > MIN_BLUE if ur_colours else not_blank(rgb)
            if drawn and last is not None and np.array_equal(rgb, last):
                return rgb, counts
            for name, proc in self.procs:
                if proc.poll() is not None:
                    raise RuntimeError(f"{name} exited with {proc.returncode}:\n{self.log_tail(name)}")
            if time.monotonic() > deadline:
                return rgb, counts
            last = rgb if drawn else None
            time.sleep(0.5)

    def __exit__(self, *_):
        for _, proc in reversed(self.procs):
            if proc.poll() is None:
                os.killpg(proc.pid, 15)
        for _, proc in reversed(self.procs):
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, 9)
                proc.wait()
        shutil.rmtree(self.fb_dir, ignore_errors=True)


def missing_programs():
    return [tool for tool in ("rviz", "Xvfb") if shutil.which(tool) is None]


# -- the test ------------------------------------------------------------------------------
def test_rviz_shows_the_robot_and_the_screenshot_is_saved(tmp_path):
    missing = missing_programs()
    if missing:
        message = f"{' and '.join(missing)} not installed: `scripts/setup --test` installs rviz and xvfb"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    with Session("ur5e", str(tmp_path)) as session:
        rgb, (grey, blue) = session.wait_for_robot()
        logs = "\n".join(f"--- {name}.log\n{session.log_tail(name)}" for name, _ in session.procs)
    seen = str(tmp_path / "screen.png")  # what the test saw, kept for a failure's diagnosis
    write_png_atomic(rgb, seen)
    logs = f"(the screen: {seen})\n" + logs
    assert rgb.shape == (HEIGHT, WIDTH, 3)
    assert not_blank(rgb), "the screen is blank: rviz drew nothing\n" + logs
    assert grey > MIN_GREY, f"only {grey} light-grey arm pixels in the middle of the 3D view\n" + logs
    assert blue > MIN_BLUE, f"only {blue} blue joint-cap pixels in the middle of the 3D view\n" + logs
    warned = warning_pixels(rgb)
    assert warned < MAX_WARNING_PIXELS, (
        f"a display shows a warning ({warned} orange pixels in the Displays panel)\n" + logs
    )
    write_png_atomic(rgb, SCREENSHOT)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--publish"]:
        publish(sys.argv[2])
    elif sys.argv[1:2] == ["--shot"]:
        with tempfile.TemporaryDirectory() as logs, Session(sys.argv[2], logs) as shot:
            picture, seen = shot.wait_for_robot(ur_colours=sys.argv[2].startswith("ur"))
        write_png_atomic(picture, sys.argv[3])
        print(f"wrote {sys.argv[3]} (grey, blue pixels in the middle: {seen})")
    else:
        sys.exit("usage: test_rviz_screenshot.py --publish ROBOT | --shot ROBOT OUT.png")
