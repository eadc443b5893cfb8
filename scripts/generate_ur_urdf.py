#!/usr/bin/env python3
"""Write the simplified robot models shipped in src/motion_common/urdf: UR5e, UR10e and
the Staubli TX90 of the paper.

The kinematics are the manufacturers' standard DH parameters (Universal Robots publish
theirs; the TX90's are its data-sheet link lengths), so forward kinematics match the
controllers' up to calibration (base frame = the DH base frame, tool0 = the flange).
Geometry is cylinders and masses are the published (UR) or estimated (TX90) link masses,
which is all the pybullet simulation and the pinocchio kinematics need. Run with any
python3:
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
    ),
    "ur10e": dict(
        d=[0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655],
        a=[0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0],
        alpha=[math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0],
        mass=[7.369, 13.051, 3.989, 2.1, 1.98, 0.615],
        effort=[330.0, 330.0, 150.0, 56.0, 56.0, 56.0],
        velocity=[2.0944, 2.0944, 3.1416, 3.1416, 3.1416, 3.1416],
        radius=0.06,
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


def _link(name, mass, vector, radius):
    xyz, rpy, length = _segment_geometry(vector, radius)
    # Solid cylinder inertia about its centre, expressed along its own axis; good enough
    # for a position-controlled simulation.
    i_axis = 0.5 * mass * radius**2
    i_perp = mass * (3 * radius**2 + length**2) / 12
    # Inertia as if the cylinder were along z: a rough but positive-definite estimate.
    ixx, iyy, izz = i_perp, i_perp, i_axis
    geom = f'<geometry><cylinder radius="{radius:.4g}" length="{length:.6g}"/></geometry>'
    # Collision cylinders stop 1 cm short of each end, so the shoulder does not rub on a
    # floor the base stands on (a phantom load on the joints in simulation).
    collision_geom = f'<geometry><cylinder radius="{radius:.4g}" length="{max(length - 0.02, 0.01):.6g}"/></geometry>'
    return f"""  <link name="{name}">
    <inertial>
      <origin xyz="{_fmt(xyz)}" rpy="0 0 0"/>
      <mass value="{mass}"/>
      <inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>
    </inertial>
    <visual>
      <origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>
      {geom}
      <material name="ur_grey"><color rgba="0.7 0.7 0.72 1"/></material>
    </visual>
    <collision>
      <origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>
      {collision_geom}
    </collision>
  </link>
"""


def generate(name, p):
    """Return the URDF text of robot ``name`` from its parameter dict ``p``."""
    out = [
        f'<?xml version="1.0"?>\n<!-- Generated by scripts/generate_ur_urdf.py: '
        f"{name} from Universal Robots' published DH parameters. -->\n"
        f'<robot name="{name}">\n',
        '  <link name="world">\n' + _TINY_INERTIAL + "  </link>\n"
        '  <joint name="world_joint" type="fixed">\n'
        '    <parent link="world"/><child link="base_link"/>\n'
        '    <origin xyz="0 0 0" rpy="0 0 0"/>\n  </joint>\n',
        _link("base_link", 4.0, (0.0, 0.0, 0.05), p["radius"] * 1.3),
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
        out.append(_link(link, p["mass"][i], vector, p["radius"] * (1.0 if i < 3 else 0.8)))
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
