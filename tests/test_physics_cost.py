"""`legged bench physics`'s pieces: each variant changes what it names on a copy of the model, and a variant's cost
is measured from the same states under the same controls. (Its figures are measured, not asserted:
assets/benchmarks/.)"""

import dataclasses

import mujoco
import numpy as np
import pytest

from legged.bench import physics_profile
from legged.physics_cost import AS_TRAINED, VARIANTS, _time_variant, variant_model, variants_named

BOX = """<mujoco><option cone="pyramidal"/><worldbody><geom type="plane" size="1 1 0.1"/>
<body pos="0 0 0.099"><freejoint/><geom type="box" size="0.1 0.1 0.1" condim="6"/>
<body pos="0 0 0.2"><joint name="hinge" type="hinge" damping="0.5" frictionloss="0.2"/><geom size="0.05"/></body>
</body></worldbody><actuator><position joint="hinge" kp="1"/></actuator></mujoco>"""
"""A box resting on a plane (4 corner contacts of 6 dimensions) carrying a ball on a hinge with damping and dry
friction."""


def named(name):
    return next(v for v in VARIANTS if v.name == name)


@pytest.fixture
def model():
    return mujoco.MjModel.from_xml_string(BOX)


def test_each_variant_changes_a_copy_as_it_says(model):
    edited = {v.name: variant_model(model, v) for v in VARIANTS}
    assert model.opt.solver == mujoco.mjtSolver.mjSOL_NEWTON and model.geom_condim.max() == 6  # untouched
    assert model.dof_frictionloss.max() == pytest.approx(0.2)
    assert edited["cg"].opt.solver == mujoco.mjtSolver.mjSOL_CG
    assert edited["pgs"].opt.solver == mujoco.mjtSolver.mjSOL_PGS
    assert edited["iterations-1"].opt.iterations == 1 and edited["iterations-1"].opt.ls_iterations == 1
    assert edited["other-cone"].opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert variant_model(edited["other-cone"], named("other-cone")).opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
    assert edited["condim-3"].geom_condim.max() == 3
    assert np.all(edited["no-frictionloss"].dof_frictionloss == 0)
    assert edited["no-eulerdamp"].opt.disableflags & mujoco.mjtDisableBit.mjDSBL_EULERDAMP
    assert edited["sparse-jacobian"].opt.jacobian == mujoco.mjtJacobian.mjJAC_SPARSE
    assert all(getattr(edited["as-trained"].opt, f) == getattr(model.opt, f)
               for f in ("solver", "iterations", "cone", "jacobian", "disableflags"))


def test_variants_are_picked_by_name_with_the_model_as_trained_first():
    picked = variants_named(["condim-3", "cg", "condim-3", "as-trained"])
    assert [v.name for v in picked] == ["as-trained", "condim-3", "cg"] and picked[0] is AS_TRAINED
    assert [v.name for v in variants_named(None)] == [v.name for v in VARIANTS]
    with pytest.raises(ValueError, match="unknown physics variant.*rk4.*choose from as-trained"):
        variants_named(["rk4"])


def test_fewer_contact_dimensions_mean_fewer_constraint_rows(model):
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rows = {v: physics_profile(variant_model(model, named(v)), [data], 1)
            ["constraint_rows"] for v in ("as-trained", "condim-3", "no-frictionloss")}  # the first step: resting
    # 4 box corners on the plane: pyramidal rows 2 (condim - 1) each; the hinge's dry friction one row
    assert rows["as-trained"] == 4 * 10 + 1 and rows["condim-3"] == 4 * 4 + 1 and rows["no-frictionloss"] == 40


def test_a_variant_is_timed_from_the_given_states_under_the_given_controls(model):
    data = mujoco.MjData(model)
    data.qpos[2] = 0.3  # dropped from 0.3 m
    mujoco.mj_forward(model, data)
    ctrls = [np.full((3, 1), 0.5), np.full((3, 1), -0.5)]
    out = _time_variant(model, [data], ctrls, n_substeps=4, threads=1, seconds=0.05)
    assert out["env_steps_per_s"] > 0 and out["finite"]
    assert data.time == 0.0  # the state handed in is left as it was


def test_each_setting_change_edits_what_it_names_of_a_tasks_config():
    from legged.setting_cost import AS_TRAINED, CHANGES, changes_named
    from legged.tasks import task_entry

    flat, confined = task_entry("go1-flat").config, task_entry("confined-waypoints").config
    changed = {c.name: c.edit(confined) for c in CHANGES}
    r = confined.randomization
    assert r.enabled and r.elliptic_share and r.contact_spin and r.contact_margin and r.contact_softness  # as trains
    assert changed["as-trained"] == confined
    assert changed["no-cone-draws"].randomization == dataclasses.replace(r, elliptic_share=None, impratio=None)
    assert changed["feet-condim-3"].randomization == dataclasses.replace(r, contact_spin=None)
    assert changed["no-margin"].randomization == dataclasses.replace(r, contact_margin=None)
    assert changed["model-softness"].randomization == dataclasses.replace(r, contact_softness=None,
                                                                           contact_timeconst=None)
    assert not changed["no-randomisation"].randomization.enabled
    assert changed["tunnels"].levels is None
    levels = changed["heights-10cm"].levels
    assert levels.resolution == levels.tunnels.resolution == 0.1
    assert {c.name for c in CHANGES if c.applies(flat)} == {c.name for c in CHANGES} - {"tunnels", "heights-10cm"}
    assert all(c.applies(confined) for c in CHANGES)
    picked = changes_named(["tunnels", "no-margin", "tunnels"])
    assert [c.name for c in picked] == ["as-trained", "tunnels", "no-margin"] and picked[0] is AS_TRAINED
    with pytest.raises(ValueError, match="unknown setting change.*cheap.*choose from as-trained"):
        changes_named(["cheap"])


def test_skipped_pairs_never_touch_and_the_others_still_do():
    xml = """<mujoco><worldbody><geom name="floor" type="plane" size="1 1 0.1"/>
    <geom name="ceiling" type="box" size="1 1 0.05" pos="0 0 0.3"/>
    <body pos="0 0 0.05"><freejoint/><geom name="trunk_mid" size="0.06"/></body>
    <body pos="0.5 0 0.02"><freejoint/><geom name="FR" size="0.02"/></body></worldbody>
    <contact><pair geom1="floor" geom2="trunk_mid"/><pair geom1="ceiling" geom2="trunk_mid"/>
    <pair geom1="floor" geom2="FR"/></contact></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    model.geom_contype[:] = model.geom_conaffinity[:] = 0  # the pairs alone
    touching = {}
    for name in ("as-trained", "no-ceiling-pairs", "no-trunk-pairs"):
        edited = variant_model(model, named(name))
        data = mujoco.MjData(edited)
        mujoco.mj_forward(edited, data)
        touching[name] = sorted(mujoco.mj_id2name(edited, mujoco.mjtObj.mjOBJ_GEOM, int(c.geom2))
                                for c in data.contact[:data.ncon])
    assert touching == {"as-trained": ["FR", "trunk_mid"], "no-ceiling-pairs": ["FR", "trunk_mid"],
                        "no-trunk-pairs": ["FR"]}
    assert variant_model(model, named("no-ceiling-pairs")).pair_margin[1] < -1 and \
        variant_model(model, named("no-ceiling-pairs")).pair_margin[[0, 2]].max() == 0
    loose = variant_model(model, named("ccd-loose")).opt
    assert loose.ccd_tolerance == pytest.approx(1e-3) and loose.ccd_iterations == 10


def test_the_other_convex_collider_is_the_flag_flipped(model):
    flag = int(mujoco.mjtDisableBit.mjDSBL_NATIVECCD)
    assert variant_model(model, named("other-ccd")).opt.disableflags & flag
    assert not variant_model(variant_model(model, named("other-ccd")), named("other-ccd")).opt.disableflags & flag
