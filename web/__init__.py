"""The browser dashboard (viser): `legged view` and `legged demo --view` serve it.

    geometry.py    MjModel geoms -> triangle meshes (numpy only)
    scene.py       meshes -> viser scene nodes; body poses, geom groups, translucent ceiling
    trajectory.py  recorded rollouts as arrays, saved to / loaded from self-contained .npz files
    rollout.py     recording MJX rollouts (policy or default controller) into trajectories
    kinematics.py  native MuJoCo body poses and contact points of recorded joint positions
    camera.py      egocentric depth image by MuJoCo ray casting
    overlays.py    path, waypoints, target, height scans, contacts, goal
    panels.py      reward and metric plots, training curves, checkpoint picker, image panel
    player.py      play / pause / step / speed / timeline
    source.py      `legged view` arguments -> what to show, with all checks before long work
    app.py         the server wiring them together
"""
