#!/usr/bin/env python3
"""Writes scenes/anymal_c.urdf and scenes/aliengo.urdf from the figures below.

Both are written for quadcl from published figures (as scenes/a1.urdf was),
with primitive collision shapes and the inertias of those primitives (solid
box / cylinder / sphere with the link's mass). They are shaped like the
makers' own descriptions where it matters to the loader: ANYmal's joint names
(LF_HAA ...), a massless root `base` with the body on a fixed child link, fixed
foot links, knees bending towards the body (front knees back, hind knees
forward); the Unitree layout with a massless `base`, a fixed `trunk`, fixed
`*_foot` links, and visuals pointing at the maker's meshes (not shipped:
visuals are not used).

    python3 scripts/write_robot_urdfs.py   # from the repository root
"""

import math


def box(m, x, y, z):
    return (m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12)


def cyl_z(m, r, h):
    side = m * (3 * r * r + h * h) / 12
    return (side, side, m * r * r / 2)


def sphere(m, r):
    v = 2 * m * r * r / 5
    return (v, v, v)


def inertial(m, i, xyz="0 0 0"):
    return (
        f'    <inertial>\n      <origin xyz="{xyz}" rpy="0 0 0"/>\n      <mass value="{m}"/>\n'
        f'      <inertia ixx="{i[0]:.6g}" ixy="0" ixz="0" iyy="{i[1]:.6g}" iyz="0" izz="{i[2]:.6g}"/>\n'
        "    </inertial>\n"
    )


def collision(geom, xyz="0 0 0"):
    return f'    <collision>\n      <origin xyz="{xyz}" rpy="0 0 0"/>\n      <geometry>{geom}</geometry>\n    </collision>\n'


def link(name, body=""):
    return f'  <link name="{name}">\n{body}  </link>\n'


def joint(name, kind, parent, child, xyz, axis=None, limit=None):
    s = f'  <joint name="{name}" type="{kind}">\n    <origin xyz="{xyz}" rpy="0 0 0"/>\n'
    s += f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
    if axis:
        s += f'    <axis xyz="{axis}"/>\n'
    if limit:
        s += f"    <limit {limit}/>\n"
    return s + "  </joint>\n"


def anymal_c():
    # ANYmal C (ANYbotics datasheet): about 50 kg, 80 N m peak joint torque
    # (ANYdrive), standing body height about 0.55 m. Layout after the public
    # anymal_c_simple_description: HAA at (+-0.30, +-0.104), HFE 0.06 m along x
    # and 0.09 m out, thigh 0.285 m, shank to foot centre 0.31 m, foot r 0.03.
    s = '<?xml version="1.0"?>\n<!-- ANYmal C-class quadruped written for quadcl by scripts/write_robot_urdfs.py from\n'
    s += "     published figures: 49.6 kg, 80 N m joints, thigh 0.285 m, shank 0.31 m, foot r 0.03 m. -->\n"
    s += '<robot name="anymal_c">\n'
    s += link("base")
    s += joint("base_to_base_inertia", "fixed", "base", "base_inertia", "0 0 0")
    s += link("base_inertia", inertial(32.0, box(32.0, 0.53, 0.27, 0.2)) + collision('<box size="0.53 0.27 0.2"/>'))
    for leg, sx, sy in [("LF", 1, 1), ("RF", 1, -1), ("LH", -1, 1), ("RH", -1, -1)]:
        lim = 'effort="80" velocity="7.5"'
        s += joint(f"{leg}_HAA", "revolute", "base", f"{leg}_HIP", f"{0.30 * sx} {0.104 * sy} 0", "1 0 0",
                   f'lower="-0.72" upper="0.72" {lim}')
        s += link(f"{leg}_HIP", inertial(2.0, cyl_z(2.0, 0.06, 0.1)))
        s += joint(f"{leg}_HFE", "revolute", f"{leg}_HIP", f"{leg}_THIGH", f"{0.06 * sx} {0.09 * sy} 0", "0 1 0",
                   f'lower="-2.5" upper="2.5" {lim}')
        s += link(f"{leg}_THIGH", inertial(1.6, cyl_z(1.6, 0.04, 0.285), "0 0 -0.14")
                  + collision('<capsule radius="0.04" length="0.2"/>', "0 0 -0.14"))
        s += joint(f"{leg}_KFE", "revolute", f"{leg}_THIGH", f"{leg}_SHANK", f"0 {0.02 * sy} -0.285", "0 1 0",
                   f'lower="-2.6" upper="2.6" {lim}')
        s += link(f"{leg}_SHANK", inertial(0.7, cyl_z(0.7, 0.025, 0.28), "0 0 -0.14")
                  + collision('<capsule radius="0.025" length="0.2"/>', "0 0 -0.14"))
        s += joint(f"{leg}_SHANK_TO_FOOT", "fixed", f"{leg}_SHANK", f"{leg}_FOOT", "0 0 -0.31")
        s += link(f"{leg}_FOOT", inertial(0.1, sphere(0.1, 0.03)) + collision('<sphere radius="0.03"/>'))
    return s + "</robot>\n"


def aliengo():
    # Unitree Aliengo (Unitree datasheet and its public aliengo_description):
    # about 21 kg; trunk 9.04 kg, 0.647 x 0.15 x 0.112 m; per leg hip 1.993 kg,
    # thigh 0.639 kg (0.25 m), calf 0.207 kg (0.25 m), foot 0.06 kg, r 0.0265;
    # hips at (+-0.2399, +-0.051), thigh joint 0.083 m out; 44 / 44 / 55 N m.
    s = '<?xml version="1.0"?>\n<!-- Aliengo-class quadruped written for quadcl by scripts/write_robot_urdfs.py from\n'
    s += "     published figures: 20.6 kg, trunk 9.04 kg, thigh and calf 0.25 m, foot r 0.0265 m. -->\n"
    s += '<robot name="aliengo">\n'
    s += link("base")
    s += joint("floating_base", "fixed", "base", "trunk", "0 0 0")
    visual = ('    <visual>\n      <geometry><mesh filename="package://aliengo_description/meshes/trunk.dae"/></geometry>\n'
              '      <material name="orange"/>\n    </visual>\n')
    s += link("trunk", visual + inertial(9.04, box(9.04, 0.647, 0.15, 0.112))
              + collision('<box size="0.647 0.15 0.112"/>'))
    for leg, sx, sy in [("FR", 1, -1), ("FL", 1, 1), ("RR", -1, -1), ("RL", -1, 1)]:
        s += joint(f"{leg}_hip_joint", "revolute", "trunk", f"{leg}_hip", f"{0.2399 * sx} {0.051 * sy} 0", "1 0 0",
                   'lower="-1.22" upper="1.22" effort="44" velocity="20"')
        s += link(f"{leg}_hip", inertial(1.993, cyl_z(1.993, 0.046, 0.08)))
        s += joint(f"{leg}_thigh_joint", "revolute", f"{leg}_hip", f"{leg}_thigh", f"0 {0.083 * sy} 0", "0 1 0",
                   'lower="-3.14" upper="3.14" effort="44" velocity="20"')
        s += link(f"{leg}_thigh", inertial(0.639, box(0.639, 0.03, 0.04, 0.25), "0 0 -0.125")
                  + collision('<box size="0.03 0.04 0.2"/>', "0 0 -0.125"))
        s += joint(f"{leg}_calf_joint", "revolute", f"{leg}_thigh", f"{leg}_calf", "0 0 -0.25", "0 1 0",
                   'lower="-2.78" upper="-0.65" effort="55" velocity="16"')
        s += link(f"{leg}_calf", inertial(0.207, cyl_z(0.207, 0.013, 0.25), "0 0 -0.125")
                  + collision('<cylinder radius="0.013" length="0.2"/>', "0 0 -0.125"))
        s += joint(f"{leg}_foot_fixed", "fixed", f"{leg}_calf", f"{leg}_foot", "0 0 -0.25")
        s += link(f"{leg}_foot", inertial(0.06, sphere(0.06, 0.0265)) + collision('<sphere radius="0.0265"/>'))
    return s + "</robot>\n"


if __name__ == "__main__":
    for name, text in [("anymal_c", anymal_c()), ("aliengo", aliengo())]:
        with open(f"scenes/{name}.urdf", "w") as f:
            f.write(text)
        print(f"scenes/{name}.urdf")
    assert math.isclose(32.0 + 4 * (2.0 + 1.6 + 0.7 + 0.1), 49.6)
