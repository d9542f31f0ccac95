"""Robotis OP3: the humanoid of the soccer tasks."""

from legged.robots.spec import ASSETS_DIR, RobotSpec

OP3_CTRL_DT = 0.025
"""Policy period of the OP3 tasks, seconds (40 Hz; 5 physics steps of the MJCF's 0.005 s)."""

_ARM = ("sho_pitch", "sho_roll", "el")
_LEG = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ank_pitch", "ank_roll")

OP3 = RobotSpec(
    name="op3",
    mjcf_path=ASSETS_DIR / "robots" / "op3.xml",
    root_body="body_link",
    # Menagerie's order (= the MJCF's actuator order): head, left arm, right arm, left leg, right leg.
    joint_names=("head_pan", "head_tilt")
    + tuple(f"{side}_{j}" for side in "lr" for j in _ARM)
    + tuple(f"{side}_{j}" for side in "lr" for j in _LEG),
    # MuJoCo Playground's OP3 "stand_bent_knees" pose (multiples of pi / 100: arms 0.17, 0.28, 0.2 pi;
    # legs 0.19, 0.36, 0.17 pi): arms down, knees bent, feet flat, torso upright, centre of mass over
    # the feet. Signs follow the joint axes, which mirror between the sides.
    default_pose=(
        0.0, 0.0,
        -0.5341, 0.8796, -0.6283,
        0.5341, -0.8796, 0.6283,
        0.0, 0.0, -0.5969, 1.1310, 0.5341, 0.0,
        0.0, 0.0, 0.5969, -1.1310, -0.5341, 0.0,
    ),
    # Playground's OP3 gains (its Kd is joint damping there, the servo's D term here; see op3.xml).
    kp=21.1,
    kd=1.084,
    action_scale=0.3,
    feet_geoms=("l_foot", "r_foot"),
    # Sole centres, 30.5 mm below the ankle roll axis (ROBOTIS' leg-end frame of its kinematics).
    feet_sites=("l_foot", "r_foot"),
    body_geoms=("torso", "head"),
    thigh_geoms=("l_thigh", "r_thigh"),
    calf_geoms=("l_shin", "r_shin"),
    imu_site="imu",
    # Torso box; note that it is centred 0.068 m above the root (hip-level) origin, not on it.
    body_box_half_extents=(0.058, 0.065, 0.073),
    # Root origin above the soles at the default pose (kinematic; it settles 3 mm lower under load).
    standing_height=0.245,
    # Feet flat, torso upright: knee 1.75 rad (0.20 m) to 0.55 rad (0.27 m; straighter legs keep no reach).
    body_height_range=(0.20, 0.27),
    arm_geoms=("l_upper_arm", "l_forearm", "r_upper_arm", "r_forearm"),
    head_camera="head_cam",
    # Dynamixel XM430-W350 at 12 V: 46 rpm without load (its stall torque is the MJCF's 4.1 N m force limit).
    motor_speeds=(46 * 2 * 3.141592653589793 / 60,) * 20,
    differences=(
        ("joint_damping", "none: Menagerie's 1.084 N m s/rad of joint damping is the D term of the servo here (Kd "
                          "1.084), so the two agree until the torque saturates and Kd randomisation acts on all of it"),
        ("foot_contact", "MuJoCo's default solref 0.02 s: Menagerie's stiffer 0.004 s (0.012 s mixed with a plain floor) "
                         "needs its 2 ms step"),
        ("body_contact", "MuJoCo's default solref 0.02 s, as the feet"),
        ("actuator_gains", "Kd 1.084 in the servo (see joint_damping; Menagerie: Kp 21.1 alone)"),
        ("force_limits", "4.1 N m, the Dynamixel XM430-W350's stall torque at 12 V from its datasheet (Menagerie: "
                         "5 N m)"),
        ("solver", "4 iterations, 8 line-search steps, Euler damping off: fast in MJX (Menagerie: 100 and 50)"),
        ("timestep", "5 ms, 5 steps per 40 Hz control step (Menagerie: MuJoCo's default 2 ms)"),
    ),
)
