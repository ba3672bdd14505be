"""The C sources of an exported model: the generated physics, ``model.h``, the DOP853 and Radau IIA tableaux
and the hand-written glue of ``symmech/export/c`` (FMI 2 and 3, the linear solve, the integrators)."""
from __future__ import annotations

import hashlib
import importlib.resources

import jinja2

from symmech.numerics import dop853_tableau as dop853, radau_tableau as radau
from symmech.export.model import ExportModel

GLUE = ("symmech_model.h", "symmech_model.c")


def token(model: ExportModel) -> str:
    """Instantiation token (FMI 3) and GUID (FMI 2): a digest of the physics and the variables, UUID-shaped."""
    digest = hashlib.sha256((model.c_source + repr(model.modules) + repr(model.variables)).encode()).hexdigest()
    return "{" + "-".join((digest[:8], digest[8:12], digest[12:16], digest[16:20], digest[20:32])) + "}"


def glue(name: str) -> str:
    """Text of a hand-written C file of ``symmech/export/c``."""
    return importlib.resources.files("symmech.export").joinpath("c", name).read_text(encoding="utf-8")


def model_header(model: ExportModel) -> str:
    """``model.h``: the layout constants, start values and the generated functions the glue calls."""
    template = importlib.resources.files("symmech.export").joinpath("model.h.j2").read_text(encoding="utf-8")
    env = jinja2.Environment(keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True,
                             undefined=jinja2.StrictUndefined)
    layout = model.layout()
    starts = ["0.0"] * layout["N_REAL"]
    for v in model.variables:
        if v.start is not None:
            starts[v.vr] = repr(float(v.start))
    nominals = [repr(float(v.nominal if v.nominal is not None else 1.0)) for v in model.variables
                if layout["VR_X"] <= v.vr < layout["VR_X"] + model.n_x]
    return env.from_string(template).render(model=model, token=token(model), layout=layout, starts=starts,
                                            nominals=nominals,
                                            table=_table(model))


def _table(model: ExportModel) -> dict:
    """The example program's table: the native main table's columns and times, or without one the states
    that are not derivatives over 1 s in 100 steps."""
    by_name = {v.name: v.vr for v in model.variables}
    if model.native is None:
        states = [v for v in model.variables if v.causality == "output" and v.vr < 1 + model.n_x
                  and v.derivative_of is None]
        return {"header": ",".join(["t"] + [v.name for v in states]), "vrs": [v.vr for v in states],
                "stop": 1.0, "steps": 100}
    names = [c.name for c in model.native.columns]
    t = model.native.column("t")
    return {"header": ",".join(names), "vrs": [by_name[n] for n in names[1:]], "stop": repr(float(t[-1])),
            "steps": len(t) - 1}


def _array(name: str, values) -> str:
    return f"static const double {name}[{len(values)}] = {{{', '.join(repr(float(x)) for x in values)}}};"


def tableau_header() -> str:
    """``dop853_tableau.h``: symmech.numerics.dop853's C, A (the 12 stages, the FSAL stage and the 3 stages of the
    dense output), B, E5, E3 and D (the interpolant's last 4 coefficient rows)."""
    n, extended = dop853.N_STAGES, dop853.N_STAGES_EXTENDED

    def matrix(name, a):
        rows = ",\n    ".join("{" + ", ".join(repr(float(x)) for x in row) + "}" for row in a)
        return f"static const double {name}[{a.shape[0]}][{a.shape[1]}] = {{\n    {rows}}};"

    return "\n".join([
        "/* The DOP853 tableau (Dormand and Prince 8(5,3), from Hairer's dop853.f) and its dense output of order 7, "
        "written by `symmech export` from symmech/numerics/dop853.py. */",
        "#ifndef DOP853_TABLEAU_H", "#define DOP853_TABLEAU_H", f"#define DOP853_STAGES {n}",
        f"#define DOP853_EXTENDED {extended}", f"#define DOP853_POWER {dop853.INTERPOLATOR_POWER}",
        _array("DOP853_C", dop853.C[:extended]), matrix("DOP853_A", dop853.A[:extended, :extended]),
        _array("DOP853_B", dop853.B), _array("DOP853_E5", dop853.E5), _array("DOP853_E3", dop853.E3),
        matrix("DOP853_D", dop853.D), "#endif", ""])


def radau_header() -> str:
    """``radau_tableau.h``: symmech.numerics.radau_tableau's nodes, error estimator, T, TI, the dense-output
    matrix and scipy's step-control constants."""
    def matrix(name, a):
        rows = ",\n    ".join(", ".join(repr(float(x)) for x in row) for row in a)
        return f"static const double {name}[{a.size}] = {{\n    {rows}}};"

    return "\n".join([
        "/* The Radau IIA tableau of order 5 and scipy's step control, written by `symmech export` from "
        "symmech/numerics/radau_tableau.py. */",
        "#ifndef RADAU_TABLEAU_H", "#define RADAU_TABLEAU_H", _array("RADAU_C", radau.C), _array("RADAU_E", radau.E[0]),
        matrix("RADAU_T", radau.T), matrix("RADAU_TI", radau.TI), matrix("RADAU_PT", radau.PT),
        f"#define RADAU_MU_REAL {radau.MU_REAL!r}", f"#define RADAU_MU_COMPLEX_RE {radau.MU_COMPLEX.real!r}",
        f"#define RADAU_MU_COMPLEX_IM {radau.MU_COMPLEX.imag!r}", f"#define RADAU_NEWTON_MAXITER {radau.NEWTON_MAXITER}",
        f"#define RADAU_MIN_FACTOR {radau.MIN_FACTOR!r}", f"#define RADAU_MAX_FACTOR {radau.MAX_FACTOR!r}",
        f"#define RADAU_POWER {radau.POWER!r}", "#endif", ""])


def files(model: ExportModel) -> dict[str, str]:
    """Every C file of the model but the FMI glue: name -> text."""
    out = {f"{model.identifier}.c": model.c_source, "model.h": model_header(model),
           "dop853_tableau.h": tableau_header(), "radau_tableau.h": radau_header()}
    out.update((f"{name}.c", text) for name, text in model.modules)
    out.update((name, glue(name)) for name in GLUE)
    return out
