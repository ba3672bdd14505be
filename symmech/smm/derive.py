"""Layer 1: symbolic SMM matrices of a mechanism, in two forms, and the bundled modules.

* :func:`matrices` forms a, b, c and the factors L_a, L_c, L_b symbolically with
  the vector-chain form (eqs. (1)-(10), :mod:`symmech.smm.forms`) or the graph
  form with structural matrices (eq. (11), :func:`graph_kinematics`).
* :func:`named_matrices` wraps them as :class:`NamedMatrix` with the scene's
  parameters as arguments; :func:`module_specs` emits one module per bundled
  scene ``scenes/smm_*.toml`` as ``symmech.generated.smm_<name>``.

The matrix elements are algebraic expressions of the parameters; nothing is
simplified or inverted.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import sympy

from symmech.core import expressions
from symmech.core.derivation import Arg, Dynamics, ModuleSpec, NamedMatrix
from symmech.core.scene import scenes_folder
from symmech.smm import forms
from symmech.smm.build import load_mechanism
from symmech.smm.model import Effects, Mechanism, interpret

ROLE = "derivation"  # found by symmech.core.discovery

SCENES = scenes_folder()
SOURCE = "Pominov, Structural models in the dynamics of mining machines, DYNAMACH'89 (seed 003)"


_SYMPY_FUNCS = {name: sympy.Abs if name == "abs" else getattr(sympy, name) for name in expressions.FUNCTIONS}
_SYMPY_CONSTS = {"pi": sympy.pi, "E": sympy.E}


class SymbolicArith:
    """Evaluates model expressions to sympy, with one real symbol per parameter."""

    zero = sympy.S.Zero

    def __init__(self, m: Mechanism):
        self.symbols = {name: sympy.Symbol(name, real=True) for name in m.parameters}
        self._cache: dict[str, sympy.Expr] = {}

    def __call__(self, text: str, where: str = "<expression>") -> sympy.Expr:
        if text not in self._cache:
            self._cache[text] = sympy.sympify(interpret(text, self.symbols, where, _SYMPY_FUNCS, _SYMPY_CONSTS,
                                                        sympy.sympify))
        return self._cache[text]

    @staticmethod
    def sqrt(x):
        return sympy.sqrt(x)

    @staticmethod
    def sum(terms):
        return sympy.Add(*terms)

    @staticmethod
    def prod(factors):
        # Products of already-canonical sums: skipping Mul's flattening (which compares and
        # sorts the factors) is what keeps a 32-link chain under a few seconds.
        factors = [f for f in factors if f != 1]
        if any(f == 0 for f in factors):
            return sympy.S.Zero
        if len(factors) < 2:
            return factors[0] if factors else sympy.S.One
        numbers = [f for f in factors if f.is_Number]
        if len(numbers) > 1 or len(set(factors)) < len(factors):
            return sympy.Mul(*factors)
        return sympy.Mul(*factors, evaluate=False)

    @staticmethod
    def is_zero(x) -> bool:
        return x == 0


def graph_kinematics(g: forms.Geometry, point: str, second: bool) -> forms.PointKinematics:
    """Graph form (11): conjugate sums as (structural) x (vertex coordinates) products.

    Vertices are all points, edges the chain vectors (one into every non-root
    point). With P the path matrix (point x edges), T_a the edges turned by q_a
    and I the incidence matrix (edges x vertices, +1 head, -1 tail), the vectors
    turned by q_a sum to P diag(T_a) I X, X the vertex coordinates.
    """
    s = getattr(g, "_graph", None)
    if s is None:
        s = g._graph = _structure(g)
    m = g.m
    on_path = {p.name for p in m.chain(point)[1:]}
    prow = sympy.Matrix([[1 if e in on_path else 0 for e in s["edges"]]])
    r = (sympy.Matrix([[1 if v == m.chain(point)[0].name else 0 for v in s["vertices"]]]) * s["X"]
         + prow * s["Y"])
    D, H = {}, {}
    for a in m.coordinate_names:
        c = m.coordinate(a)
        if c.kind == "angle":
            S = prow.multiply_elementwise(s["T"][a]) * s["Y"]
            D[a] = forms.cross(g.axis[a], tuple(S))
        else:
            n = (prow * s["Ts"][a].T)[0, 0]
            D[a] = tuple(n * x for x in g.axis[a])
    if second:
        parts: dict = {}
        for (a, b), row in s["T2"].items():
            S = prow.multiply_elementwise(row) * s["Y"]
            v = (forms.cross(g.axis[a], forms.cross(g.axis[b], tuple(S))) if m.coordinate(b).kind == "angle"
                 else forms.cross(g.axis[a], tuple(sum(prow.multiply_elementwise(row)) * x for x in g.axis[b])))
            parts.setdefault(g.pair(a, b), []).append(v)
        H = {k: tuple(sympy.Add(*[v[i] for v in vs]) for i in range(3)) for k, vs in parts.items()}
    return forms.PointKinematics(tuple(r), {k: v for k, v in D.items() if any(x != 0 for x in v)},
                                 {k: v for k, v in H.items() if any(x != 0 for x in v)})


def _structure(g: forms.Geometry) -> dict:
    m = g.m
    vertices = list(m.points)
    edges = [p for p in vertices if m.points[p].parent is not None]
    vi = {v: i for i, v in enumerate(vertices)}
    inc = sympy.zeros(len(edges), len(vertices))
    for k, e in enumerate(edges):
        inc[k, vi[e]] += 1
        inc[k, vi[m.points[e].parent]] -= 1
    # vertex coordinates: roots at their positions, others by summing their path
    V = sympy.Matrix([list(g.vector[e]) for e in edges]) if edges else sympy.zeros(0, 3)
    X = sympy.zeros(len(vertices), 3)
    for v in vertices:
        chain = m.chain(v)
        row = sympy.Matrix([[1 if e in {p.name for p in chain[1:]} else 0 for e in edges]])
        X[vi[v], :] = sympy.Matrix([list(g.vector[chain[0].name])]) + (row * V if edges else sympy.zeros(1, 3))
    T = {a: sympy.Matrix([[1 if a in m.points[e].turns else 0 for e in edges]]) for a in m.coordinate_names}
    Ts = {a: sympy.Matrix([[1 if a in m.points[e].slides else 0 for e in edges]]) for a in m.coordinate_names}
    T2: dict = {}
    for k, e in enumerate(edges):
        p = m.points[e]
        for i, a in enumerate(p.turns):
            for b in p.turns[i:] + p.slides:
                T2.setdefault((a, b), sympy.zeros(1, len(edges)))[0, k] = 1
    return {"vertices": vertices, "edges": edges, "X": X, "Y": inc * X, "T": T, "Ts": Ts, "T2": T2}


def _dense(n: int, entries: dict, symmetric: bool = True) -> sympy.Matrix:
    out = sympy.zeros(n, n)
    for (i, j), terms in entries.items():
        v = sympy.Add(*terms)
        out[i, j] += v
        if symmetric and i != j:
            out[j, i] += v
    return out


def _factor(n: int, columns: list) -> sympy.Matrix:
    L = sympy.zeros(n, len(columns))
    for k, (_, col) in enumerate(columns):
        for i, v in col.items():
            L[i, k] = v
    return L


def matrices(m: Mechanism, form: str = "chain", effects: Effects | None = None) -> dict[str, sympy.Matrix]:
    """Symbolic a, b, c and their factors for ``m`` (form ``chain`` or ``graph``).

    Keys: a, b, c (k x k); L_a, L_c, L_b (k x columns); m_a, c_d, b_d (diagonals);
    residual (k x 1, dPi/dq in the configuration, eq. (5)).
    """
    ar = SymbolicArith(m)
    kin = {"chain": forms.chain_kinematics, "graph": graph_kinematics}[form]
    asm = forms.assemble(m, ar, kin, effects, equilibrium_tensions(m, ar, kin))
    n = len(asm.coords)
    out = {
        "L_a": _factor(n, asm.La), "m_a": sympy.diag(*asm.ma) if asm.ma else sympy.zeros(0, 0),
        "L_c": _factor(n, asm.Lc), "c_d": sympy.diag(*asm.kc) if asm.kc else sympy.zeros(0, 0),
        "L_b": _factor(n, asm.Lb), "b_d": sympy.diag(*asm.mb) if asm.mb else sympy.zeros(0, 0),
        "a": _dense(n, forms.triple_product(ar, asm.La, asm.ma, n)),
        "b": _dense(n, forms.triple_product(ar, asm.Lb, asm.mb, n)),
        "residual": sympy.Matrix([sympy.Add(*asm.residual.get(i, [])) for i in range(n)]),
    }
    entries = forms.triple_product(ar, asm.Lc, asm.kc, n)
    for part in (asm.preload, asm.gravity):
        for key, terms in part.items():
            entries.setdefault(key, []).extend(terms)
    out["c"] = _dense(n, entries)
    out["column_labels"] = {"L_a": [c[0] for c in asm.La], "L_c": [c[0] for c in asm.Lc],
                            "L_b": [c[0] for c in asm.Lb]}
    return out


def equilibrium_tensions(m: Mechanism, ar, kinematics=forms.chain_kinematics) -> dict:
    """Symbolic tensions of ``preload = "equilibrium"`` springs: eq. (5) solved on the
    independent rows chosen numerically (a u x u system, u = number of such springs), eliminated
    in the numerically pivoted row order (a round-off entry never becomes a pivot)."""
    from symmech.smm.numeric import equilibrium_tensions as numeric_tensions

    _, rows = numeric_tensions(m)  # also reports an indeterminate or unbalanced system
    names, cols, r0 = forms.tension_system(m, ar, kinematics)
    if not names:
        return {}
    G = sympy.Matrix([[col.get(i, 0) for col in cols] for i in rows])
    T = G.LUsolve(sympy.Matrix([-r0.get(i, 0) for i in rows]))
    return dict(zip(names, T))


def parameter_args(m: Mechanism) -> tuple[Arg, ...]:
    ar = SymbolicArith(m)
    return tuple(Arg(ar.symbols[p.name], p.meaning, p.unit) for p in m.parameters.values())


_MEANING = {
    "a": ("inertia matrix (a), a q'' + b q' + c q = Q", "kg, kg m, kg m^2 by coordinate kinds", "(1), (3)"),
    "b": ("damping matrix (b)", "N s/m, N s, N m s by coordinate kinds", "(10)"),
    "c": ("stiffness matrix (c) with the effects the scene asks for", "N/m, N, N m by coordinate kinds",
          "(7), (9)"),
    "L_a": ("inertia transformation matrix (L_a): rows coordinates, columns mass/inertia components",
            "m or 1", "(3)"),
    "L_c": ("stiffness transformation matrix (L_c): rows coordinates, columns springs", "m or 1", "(9)"),
}


def named_matrices(m: Mechanism) -> dict[str, NamedMatrix]:
    """a, b, c, L_a, L_c of ``m`` as NamedMatrix (arguments: the scene's parameters)."""
    mats = matrices(m)
    args = parameter_args(m)
    out = {}
    for key, (meaning, unit, eqs) in _MEANING.items():
        mat = mats[key]
        if mat.shape[1] == 0:  # no columns (e.g. no springs): an explicit empty factor
            mat = sympy.zeros(mat.shape[0], 1)
        out[key] = NamedMatrix(key, mat, args, f"{m.name}: {meaning}", unit, eqs)
    return out


def readable(nm: NamedMatrix, values: dict[str, float], max_ops: int = 150) -> NamedMatrix:
    """``nm`` tidied for display (``symmech latex``), assuming positive every parameter whose
    value is positive: square roots of sums (spring lengths) are trig-simplified and elements
    under ``max_ops`` operations simplified. Generated code keeps the general form, valid for
    parameters of any sign; the assumption is stated in the returned meaning."""
    used = nm.matrix.free_symbols
    positive = {a.symbol: sympy.Symbol(a.name, positive=True) for a in nm.args
                if a.symbol in used and values[a.name] > 0}
    back = {v: k for k, v in positive.items()}
    roots = (sympy.S.Half, -sympy.S.Half, sympy.Rational(-3, 2))

    def tidy(e):
        e = e.xreplace(positive)
        e = e.xreplace({p: sympy.Pow(sympy.trigsimp(sympy.factor_terms(p.base)), p.exp)
                        for p in e.atoms(sympy.Pow) if p.exp in roots and p.base.is_Add})
        return (sympy.simplify(e) if sympy.count_ops(e) < max_ops else e).xreplace(back)

    names = ", ".join(sorted(s.name for s in positive))
    meaning = nm.meaning + (f"; shown for {names} > 0" if names else "")
    return replace(nm, matrix=nm.matrix.applyfunc(tidy), meaning=meaning)


def module_name(m: Mechanism) -> str:
    return "smm_" + "".join(ch if ch.isalnum() else "_" for ch in m.name.lower())


def free_motion(m: Mechanism, nms: dict[str, NamedMatrix]) -> Dynamics:
    """The free motion a q'' + b q' + c q = 0 as M y' = F: y = (q, q'), M = diag(E, a),
    F = (q', -(b q' + c q)); the linear motion about the configuration that `run` integrates."""
    q = [Arg(sympy.Symbol(f"q_{c.name}", real=True), f"coordinate {c.name} ({c.kind})", c.unit)
         for c in m.coordinates]
    qd = [Arg(sympy.Symbol(f"qd_{c.name}", real=True), f"rate of {c.name}", f"{c.unit}/s")
          for c in m.coordinates]
    qv, qdv = (sympy.Matrix([a.symbol for a in x]) for x in (q, qd))
    n = len(q)
    mass = sympy.diag(sympy.eye(n), nms["a"].matrix)
    rate = sympy.Matrix.vstack(qdv, -(nms["b"].matrix * qdv + nms["c"].matrix * qv))
    return Dynamics(q + qd, nms["a"].args, rate, mass, meaning=f"the free motion of '{m.name}' about its configuration")


def module_spec(m: Mechanism) -> ModuleSpec:
    nms = named_matrices(m)
    doc = (f"Structural model method matrices of the mechanism '{m.name}': "
           f"a q'' + b q' + c q = Q, coordinates ({', '.join(m.coordinate_names)}).")
    return ModuleSpec(module_name(m), doc, SOURCE, tuple(nms.values()), free_motion(m, nms))


def bundled_scenes() -> list[Path]:
    """The bundled mechanism scenes whose modules live in generated/."""
    return sorted(SCENES.glob("smm_*.toml"))


def module_specs() -> list[ModuleSpec]:
    return [module_spec(load_mechanism(p)) for p in bundled_scenes()]
