"""placo's walk and kick for the OP3, and the scripted player that plays them back.

Offline, with placo (a whole-body planner on pinocchio): the URDF it plans for (`urdf`), the walk (`walk`), the
gait table's builder (`gait_build`) and the kick's (`kick_build`, with the left-right mirror of `mirror`). At run
time, without placo: the tables as data and their pure lookups (`gait_table`, `kick_table`, read and written by
`npz_tables`), the scripted player in JAX (`player`) and open-loop checks of the tables in native MuJoCo
(`open_loop`). The committed tables are assets/placo/op3_gait.npz and op3_kick.npz.

The package is named after the library; its modules import the library by its absolute name (`import placo`), so
the builders run as modules: `python -m legged.soccer.placo.gait_build`, `python -m legged.soccer.placo.kick_build`.
"""
