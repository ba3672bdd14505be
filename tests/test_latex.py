"""`symmech latex`: aligned lines people can paste, and a standalone .tex that compiles."""
import re
import shutil
import subprocess

import numpy as np
import pytest
import sympy

from symmech.cli import main
from symmech.core import codegen, latex

MAX_LINE = 2000
# every derivation runs once per process (codegen.derive caches): one xdist worker derives them all
pytestmark = pytest.mark.xdist_group("derive")


def balanced(text: str) -> None:
    """Environments nest, braces balance, \\left/\\right pair within each line, \\bigl/\\bigr overall."""
    stack = []
    for kind, env in re.findall(r"\\(begin|end)\{([^}]*)\}", text):
        if kind == "begin":
            stack.append(env)
        else:
            assert stack and stack.pop() == env, f"\\end{{{env}}} without its \\begin"
    assert not stack, f"unclosed environments {stack}"
    body = text.replace(r"\{", "").replace(r"\}", "")
    assert body.count("{") == body.count("}")
    for line in text.splitlines():
        assert len(re.findall(r"\\left\b", line)) == len(re.findall(r"\\right\b", line)), line[:200]
    assert text.count(r"\bigl(") == text.count(r"\bigr)")


# The largest expressions take seconds each to lay out (~35 s of CPU in all with their `--cse` forms, 160 s
# before symmech.core.latex printed each subexpression once): the slow tier prints them.
HEAVY = ("trolley_elastic_lagrange.rate", "trolley_elastic_lagrange.lagrange_residual",
         "trolley_elastic_lagrange.rate_mass", "smm_spatial_boom.rate", "smm_spatial_boom.c",
         "smm_spatial_boom.rate_jacobian", "grain_sliding.stick_force", "grain_sliding.slip_direction",
         "grain_sliding.slip_rate", "grain_sliding.stick_rate", "grain_sliding.stick_events",
         "grain_sliding.friction_impulse")


def _prints_in_short_balanced_lines(name, nm):
    text = latex.environment(latex.lines(latex.equations(nm)))
    balanced(text)
    longest = max(map(len, text.splitlines()))
    assert longest <= MAX_LINE, (name, longest)


@pytest.mark.parametrize("producer", codegen.producers())
def test_every_derived_matrix_prints_in_short_balanced_lines(producer):
    names = []
    for spec in codegen.derive(producer)[0]:
        for f in spec.functions:
            name = f"{spec.name}.{f.name}"
            if name not in HEAVY:
                _prints_in_short_balanced_lines(name, f)
                names.append(name)
    assert names  # every producer declares matrices


@pytest.mark.slow
def test_the_largest_derived_matrices_print_in_short_balanced_lines():
    matrices = codegen.named_matrices()
    for name in HEAVY:
        _prints_in_short_balanced_lines(name, matrices[name])


def test_largest_matrix_is_entry_by_entry(capsys):
    """grain_impact.H was one 44 KB line; now nine entries in aligned lines of at most ~600 characters."""
    assert main(["latex", "grain_impact.H"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].startswith("% grain_impact.H: ") and lines[1] == r"\begin{aligned}" and lines[-1] == r"\end{aligned}"
    entries = [l.split(" &= ")[0] for l in lines if " &= " in l]
    assert entries == [f"H_{{{i},{j}}}" for i in (1, 2, 3) for j in (1, 2, 3)]
    assert len(lines) > 100 and max(map(len, lines)) < 700
    balanced("\n".join(lines[1:]))


def test_a_short_sum_breaks_only_between_terms():
    x = sympy.symbols("x0:40")
    expr = sum((-1) ** k * (k + 1) * x[k] ** 2 for k in range(40))
    pieces = latex.chunks(expr)
    assert len(pieces) == 40 and " ".join(pieces) == sympy.latex(expr)
    body = latex.lines([("y", expr)])
    assert body[0].startswith("y &= ") and all(l.startswith(r"&\quad ") for l in body[1:])
    assert max(map(len, body)) <= latex.WIDTH + 20
    # the lines join back to the expression sympy prints
    joined = " ".join(l.replace("y &= ", "").replace(r"&\quad ", "") for l in body)
    assert joined == sympy.latex(expr)


def test_a_long_factor_opens_in_big_parentheses():
    x = sympy.symbols("x0:30")
    s = sum(x)
    expr = -sympy.Symbol("a") * s / (1 + sympy.Symbol("b") ** 2)
    pieces = latex.chunks(expr)
    assert pieces[0].startswith(r"- a \frac{1}{b^{2} + 1} \bigl(x_{0}")
    assert pieces[-1].endswith(r"\bigr)")
    balanced(" ".join(pieces))


def test_short_matrix_stays_a_matrix(capsys):
    assert main(["latex", "grain_impact.euler_rate_matrix"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[2].startswith(r"\mathrm{euler\_rate\_matrix} &= \left[\begin{matrix}\cos{\left(\phi \right)}")


def test_text_escapes_and_greek():
    assert latex.text("Λ* and ω_1: 5 % of θ") == r"$\Lambda$* and $\omega$\_1: 5 \% of $\theta$"


def _write_tex(tmp_path, capsys, name, *flags):
    path = tmp_path / (name.replace(":", "_") + ".tex")
    assert main(["latex", name, "--tex", str(path), *flags]) == 0
    capsys.readouterr()
    text = path.read_text()
    balanced(text)
    assert max(map(len, text.splitlines())) <= MAX_LINE
    assert text.isascii()
    return path


@pytest.mark.parametrize("name, flags", [("grain_impact.H", ()),
                                         pytest.param("smm:spatial_boom.c", (), marks=pytest.mark.slow),
                                         ("trolley_frame.Lambda", ("--cse",))])
def test_standalone_tex_compiles(tmp_path, capsys, name, flags):
    path = _write_tex(tmp_path, capsys, name, *flags)
    assert path.read_text().startswith(r"\documentclass")
    tex = shutil.which("pdflatex")
    if tex is None:
        pytest.skip("pdflatex not found (.ci/run installs Debian's texlive-latex-base); structure checked only")
    run = subprocess.run([tex, "-interaction=nonstopmode", "-halt-on-error", path.name], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-2000:]
    assert path.with_suffix(".pdf").read_bytes().startswith(b"%PDF")
    pages = int(re.search(r"Output written on .*\((\d+) pages?", run.stdout).group(1))
    assert pages >= (2 if name == "grain_impact.H" else 1)
    assert "Undefined control sequence" not in run.stdout


def test_short_is_the_latex_exactly_when_it_fits():
    """The count that spares printing long subtrees never calls a short expression long (else a line would
    break where it need not) and never returns a long one."""
    rng = np.random.default_rng(7)
    atoms = [*sympy.symbols("x y_1 theta omega_3 xdot xprime q__2"), sympy.Integer(-1), sympy.Rational(1, 2),
             sympy.Integer(3), sympy.Function("f")(sympy.Symbol("t")), sympy.pi]
    ops = [sympy.Add, sympy.Mul, lambda a, b: sympy.Pow(a, b), lambda a, b: sympy.sin(a) * b]
    for _ in range(300):
        expr = atoms[rng.integers(len(atoms))]
        for _ in range(rng.integers(1, 6)):
            expr = ops[rng.integers(len(ops))](expr, atoms[rng.integers(len(atoms))])
        text = sympy.latex(expr)
        for width in (len(text) - 1, len(text), 5, 20, 60):
            assert latex._short(expr, width) == (text if len(text) <= width else None), (expr, width)
