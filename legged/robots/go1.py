"""Unitree Go1: the quadruped of the confined-space tasks."""

from legged.robots.spec import ASSETS_DIR, RobotSpec

_LEGS = ("FR", "FL", "RR", "RL")

GO1 = RobotSpec(
    name="go1",
    mjcf_path=ASSETS_DIR / "robots" / "go1.xml",
    root_body="trunk",
    joint_names=tuple(f"{leg}_{part}_joint" for leg in _LEGS for part in ("hip", "thigh", "calf")),
    # Standing pose of the paper's code base (walk-these-ways lineage): with Kp 20 the deeper
    # 0.9 / -1.8 crouch of menagerie's keyframe collapses the rear legs.
    default_pose=(-0.1, 0.8, -1.5, 0.1, 0.8, -1.5, -0.1, 1.0, -1.5, 0.1, 1.0, -1.5),
    kp=20.0,
    kd=0.5,
    action_scale=0.25,
    feet_geoms=_LEGS,
    feet_sites=_LEGS,
    body_geoms=("trunk_front", "trunk_mid", "trunk_rear"),
    thigh_geoms=tuple(f"{leg}_thigh" for leg in _LEGS),
    calf_geoms=tuple(f"{leg}_calf" for leg in _LEGS),
    imu_site="imu",
    body_box_half_extents=(0.188, 0.047, 0.057),
    standing_height=0.27,
    # The paper's local planner picks body heights in 0.23-0.31 m; a little crouch below that is held
    # easily with Kp 20, a stretch above 0.32 m leaves the feet too little reach over bumps.
    body_height_range=(0.22, 0.32),
    # Unitree's Go1 joint motor: 23.7 N m and 30.1 rad/s at the hip and thigh; through the knee's extra 1.5:1
    # linkage 35.55 N m and 20.06 rad/s (the force limits are the MJCF's forcerange).
    motor_speeds=(30.1, 30.1, 20.06) * 4,
    differences=(
        ("joint_damping", "0.5 N m s/rad on every joint, MuJoCo Playground's MJX Go1 value, which the shipped policies "
                          "trained with (Menagerie: 1 on abduction, 2 on hip and knee)"),
        ("foot_contact", "condim 3 with MuJoCo's default solver parameters and no margin, the plain contact MJX is fast "
                         "with (Menagerie: condim 6 with torsional and rolling friction, solimp 0.015-1 over 23 mm, "
                         "1 mm margin)"),
        ("body_contact", "no margin (Menagerie: 1 mm)"),
        ("actuator_gains", "the policies' PD servo, Kp 20 and Kd 0.5 (Menagerie: a position actuator with Kp 100 and "
                           "no D term)"),
        ("solver", "pyramidal cone, 4 iterations, 8 line-search steps, Euler damping off: fast in MJX (Menagerie: "
                   "elliptic cone with impratio 100, 100 and 50 iterations)"),
        ("timestep", "5 ms, 4 steps per 50 Hz control step (Menagerie: MuJoCo's default 2 ms)"),
    ),
)
