"""The [elastic] table of a trolley scene: validation, the rigid model bit for bit, a full run."""
import copy
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.core.scene import SceneError
from symmech.core.schema import validate
from symmech.trolley import scene
from symmech.trolley.elastic import scene as elastic_scene

sys.path.insert(0, str(Path(__file__).parent))
from trolley_util import prepared as trolley_setup, setup as scene_dict  # noqa: E402

HELIX = scene_dict(frame="frenet", track={"type": "helix", "radius": 7.0, "rise": 5 / (2 * np.pi)},
                   trolley={"mass": 100.0, "com": [1.0, 0.5, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0]},
                   motion={"speed": "3*t + 7*sin(t/2)"}, time={"t_end": 3.0, "steps": 15},
                   effects={"gravity": True, "local_curvature": True})
ELASTIC = {
    "rollers": {"stiffness": [1e7] * 5, "damping": [3e3] * 5},
    "beams": [{"root": [0.5, 0.5, 0.0], "axis": [0, 1, 0], "plane": [1, 0, 0], "length": 1.5,
               "mass_per_length": 4.0, "ei": [2e4, 3e4], "modes": 2, "tip_mass": 2.0, "damping_ratio": 0.02}],
    "points": [{"name": "tip", "beam": 0, "xi": 1.0}, {"name": "seat", "at": [1.0, 0.5, 0.0]}],
    "numerics": {"modal_samples": 3},
}


def prepared(elastic, case=2, data=HELIX):
    st = trolley_setup(data)
    resolved = validate(elastic_scene.SCHEMA, copy.deepcopy(elastic))
    return st, elastic_scene.prepare(resolved, st.body, elastic_scene.drive_of(st, case), st.t)


def test_no_elastic_effect_gives_the_rigid_results_bit_for_bit():
    off = {"effects": {"rollers": False, "body": False}}
    st, es = prepared(off)
    rigid = scene.compute(st)[2]["P"]
    got = elastic_scene.run(es).tables["elastic_reactions"]
    assert np.array_equal(got.data[:, 1:], rigid)
    assert [c.header for c in got.columns] == ["t [s]"] + [f"P{i} [N]" for i in range(6)]


def test_full_run_tables_and_summary():
    st, es = prepared(ELASTIC)
    res = elastic_scene.run(es)
    res.check_finite()
    P = res.tables["elastic_reactions"]
    # beside them: the rigid model of the whole body (trolley 100 kg, beam 6 kg, tip 2 kg), by hand
    parts = [(100.0, np.array([1.0, 0.5, 0.0]), np.diag([10.0, 20.0, 15.0])),
             (6.0, np.array([0.5, 1.25, 0.0]), np.diag([6.0 * 1.5 ** 2 / 12, 0.0, 6.0 * 1.5 ** 2 / 12])),
             (2.0, np.array([0.5, 2.0, 0.0]), np.zeros((3, 3)))]
    m = sum(p[0] for p in parts)
    com = sum(p[0] * p[1] for p in parts) / m
    inertia = sum(I + mi * ((c - com) @ (c - com) * np.eye(3) - np.outer(c - com, c - com)) for mi, c, I in parts)
    whole = copy.deepcopy(HELIX)
    whole["trolley"] = {**whole["trolley"], "mass": m, "com": com.tolist(),
                        "inertia": [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[1, 2],
                                    inertia[0, 2]]}
    rigid = scene.compute(trolley_setup(whole))[2]["P"]
    assert np.allclose(P.data[:, 8:], rigid, rtol=1e-9, atol=1e-9)
    late = P.column("t") > 1.5
    assert np.abs(P.data[late, 2:8] - rigid[late]).max() < 0.05 * np.abs(rigid).max()
    assert set(res.tables) == {"elastic_reactions", "energy", "roller_deflections", "points", "modes"}
    # the energy balance's columns as the outputs' metadata gives them, the residual written out
    E = res.tables["energy"]
    assert [(c.name, c.unit, c.doc) for c in E.columns] == [
        ("t", "s", ""), ("h", "J", "T2 - T0 + Π + V_g (constant on a steady frame without damping)"),
        ("E", "J", "total energy T + Π + V_g in the fixed frame"), ("work", "J", "work of the track forces on the body"),
        ("dissipated", "J", "energy dissipated by the dampers"),
        ("residual", "J", "E - E(0) - work + dissipated (zero up to the integration error)")]
    assert np.array_equal(E.column("residual"),
                          E.column("E") - E.column("E")[0] - E.column("work") + E.column("dissipated"))
    # the summary's energy figures are the table's last work and dissipation, and its largest residual
    info = res.summary["elastic"]
    assert (info["track_work_J"], info["dissipated_J"]) == (E.column("work")[-1], E.column("dissipated")[-1])
    assert info["energy_residual_max_J"] == np.abs(E.column("residual")).max()
    pts = res.tables["points"]
    assert pts.column("seat_e1").max() == 0.0  # the trolley itself does not deform
    assert np.abs(pts.column("tip_e1")).max() > 1e-6
    amp = res.summary["elastic"]["dynamic_amplification"]
    assert 0.9 < amp["P3"] < 1.2
    modes = res.tables["modes"]
    # 3 samples x 9 modes; t, s, V0, mode_id, f, zeta, 7 identity columns, 3 x 2 report points, 3 forcing
    assert modes.data.shape == (3 * 9, 6 + 7 + 6 + 3) and len(modes.text["component"]) == 3 * 9
    assert np.all(modes.column("f") > 0)


# the held ends' refusals as a user reads them
HELD_WORDS = {"elastic.beams[0].axial": "`held` needs support = `pinned` (a cantilever has a free end)",
              "elastic.beams[0].ea": "missing: held ends (axial = `held`) need the axial stiffness EA in (0, 1e+15] N"}


@pytest.mark.parametrize("elastic, field", [
    ({"rollers": {"stiffness": [1e7] * 4}}, "elastic.rollers.stiffness"),
    ({"effects": {"rollers": True}}, "elastic.rollers"),
    ({"rollers": {"stiffness": [1e7] * 5}, "beams": [{**ELASTIC["beams"][0], "plane": [0, 2, 0]}]},
     "elastic.beams[0].plane"),
    ({"rollers": {"stiffness": [1e7] * 5}, "points": [{"name": "p", "beam": 3, "xi": 0.5}]},
     "elastic.points[0].beam"),
    ({"rollers": {"stiffness": [1e7] * 5}, "points": [{"name": "p"}]}, "elastic.points[0]"),
    ({"rollers": {"stiffness": [1e7] * 5}, "beams": [{**ELASTIC["beams"][0], "modes": 9}]},
     "elastic.beams[0].modes"),
    ({"rollers": {"stiffness": [1e7] * 5}, "beams": [{**ELASTIC["beams"][0], "axial": "held", "ea": 1e7}]},
     "elastic.beams[0].axial"),
    ({"rollers": {"stiffness": [1e7] * 5}, "beams": [{**ELASTIC["beams"][0], "axial": "held", "support": "pinned"}]},
     "elastic.beams[0].ea"),
])
def test_bad_fields_name_themselves(elastic, field):
    with pytest.raises(SceneError) as err:
        st = trolley_setup(HELIX)
        resolved = elastic_scene.SCHEMA.check("elastic", copy.deepcopy(elastic))
        elastic_scene.prepare(resolved, st.body, elastic_scene.drive_of(st, 2), st.t)
    assert str(err.value).startswith(f"scene field '{field}'")
    if field in HELD_WORDS:
        assert str(err.value) == f"scene field '{field}': {HELD_WORDS[field]}"


def test_point_mass_trolley_on_elastic_rollers_is_refused():
    data = copy.deepcopy(HELIX)
    data["trolley"]["inertia"] = [0.0] * 6
    with pytest.raises(SceneError, match="trolley.inertia"):
        prepared({"rollers": {"stiffness": [1e7] * 5}}, data=data)
