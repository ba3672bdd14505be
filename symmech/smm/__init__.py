"""Paper 3 (seed 003): the structural model method (SMM) for lumped-parameter mechanisms."""
from pathlib import Path

SEED = "003_6166172b9b245651"  # the seed file's stem: how every record names this paper

# legible entries of the printed 5.2 (L_c): (row, column) with rows s1 s2 phi3 phi4 phi5, columns c1..c4; here
# (no sympy) for both the printed twin (symmech.smm.printed) and the errata that compare it
EX52_LC_ENTRIES = ((0, 0), (0, 1), (0, 2), (0, 3), (1, 0), (1, 1), (1, 2), (1, 3), (2, 2), (2, 3),
                   (3, 0), (3, 1), (3, 2), (3, 3), (4, 0), (4, 1), (4, 2), (4, 3))


def latex_matrices(rest: str) -> dict:
    """Matrices for ``symmech latex smm:<scene>.<name>``.

    ``<scene>`` is a scene file path or the name of a bundled scene
    (``scenes/smm_<scene>.toml``); ``<name>`` is a, b, c, L_a or L_c. Shown in the readable
    form of :func:`symmech.smm.derive.readable` (parameters with positive values taken as positive).
    """
    from symmech.core.scene import SymmechError
    from symmech.smm.build import load_mechanism
    from symmech.smm.derive import SCENES, named_matrices, readable

    scene, _, key = rest.rpartition(".")
    if not scene:
        raise SymmechError(f"expected smm:<scene>.<matrix>, got 'smm:{rest}'")
    path = Path(scene)
    if not path.suffix == ".toml":
        path = SCENES / f"smm_{scene}.toml"
    if not path.exists():
        raise SymmechError(f"no mechanism scene '{scene}' (a .toml path or a bundled name such as "
                           "'double_pendulum')")
    m = load_mechanism(path)
    matrices = named_matrices(m)
    if key not in matrices:
        raise SymmechError(f"smm:{rest}: no matrix '{key}' (expected one of {', '.join(matrices)})")
    return {f"smm:{scene}.{key}": readable(matrices[key], m.values())}
