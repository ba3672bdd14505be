"""Presentation MathML of derived matrices (browsers render it natively), for ``symmech report``.

Printed once by ``symmech codegen`` into ``generated/<name>_mathml.py`` (:mod:`symmech.core.emit`), which the report
of a bundled scene reads without sympy; the report prints it itself only for a module rendered at run time (a
mechanism scene of the user's own). sympy is imported here, so runtime modules import this module lazily.
"""
from __future__ import annotations

import itertools

import sympy
from sympy.printing.mathml import mathml

# Derivations whose sympy text is longer than this are listed, not typeset (H alone is 19,000 characters: MathML of
# it would be megabytes nobody reads).
MATHML_LIMIT = 2500
_GREEK_NAMES = ("lambda", "omega", "theta", "phi", "psi")  # names typeset as a symbol, not upright text


def longer_than(expr, width: int, least) -> bool:
    """Whether ``expr`` (an expression or a matrix, every entry) prints in more than ``width`` characters by a
    lower bound alone: the sum of ``least(node)`` over its tree, each node's fewest characters in the printer's
    form. Stops as soon as the sum passes ``width``, so a huge tree costs no more than ``width`` nodes."""
    entries = expr if isinstance(expr, sympy.MatrixBase) else [expr]
    total = 0
    for node in itertools.chain.from_iterable(map(sympy.preorder_traversal, entries)):
        total += least(node)
        if total > width:
            return True
    return False


def _too_long(expr) -> bool:
    """Whether ``expr`` prints in more than :data:`MATHML_LIMIT` characters of sympy text. Each atom prints in at
    least one, so past the limit in atoms the answer is known without printing: a matrix of ~10^5 characters costs
    sympy seconds to print only to be measured."""
    return longer_than(expr, MATHML_LIMIT, lambda node: not node.args) or len(str(expr)) > MATHML_LIMIT


def _name(name: str) -> str:
    """A matrix name as MathML: a symbol (``H``, ``L_c``, ``Lambda``), else upright text (``inertia_ratio``)."""
    head = name.split("_", 1)[0]
    if len(head) == 1 or head.lower() in _GREEK_NAMES:
        return mathml(sympy.Symbol(name), printer="presentation")
    return f"<mtext>{name}</mtext>"


def block(nm) -> str | None:
    """``name = matrix`` of ``nm`` (a NamedMatrix; a scalar when its shape is ``()``) as one block of MathML;
    None when it is longer than :data:`MATHML_LIMIT`."""
    expr = nm.matrix if nm.shape else nm.matrix[0, 0]
    if _too_long(expr):
        return None
    rhs = mathml(expr, printer="presentation")
    return f'<math display="block"><mrow>{_name(nm.name)}<mo>=</mo>{rhs}</mrow></math>'
