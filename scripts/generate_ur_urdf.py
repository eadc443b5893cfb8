#!/usr/bin/env python3
"""Write the simplified robot models shipped in src/motion_common/urdf: UR5e, UR10e and
the Staubli TX90 of the paper.

The kinematics are the manufacturers' standard DH parameters (Universal Robots publish
theirs; the TX90's are its data-sheet link lengths), so forward kinematics match the
controllers' up to calibration (base frame = the DH base frame, tool0 = the flange).
Collision geometry is one cylinder per link and masses are the published (UR) or estimated
(TX90) link masses, which is all the pybullet simulation and the pinocchio kinematics need.

The <visual> elements are separate, for RViz: Debian ships no ur_description or Staubli
meshes, so each arm is drawn from primitives sized like the real one (joint housings as
drums around their axes, the tubes of the upper arm and forearm at their real lateral
offsets, the tool flange) in the makers' colours. They change nothing the simulation or the
kinematics read. Run with any python3:
    python3 scripts/generate_ur_urdf.py
"""

import math
import os

# name: (d, a, alpha, link masses, joint efforts [Nm], joint velocities [rad/s], radius)
ROBOTS = {
    "ur5e": dict(
        d=[0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996],
        a=[0.0, -0.425, -0.3922, 0.0, 0.0, 0.0],
        alpha=[math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0],
        mass=[3.761, 8.058, 2.846, 1.37, 1.3, 0.365],
        effort=[150.0, 150.0, 150.0, 28.0, 28.0, 28.0],
        velocity=[3.1416] * 6,
        radius=0.045,
        # Look of the real arm (metres): foot and joint housing radii (the base, shoulder
        # and elbow drives are larger than the three wrist drives), tube radii, and the
        # lateral offsets of the upper-arm and forearm tubes along the parallel shoulder,
        # elbow and wrist-1 axes (the DH model folds them into d4: 0.138 - 0.131 + 0.127).
        look=dict(
            style="ur",
            foot=(0.0745, 0.025),
            housing=[0.06, 0.06, 0.05, 0.045, 0.045, 0.045],
            upper_tube=0.043,
            fore_tube=0.037,
            shoulder_offset=0.138,
            elbow_offset=0.131,
            flange=(0.0315, 0.008),
        ),
    ),
    "ur10e": dict(
        d=[0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655],
        a=[0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0],
        alpha=[math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0],
        mass=[7.369, 13.051, 3.989, 2.1, 1.98, 0.615],
        effort=[330.0, 330.0, 150.0, 56.0, 56.0, 56.0],
        velocity=[2.0944, 2.0944, 3.1416, 3.1416, 3.1416, 3.1416],
        radius=0.06,
        # As the UR5e's, one drive size up (d4: 0.176 - 0.137 + 0.135).
        look=dict(
            style="ur",
            foot=(0.095, 0.03),
            housing=[0.075, 0.075, 0.06, 0.0475, 0.0475, 0.0475],
            upper_tube=0.054,
            fore_tube=0.045,
            shoulder_offset=0.176,
            elbow_offset=0.137,
            flange=(0.0315, 0.008),
        ),
    ),
    # Staubli TX90: 478 mm shoulder height, 50 mm shoulder offset, 425 mm upper arm, 50 mm
    # elbow offset, 425 mm forearm, 100 mm to the flange (1000 mm reach). Zero pose upright,
    # hence the theta offsets on joints 2 and 3.
    "tx90": dict(
        d=[0.478, 0.0, 0.05, 0.425, 0.0, 0.1],
        a=[0.05, 0.425, 0.0, 0.0, 0.0, 0.0],
        alpha=[-math.pi / 2, 0.0, math.pi / 2, -math.pi / 2, math.pi / 2, 0.0],
        offset=[0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0],
        mass=[30.0, 25.0, 12.0, 8.0, 3.0, 1.0],
        effort=[320.0, 320.0, 160.0, 50.0, 50.0, 30.0],
        velocity=[math.radians(v) for v in (400, 400, 430, 540, 475, 760)],
        lower=[math.radians(v) for v in (-180, -130, -145, -270, -115, -270)],
        upper=[math.radians(v) for v in (180, 147.5, 145, 270, 140, 270)],
        radius=0.07,
        # Look: a round foot and column, the shoulder drum, the upper arm as a flat link on
        # the outer side of the shoulder and elbow drums, a round forearm along joint 4,
        # the wrist drum and the flange.
        look=dict(style="staubli", foot=(0.125, 0.07), column=0.11, flange=(0.0315, 0.01)),
        joints=["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"],
        links=["link_1", "link_2", "link_3", "link_4", "link_5", "link_6"],
    ),
}
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
LINKS = ["shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link"]
# The elbow cannot pass through itself: UR limits it to +-pi, the other joints to +-2pi.
LIMITS = [2 * math.pi, 2 * math.pi, math.pi, 2 * math.pi, 2 * math.pi, 2 * math.pi]


# Massless frames get a token inertia so physics engines need not invent one.
_TINY_INERTIAL = (
    '    <inertial><mass value="0.001"/>'
    '<inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial>\n'
)


def _segment_geometry(vector, radius):
    """Return (origin xyz, rpy, length) of a cylinder from the link origin to ``vector``."""
    x, y, z = vector
    length = math.sqrt(x * x + y * y + z * z)
    if length < 2 * radius:  # a joint with no offset: a short drum around its axis
        return (0.0, 0.0, z / 2), (0.0, 0.0, 0.0), 2 * radius
    # Rz(yaw) Ry(pitch) turns the cylinder's z axis onto the segment.
    pitch, yaw = math.atan2(math.hypot(x, y), z), math.atan2(y, x)
    return (x / 2, y / 2, z / 2), (0.0, pitch, yaw), length


def _fmt(values):
    return " ".join(f"{v:.12g}" for v in values)


# Colours of the visuals: Universal Robots' light grey housings, aluminium tubes and blue
# joint caps; Staubli's yellow arm with white covers; a dark tool flange on both.
MATERIALS = {
    "ur_grey": "0.86 0.87 0.88 1",
    "ur_tube": "0.68 0.70 0.72 1",
    "ur_blue": "0.27 0.55 0.80 1",
    "staubli_yellow": "0.96 0.74 0.09 1",
    "staubli_white": "0.94 0.94 0.91 1",
    "flange_dark": "0.22 0.23 0.25 1",
}
# A cylinder's axis is its z; these turn it onto the link frame's x or y axis.
_AXIS_RPY = {"x": (0.0, math.pi / 2, 0.0), "y": (math.pi / 2, 0.0, 0.0), "z": (0.0, 0.0, 0.0)}
CAP = 0.01  # thickness of a joint cap, drawn 1 mm proud of its housing


def _visual(geometry, xyz, rpy, material):
    return (
        f'    <visual>\n      <origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>\n'
        f"      <geometry>{geometry}</geometry>\n"
        f'      <material name="{material}"><color rgba="{MATERIALS[material]}"/></material>\n'
        "    </visual>\n"
    )


def _cylinder(radius, axis, lo, hi, material, at=(0.0, 0.0, 0.0)):
    """A cylinder of ``radius`` along the link frame's ``axis`` ("x", "y" or "z") from
    coordinate ``lo`` to ``hi`` on it, its axis through the point ``at`` (whose coordinate
    on ``axis`` is ignored)."""
    index = "xyz".index(axis)
    centre = list(at)
    centre[index] = (lo + hi) / 2
    geometry = f'<cylinder radius="{radius:.6g}" length="{abs(hi - lo):.6g}"/>'
    return _visual(geometry, centre, _AXIS_RPY[axis], material)


def _housing(radius, lo, hi, material, caps, cap_material, at=(0.0, 0.0, 0.0), axis="z"):
    """A joint drum from ``lo`` to ``hi`` along ``axis`` with a cap on each end in ``caps``
    ("lo", "hi")."""
    out = [_cylinder(radius, axis, lo, hi, material, at)]
    for end in caps:
        edge = lo if end == "lo" else hi
        inward = CAP if end == "lo" else -CAP
        out.append(_cylinder(radius + 0.001, axis, edge - 0.1 * inward, edge + 0.9 * inward, cap_material, at))
    return out


def _box(size, xyz, material):
    return _visual(f'<box size="{_fmt(size)}"/>', xyz, (0.0, 0.0, 0.0), material)


def ur_visuals(p):
    """Link name -> <visual> elements of a Universal Robots arm. Each joint's drum is drawn
    in the link the joint turns, around that link's z axis (a drum turning about its own
    axis looks the same from either side of the joint)."""
    look, d, a = p["look"], p["d"], p["a"]
    r = look["housing"]
    tube_u, tube_f = look["upper_tube"], look["fore_tube"]
    s2 = look["shoulder_offset"]  # upper-arm tube, along the shoulder-lift axis
    s3 = s2 - look["elbow_offset"]  # forearm tube, along the (parallel) elbow axis
    foot_r, foot_h = look["foot"]
    flange_r, flange_t = look["flange"]
    grey, tube, blue = "ur_grey", "ur_tube", "ur_blue"
    return {
        "base_link": [_cylinder(foot_r, "z", 0.0, foot_h, grey)],
        # Base drive: up from the foot into the shoulder drum.
        "shoulder_link": [_cylinder(r[0], "z", foot_h, d[0], grey)],
        # Shoulder drum: from behind the base axis out to the far side of the upper-arm tube.
        "upper_arm_link": _housing(r[1], -r[1], s2 + tube_u, grey, ("lo", "hi"), blue)
        + [_cylinder(tube_u, "x", a[1], 0.0, tube, at=(0.0, 0.0, s2))],
        # Elbow drum spans both tubes.
        "forearm_link": _housing(r[2], s3 - r[2], s2 + tube_u, grey, ("lo", "hi"), blue)
        + [_cylinder(tube_f, "x", a[2], 0.0, tube, at=(0.0, 0.0, s3))],
        # Wrist 1 drum: from the forearm tube to the wrist-2 axis (d4 along it).
        "wrist_1_link": _housing(r[3], s3 - r[3], d[3], grey, ("lo",), blue),
        "wrist_2_link": _housing(r[4], -r[4], d[4], grey, ("lo",), blue),
        "wrist_3_link": _housing(r[5], -r[5], d[5] - flange_t, grey, ("lo",), blue)
        + [_cylinder(flange_r, "z", d[5] - flange_t, d[5], "flange_dark")],
    }


def staubli_visuals(p):
    """Link name -> <visual> elements of the Staubli TX90 (frames as in ``generate``)."""
    look, d, a = p["look"], p["d"], p["a"]
    foot_r, foot_h = look["foot"]
    flange_r, flange_t = look["flange"]
    yellow, white = "staubli_yellow", "staubli_white"
    shoulder_r, elbow_r, fore_r, wrist_r = 0.115, 0.085, 0.06, 0.06
    arm_lo, arm_hi = -0.19, -0.10  # the upper arm's flat link, outside both drums
    return {
        "base_link": [_cylinder(foot_r, "z", 0.0, foot_h, white)],
        "link_1": [_cylinder(look["column"], "z", foot_h, d[0], yellow)],
        # Shoulder drum around joint 2 (this link's z), then the flat upper arm along -y to
        # the elbow, rounded at both ends.
        "link_2": _housing(shoulder_r, arm_hi, 0.14, yellow, ("hi",), white)
        + _housing(shoulder_r - 0.005, arm_lo, arm_hi, yellow, ("lo",), white)
        + _housing(elbow_r, arm_lo, arm_hi, yellow, ("lo",), white, at=(0.0, -a[1], 0.0))
        + [_box((2 * elbow_r, a[1], arm_hi - arm_lo), (0.0, -a[1] / 2, (arm_lo + arm_hi) / 2), yellow)],
        # Elbow drum; the forearm leaves it along joint 4 at d3.
        "link_3": _housing(elbow_r, arm_hi, d[2] + 0.08, yellow, ("hi",), white),
        # Joint 4 drive behind the elbow, then the forearm to the wrist centre (d4).
        "link_4": _housing(0.075, -0.10, 0.14, yellow, ("lo",), white) + [_cylinder(fore_r, "z", 0.14, d[3], yellow)],
        "link_5": _housing(wrist_r, -0.07, 0.07, yellow, ("lo", "hi"), white),
        "link_6": [
            _cylinder(0.045, "z", wrist_r - 0.02, d[5] - flange_t, white),
            _cylinder(flange_r, "z", d[5] - flange_t, d[5], "flange_dark"),
        ],
    }


def _link(name, mass, vector, radius, visuals):
    xyz, rpy, length = _segment_geometry(vector, radius)
    # Solid cylinder inertia about its centre, expressed along its own axis; good enough
    # for a position-controlled simulation.
    i_axis = 0.5 * mass * radius**2
    i_perp = mass * (3 * radius**2 + length**2) / 12
    # Inertia as if the cylinder were along z: a rough but positive-definite estimate.
    ixx, iyy, izz = i_perp, i_perp, i_axis
    # Collision cylinders stop 1 cm short of each end, so the shoulder does not rub on a
    # floor the base stands on (a phantom load on the joints in simulation).
    collision_geom = f'<geometry><cylinder radius="{radius:.4g}" length="{max(length - 0.02, 0.01):.6g}"/></geometry>'
    return f"""  <link name="{name}">
    <inertial>
      <origin xyz="{_fmt(xyz)}" rpy="0 0 0"/>
      <mass value="{mass}"/>
      <inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>
    </inertial>
{"".join(visuals)}    <collision>
      <origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>
      {collision_geom}
    </collision>
  </link>
"""


def generate(name, p):
    """Return the URDF text of robot ``name`` from its parameter dict ``p``."""
    visuals = (ur_visuals if p["look"]["style"] == "ur" else staubli_visuals)(p)
    out = [
        f'<?xml version="1.0"?>\n<!-- Generated by scripts/generate_ur_urdf.py: '
        f"{name} from Universal Robots' published DH parameters. -->\n"
        f'<robot name="{name}">\n',
        # The root link carries no inertia: KDL (robot_state_publisher) cannot use one there
        # and warns on every start; the base is fixed, so no physics engine needs it.
        '  <link name="world"/>\n'
        '  <joint name="world_joint" type="fixed">\n'
        '    <parent link="world"/><child link="base_link"/>\n'
        '    <origin xyz="0 0 0" rpy="0 0 0"/>\n  </joint>\n',
        _link("base_link", 4.0, (0.0, 0.0, 0.05), p["radius"] * 1.3, visuals["base_link"]),
    ]
    parent, origin_xyz, origin_rpy = "base_link", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    offsets = p.get("offset", [0.0] * 6)
    lower = p.get("lower", [-v for v in LIMITS])
    upper = p.get("upper", LIMITS)
    for i, (joint, link) in enumerate(zip(p.get("joints", JOINTS), p.get("links", LINKS))):
        out.append(f"""  <joint name="{joint}" type="revolute">
    <parent link="{parent}"/><child link="{link}"/>
    <origin xyz="{_fmt(origin_xyz)}" rpy="{_fmt(origin_rpy)}"/>
    <axis xyz="0 0 1"/>
    <limit lower="{lower[i]:.6f}" upper="{upper[i]:.6f}" effort="{p["effort"][i]}" velocity="{p["velocity"][i]:.6f}"/>
    <dynamics damping="0.5" friction="0.0"/>
  </joint>
""")
        # Standard DH: after joint i turns, the fixed part of the step is
        # Rz(offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i), which becomes the next joint's origin
        # (URDF rpy (alpha, 0, offset) is exactly Rz(offset) Rx(alpha)).
        off = offsets[i]
        vector = (p["a"][i] * math.cos(off), p["a"][i] * math.sin(off), p["d"][i])
        out.append(_link(link, p["mass"][i], vector, p["radius"] * (1.0 if i < 3 else 0.8), visuals[link]))
        parent = link
        origin_xyz = vector
        origin_rpy = (p["alpha"][i], 0.0, off)
    out.append(f"""  <link name="tool0">\n{_TINY_INERTIAL}  </link>
  <joint name="{parent}-tool0_fixed_joint" type="fixed">
    <parent link="{parent}"/><child link="tool0"/>
    <origin xyz="{_fmt(origin_xyz)}" rpy="{_fmt(origin_rpy)}"/>
  </joint>
</robot>
""")
    return "".join(out)


if __name__ == "__main__":
    target = os.path.join(os.path.dirname(__file__), "..", "src", "motion_common", "urdf")
    for robot_name, params in ROBOTS.items():
        path = os.path.join(target, f"{robot_name}.urdf")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(generate(robot_name, params))
        print("wrote", os.path.normpath(path))
