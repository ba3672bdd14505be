"""LaTeX people can paste: long expressions broken into aligned lines, matrices entry by entry.

A derived matrix is shown as equations ``lhs &= rhs`` (one per entry when the
whole matrix is too long for one line). A long right-hand side is broken between
the terms of a sum, recursing into long factors ``\\bigl( ... \\bigr)``; the lines
go into an ``aligned`` environment (printed) or ``align*`` (a standalone document,
which may break across pages). Used by ``symmech latex``; sympy is imported here,
so runtime modules import this module lazily.
"""
from __future__ import annotations

import functools
import re
import unicodedata

import sympy

from symmech.core.typeset import longer_than

WIDTH = 110  # characters of LaTeX source per line: about one printed line
MATRIX_WIDTH = 400  # a whole matrix up to this length is printed as one matrix


def name_tex(name: str) -> str:
    """LaTeX for a matrix name: ``H`` -> ``H``, ``L_c`` -> ``L_{c}``, ``Lambda`` -> ``\\Lambda``,
    a word such as ``inertia_ratio`` upright."""
    head = name.split("_", 1)[0]
    if len(head) == 1 or head.lower() in _GREEK:
        return sympy.latex(sympy.Symbol(name))
    return r"\mathrm{" + name.replace("_", r"\_") + "}"


_GREEK = {"alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa", "lambda", "mu",
          "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi", "omega"}


def entry_tex(name: str, index: tuple[int, ...]) -> str:
    base = name_tex(name)
    if "_" in base and not base.startswith(r"\mathrm"):
        base = rf"\left({base}\right)"
    return base + "_{" + ",".join(str(i + 1) for i in index) + "}"


def equations(nm) -> list[tuple[str, sympy.Expr]]:
    """(lhs LaTeX, expression) pairs showing ``nm``: the whole matrix if short, else entry by entry."""
    matrix = nm.matrix
    if not nm.shape:
        return [(name_tex(nm.name), matrix[0, 0])]
    if _short(matrix, MATRIX_WIDTH) is not None:
        return [(name_tex(nm.name), matrix)]
    rows, cols = matrix.shape
    return [(entry_tex(nm.name, (i,) if nm.shape == (rows,) else (i, j)), matrix[i, j])
            for i in range(rows) for j in range(cols)]


def _short(expr, width: int) -> str | None:
    """The LaTeX of ``expr`` if it is at most ``width`` characters, else None. A symbol prints as its
    own LaTeX wherever it stands, any other leaf in at least one character, and every further argument
    of a node adds at least a separator: a tree longer by that count is long without printing it
    (printing each subtree at every level of the breaking would be quadratic in the largest matrices)."""
    if longer_than(expr, width, _least_latex):
        return None
    text = sympy.latex(expr) if isinstance(expr, sympy.MatrixBase) else _latex(expr)
    return text if len(text) <= width else None


@functools.lru_cache(maxsize=4096)
def _latex(expr) -> str:
    """sympy's LaTeX of ``expr`` (not a matrix), printed once: breaking long entries asks for the same
    subexpressions many times over (the 19 matrices of ``symmech.grain.derive_motion`` that test_latex lays out:
    17,276 prints of 266 distinct expressions, 19.4 s of CPU against 2.7 s printed once each)."""
    return sympy.latex(expr)


def _least_latex(node) -> int:
    """A node's fewest characters in LaTeX: a separator per further argument, a leaf its own length."""
    return len(node.args) - 1 if node.args else _leaf_length(node)


@functools.lru_cache(maxsize=4096)
def _leaf_length(leaf) -> int:
    return len(sympy.latex(leaf)) if leaf.is_Symbol else 1


def _wrap(head: str, inner: list[str], tail: str) -> list[str]:
    return [head + inner[0]] + inner[1:-1] + [inner[-1] + tail] if len(inner) > 1 else [head + inner[0] + tail]


def chunks(expr) -> list[str]:
    """Pieces of LaTeX for ``expr`` between which a line may break, in reading order."""
    text = sympy.latex(expr) if isinstance(expr, sympy.MatrixBase) else _short(expr, WIDTH)
    if text is not None:
        return [text]
    if expr.is_Add:
        out = []
        for i, term in enumerate(expr.as_ordered_terms()):
            if i and term.could_extract_minus_sign():
                sign, term = "- ", -term
            else:
                sign = "+ " if i else ""
            inner = _term_chunks(term)
            out += [sign + inner[0]] + inner[1:]
        return out
    return _term_chunks(expr)


def _term_chunks(term) -> list[str]:
    """A product or power with a long sum inside, opened as ``\\bigl( ... \\bigr)``; else one piece."""
    text = _short(term, WIDTH)
    if text is not None:
        return [text]
    if term.could_extract_minus_sign():
        inner = _term_chunks(-term)
        return ["- " + inner[0]] + inner[1:]
    if term.is_Mul:
        numer, denom = sympy.fraction(term)
        factors = sympy.Mul.make_args(numer)
        long_sums = [f for f in factors if (f.is_Add or f.is_Pow) and _short(f, WIDTH) is None]
        rest = sympy.Mul(*[f for f in factors if f not in long_sums])
        # a long factor of the denominator is opened as (...)^{-1}: a fraction cannot break across lines
        denoms = sympy.Mul.make_args(denom)
        long_denoms = [f for f in denoms if _short(f, WIDTH) is None]
        short_denom = sympy.Mul(*[f for f in denoms if f not in long_denoms])
        out = ["" if rest == 1 else _latex(rest) + " "]
        if short_denom != 1:
            out[0] += r"\frac{1}{" + _latex(short_denom) + "} "
        pieces = [_term_chunks(f) if f.is_Pow else _wrap(r"\bigl(", chunks(f), r"\bigr)") for f in long_sums]
        pieces += [_wrap(r"\bigl(", chunks(f), r"\bigr)^{-1}") for f in long_denoms]
        for inner in pieces:
            out[-1] += inner[0]
            out += inner[1:]
        return [c.strip() for c in out if c.strip()]
    if term.is_Pow and term.base.is_Add:
        return _wrap(r"\bigl(", chunks(term.base), r"\bigr)^{" + _latex(term.exp) + "}")
    return [_latex(term)]


def lines(pairs: list[tuple[str, object]], width: int = WIDTH) -> list[str]:
    """Alignment lines ``lhs &= ...`` and ``&\\quad ...`` (no ``\\\\``) for (lhs, expression) pairs."""
    out = []
    for lhs, expr in pairs:
        line = f"{lhs} &= "
        first = True
        for piece in chunks(expr):
            if not first and len(line) + len(piece) > width:
                out.append(line.rstrip())
                line = r"&\quad "
            line += piece + " "
            first = False
        out.append(line.rstrip())
    return out


def environment(body: list[str], env: str = "aligned") -> str:
    """``body`` lines inside ``\\begin{env}`` ... ``\\end{env}``, separated by ``\\\\``."""
    return "\n".join([rf"\begin{{{env}}}", " \\\\\n".join(body), rf"\end{{{env}}}"])


def text(s: str) -> str:
    """Plain text for a LaTeX document: special characters escaped, Greek letters in math mode."""
    special = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
               "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}
    out = []
    for c in s:
        if c in special:
            out.append(special[c])
        elif ord(c) < 128:
            out.append(c)
        else:
            out.append(_unicode(c))
    return "".join(out)


_SYMBOLS = {"−": "$-$", "·": r"$\cdot$", "×": r"$\times$", "∂": r"$\partial$", "≤": r"$\le$", "≥": r"$\ge$",
            "→": r"$\to$", "°": r"$^\circ$", "²": r"$^2$", "³": r"$^3$", "ᵀ": r"$^T$", "–": "--", "—": "---",
            "’": "'", "‘": "`", "“": "``", "”": "''", "…": r"\dots{}", "≈": r"$\approx$", "√": r"$\surd$"}


def _unicode(c: str) -> str:
    if c in _SYMBOLS:
        return _SYMBOLS[c]
    m = re.fullmatch(r"GREEK (SMALL|CAPITAL) LETTER (\w+)", unicodedata.name(c, ""))
    if m:
        letter = m.group(2).lower().replace("lamda", "lambda")
        return "$\\" + (letter.capitalize() if m.group(1) == "CAPITAL" else letter) + "$"
    return "?"


def document(title: str, sections: list[tuple[str, str, list[str]]]) -> str:
    """A standalone article: for each (heading, description, lines) an ``align*`` block."""
    parts = [r"\documentclass[10pt]{article}", r"\usepackage{amsmath}",
             r"\usepackage[a4paper,landscape,margin=1.5cm]{geometry}", r"\allowdisplaybreaks",
             r"\begin{document}", rf"\section*{{{text(title)}}}"]
    for heading, description, body in sections:
        parts += [rf"\subsection*{{{text(heading)}}}", text(description), "", environment(body, "align*")]
    parts.append(r"\end{document}")
    return "\n".join(parts) + "\n"
