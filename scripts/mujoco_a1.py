"""quadcl's A1 in MuJoCo, for the comparisons in scripts/ (issue 15's PPO stack, issue 33's physics).

scenes/a1.urdf with a floating base at 0.42 m and a floor (friction 1.0), and a
position actuator per hinge: kp 20, kd 0.5, torque limited to 33.5 N m. The
default pose and the PD gains are quadcl's.
"""

import pathlib

import mujoco
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
DEFAULT_Q = np.array([0.1, 0.8, -1.5, -0.1, 0.8, -1.5, 0.1, 1.0, -1.5, -0.1, 1.0, -1.5])  # FL FR RL RR
KP, KD, TORQUE = 20.0, 0.5, 33.5


def a1_model(dt, integrator=None):
    """The compiled model at physics step `dt`; `integrator` a mujoco.mjtIntegrator (MuJoCo's default, Euler, if None)."""
    spec = mujoco.MjSpec.from_file(str(ROOT / "scenes" / "a1.urdf"))
    spec.option.timestep = dt
    if integrator is not None:
        spec.option.integrator = integrator
    trunk = spec.body("trunk")
    trunk.add_freejoint()
    trunk.pos = [0, 0, 0.42]
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1], friction=[1.0, 0.005, 0.0001])
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    assert len(joints) == 12, joints
    for name in joints:
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=KP, kv=KD)
        act.forcerange = [-TORQUE, TORQUE]
        act.forcelimited = True
    return spec.compile()
