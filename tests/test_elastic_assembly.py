"""The elastic trolley's generated assembly (symmech.trolley.elastic.symbolic_assembly, printed in C99 at export
time) against the Python engine's (symmech.trolley.elastic.System: the numpy sums over the same invariants), at
seeded random states and frame motions: R, M, P0…P5 and the roller deflections to 1e-12 of each quantity's
scale. Default tier: the bundled helix with one beam mode per plane, no report points and the clamped roller
law; slow tier: the bundled helix as it is (its report points' outputs are checked through the exported FMU,
tests/test_export_trolley.py), and the assembly under traction against the Python engine's traction step."""
from __future__ import annotations

import ctypes
import shutil
import subprocess
import tomllib

import dataclasses

import numpy as np
import pytest

from fuzzscenes import toml_text
from symmech.core import expressions, pipeline
from symmech.core.scene import scenes_folder
from symmech.export import trolley
from symmech.trolley.elastic import frame as el_frame, simulate as el_sim, system as el

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
DOUBLES = ctypes.POINTER(ctypes.c_double)
RTOL = 1e-12


def _scene(tmp_path, edit):
    """The bundled helix without its modal study, edited by ``edit``: the loaded scene."""
    doc = tomllib.loads((scenes_folder() / "trolley_elastic_helix.toml").read_text(encoding="utf-8"))
    doc["elastic"]["numerics"]["modal_samples"] = 0
    edit(doc)
    path = tmp_path / "scene.toml"
    path.write_text(toml_text(doc))
    return pipeline.load(path)


def _system(tmp_path, edit) -> el.System:
    return _scene(tmp_path, edit).setup.elastic.system


def _library(system, tmp_path, law=None):
    source = tmp_path / "elastic_assembly.c"
    source.write_text(trolley.assembly_c(system, law))
    library = tmp_path / "elastic_assembly.so"
    subprocess.run(["cc", "-std=c99", "-O1", "-fPIC", "-shared", "-Wall", "-Werror", "-o", str(library),
                    str(source), "-lm"], check=True)
    return ctypes.CDLL(str(library))


def _pointers(*arrays):
    return [a.ctypes.data_as(DOUBLES) for a in arrays]


def _rates(library, y, p, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """F (n) of M y' = F and M's block below its identity rows (n/2, n/2) from the generated
    ``rate_and_mass_block`` at time t [s], state y (n,)."""
    n2, k = y.size, y.size // 2
    both = np.full(n2 + k * k, np.nan)
    library.elastic_assembly_rate_and_mass_block(ctypes.c_double(t), *_pointers(y, p, both))
    return both[:n2], both[n2:].reshape(k, k)


def _close(got, expected, scale) -> None:
    np.testing.assert_allclose(got, expected, rtol=0, atol=RTOL * scale)


def _compare(system, library, states: int = 5) -> None:
    """The generated rate, mass block and outputs against System.evaluate, mass, reactions and roller_state."""
    rng = np.random.default_rng(32)
    n = system.N
    rl = system.mdl.rollers
    damping = rl.damping if system.mdl.effects.damping else np.zeros(5)
    rollers = np.r_[rl.stiffness, damping, rl.preload]  # the generated module's first parameters
    for _ in range(states):
        q, qd, qdd = rng.normal(0.0, 1e-3, n), rng.normal(0.0, 1e-2, n), rng.normal(0.0, 1.0, n)
        v0, a0, w, dw, nu = (rng.normal(0.0, 1.0, 3) for _ in range(5))
        fs = el_frame.FrameState(v0, a0, w, dw, nu)
        load = a0 + system.mdl.g0 * nu
        p = np.r_[rollers, load, w, dw, v0]
        rate, block = _rates(library, np.r_[q, qd], p)
        R = system.evaluate(fs, q, qd, np.zeros(n))
        terms = np.abs(system.inv.K @ q).max() + np.abs(system.inv.S1).max() * np.abs(load).max()
        np.testing.assert_array_equal(rate[:n], qd)
        _close(-rate[n:], R, terms)
        M = system.mass(q)
        _close(block, np.tril(M), np.abs(M).max())  # M is symmetric: the Cholesky solve reads its lower triangle
        outputs = np.full(11 + 9 * len(system.inv.probe_points), np.nan)
        library.elastic_assembly_outputs(*_pointers(np.r_[q, qd, qdd, p], outputs))
        P = system.reactions(fs, q, qd, qdd)
        _close(outputs[:6], P, np.abs(P).max())
        d = system.roller_state(q, qd)[0]
        _close(outputs[6:11], d, np.abs(d).max())


def test_generated_assembly_equals_the_python_engine(tmp_path):
    def small(doc):
        doc["elastic"]["beams"][0]["modes"] = 1
        del doc["elastic"]["points"]
        doc["elastic"]["rollers"]["law"] = "clamped_pair"
        doc["elastic"]["rollers"]["preload"] = [2e-4] * 5
    system = _system(tmp_path, small)
    assert system.mdl.rollers.law != "linear"
    _compare(system, _library(system, tmp_path))


@pytest.mark.slow  # the whole helix: ~5 s of sympy
def test_generated_assembly_of_the_bundled_helix_equals_the_python_engine(tmp_path):
    system = _system(tmp_path, lambda doc: None)
    _compare(system, _library(system, tmp_path))


@pytest.mark.slow  # sympy derives the traction assembly (~3 s)
def test_generated_traction_assembly_equals_the_python_engine(tmp_path):
    """Under traction (y = (q, s, q', V0)): q'' and V0' solved from the generated rate and mass, and the outputs
    P0…P5, against the Python engine's Timeline.traction_step and reactions at seeded random states along the
    track and times (law P0 = 100 - 10 v + 5 t N); with 50 N added to F's last row (the FMU's input), against
    the engine with the law + 50 N."""
    def traction(doc):
        doc["elastic"]["beams"][0]["modes"] = 1
        del doc["elastic"]["points"]
        doc["motion"] = {"traction": "100 - 10*v + 5*t", "initial_speed": 3.0}
        doc["effects"]["traction"] = True
    scene = _scene(tmp_path, traction)
    system, drive = scene.setup.elastic.system, scene.setup.elastic.drive
    law = expressions.parse("motion.traction", "100 - 10*v + 5*t", ("t", "v"))
    library = _library(system, tmp_path, law)
    rng = np.random.default_rng(32)
    n = system.N
    rollers = np.r_[system.mdl.rollers.stiffness, system.mdl.rollers.damping, np.zeros(5)]
    for extra in (0.0, 50.0):
        stronger = dataclasses.replace(drive, traction=lambda t, v: drive.traction(t, v) + extra)
        line = el_sim.Timeline(system, stronger, [0.0, 3.0], None)
        for _ in range(4):
            q, qd = rng.normal(0.0, 1e-4, n), rng.normal(0.0, 1e-3, n)
            s, V, t = rng.uniform(0.0, 10.0), rng.uniform(1.0, 8.0), rng.uniform(0.0, 3.0)
            p = np.r_[rollers, el_frame.geometry(drive, np.array([s]))[0]]
            rate, block = _rates(library, np.r_[q, s, qd, V], p, t)
            np.testing.assert_array_equal(rate[:n + 1], np.r_[qd, V])
            rate[-1] += extra
            x = np.linalg.solve(block, rate[n + 1:])  # the exported model solves with the block
            fs, qdd, dV = line.traction_step(t, np.r_[q, qd, 0.0, 0.0, s, V])
            _close(x[:n], qdd, np.abs(qdd).max())
            _close(x[n], dV, abs(dV))
            outputs = np.full(11, np.nan)
            library.elastic_assembly_outputs(*_pointers(np.r_[q, s, qd, V, x, p], outputs))
            P = system.reactions(fs, q, qd, qdd)
            _close(outputs[:6], P, np.abs(P).max())
            assert outputs[0] == pytest.approx(100 - 10 * V + 5 * t + extra, rel=1e-12)
