"""The one safe expression language of scene files: parse to sympy, check over a domain.

An expression is Python arithmetic text (``3*t + 7*sin(t/2)``) read by :mod:`ast`,
never evaluated by Python. :func:`tree` checks it against a whitelist before
anything is computed:

* size: at most ``MAX_CHARS`` characters and ``MAX_NODES`` syntax-tree nodes;
* nodes: numbers, names, ``+ - * / **``, unary ``+ -`` and calls of the whitelisted
  functions with their exact argument count — no attributes, subscripts, keywords,
  strings, comparisons or lambdas;
* names: the caller's variables and constants, ``pi`` and ``E``; anything else
  (``x0``, ``numpy``, ``__import__``) is refused by name;
* powers: a constant exponent must satisfy ``|p| <= MAX_EXPONENT`` and every
  constant sub-expression must stay below ``MAX_MAGNITUDE``, found by float
  arithmetic on the tree — ``9**9**9`` is refused without being evaluated.

:func:`parse` builds the sympy expression from the checked tree (sympy is
imported there, never at module import). :func:`check_domain` evaluates an
expression over its whole domain — dense samples plus, for every sub-expression
with a restricted domain (denominators, log, fractional powers, tan, asin, acos,
acosh), a search for the parameter value where the restriction is violated — and
raises a SceneError naming the field and that value.
"""
from __future__ import annotations

import ast
import keyword
import math
import re

import numpy as np

from symmech.core.scene import SceneError

MAX_CHARS = 2000
MAX_NODES = 400
MAX_EXPONENT = 100
MAX_MAGNITUDE = 1e300
MAX_DERIVED_NODES = 20_000  # expression-tree nodes a derivative may have (bounds the work on it)
# Function name -> number of arguments.
FUNCTIONS = {"sin": 1, "cos": 1, "tan": 1, "exp": 1, "log": 1, "sqrt": 1, "sinh": 1, "cosh": 1, "tanh": 1,
             "asinh": 1, "acosh": 1, "atanh": 1, "asin": 1, "acos": 1, "atan": 1, "atan2": 2, "abs": 1}
CONSTANTS = {"pi": math.pi, "E": math.e}
# Names users may not give to their own constants: the language's own names, and
# names internal to generated or lambdified code (cse symbols x0, x1, ..., modules).
_RESERVED = re.compile(r"x\d+|_.*|numpy|np|math|sympy|scipy|builtins|lambda|Dummy|Symbol|Integer|Float")
_OPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_FLOAT_FUNCS = {"sin": math.sin, "cos": math.cos, "tan": math.tan, "exp": math.exp, "log": math.log,
                "sqrt": math.sqrt, "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "asinh": math.asinh,
                "acosh": math.acosh, "atanh": math.atanh, "asin": math.asin, "acos": math.acos, "atan": math.atan,
                "atan2": math.atan2, "abs": abs}
_NODE_NAMES = {ast.Attribute: "attribute access", ast.Subscript: "subscripts", ast.Lambda: "lambda",
               ast.Compare: "comparisons", ast.BoolOp: "and/or", ast.IfExp: "if-else",
               ast.BitXor: "^ (use ** for powers)"}


def check_name(field: str, name: str, taken=()) -> str:
    """``name`` if it may name a user constant; SceneError (reserved, keyword, function, duplicate) otherwise."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise SceneError(field, f"{name!r} is not an identifier")
    if keyword.iskeyword(name) or _RESERVED.fullmatch(name) or name in FUNCTIONS or name in CONSTANTS:
        raise SceneError(field, f"the name {name!r} is reserved (functions, pi, E, x0, x1, ..., "
                                "module names and names starting with _ cannot be redefined)")
    if name in taken:
        raise SceneError(field, f"the name {name!r} is already used by a variable")
    return name


def tree(field: str, text, names) -> ast.Expression:
    """The checked syntax tree of ``text``; ``names`` are the admissible variable/constant names
    (None: any name, for a syntax check before the names are known)."""
    if not isinstance(text, str):
        raise SceneError(field, f"expected an expression (a string), got {text!r}"[:200])
    if len(text) > MAX_CHARS:
        raise SceneError(field, f"expression of {len(text)} characters; at most {MAX_CHARS}")
    if not text.strip():
        raise SceneError(field, "empty expression")
    try:
        root = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, MemoryError, RecursionError) as exc:
        raise SceneError(field, f"cannot parse {_short(text)}: {getattr(exc, 'msg', type(exc).__name__)}") from None
    nodes = list(ast.walk(root))
    if len(nodes) > MAX_NODES:
        raise SceneError(field, f"expression of {len(nodes)} syntax nodes; at most {MAX_NODES}")
    allowed = None if names is None else set(names) | set(CONSTANTS)
    called = {id(n.func) for n in nodes if isinstance(n, ast.Call)}
    for node in nodes:
        if isinstance(node, ast.Name) and node.id in FUNCTIONS and id(node) not in called:
            raise SceneError(field, f"the function {node.id} is used without arguments in {_short(text)}")
        _check_node(field, text, node, allowed)
    _constant_value(field, text, root.body)
    return root


def _check_node(field, text, node, allowed):
    if isinstance(node, (ast.Expression, ast.Load, ast.UAdd, ast.USub)) or type(node) in _OPS:
        return
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise SceneError(field, f"{node.value!r} is not a real number in {_short(text)}")
        return
    if isinstance(node, ast.Name):
        if allowed is not None and node.id not in allowed and node.id not in FUNCTIONS:
            raise SceneError(field, f"unknown name {node.id!r} in {_short(text)}; allowed: "
                                    f"{', '.join(sorted(allowed))} and the functions {', '.join(FUNCTIONS)}")
        return
    if isinstance(node, ast.BinOp):
        if type(node.op) not in _OPS:
            raise SceneError(field, f"operator {_NODE_NAMES.get(type(node.op), type(node.op).__name__)} "
                                    f"is not allowed in {_short(text)}")
        return
    if isinstance(node, ast.UnaryOp):
        if not isinstance(node.op, (ast.UAdd, ast.USub)):
            raise SceneError(field, f"operator {type(node.op).__name__} is not allowed in {_short(text)}")
        return
    if isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS:
            raise SceneError(field, f"only the functions {', '.join(FUNCTIONS)} may be called, in {_short(text)}")
        if node.keywords or len(node.args) != FUNCTIONS[name] or any(isinstance(a, ast.Starred) for a in node.args):
            raise SceneError(field, f"{name} takes {FUNCTIONS[name]} argument(s), in {_short(text)}")
        return
    what = _NODE_NAMES.get(type(node), type(node).__name__)
    raise SceneError(field, f"{what} is not allowed in {_short(text)}")


def _constant_value(field, text, node):
    """Float value of ``node`` when it is constant (None otherwise), enforcing the power and
    magnitude bounds on every constant sub-expression; never evaluates a refused power."""
    if isinstance(node, ast.Constant):
        value = node.value
        if not abs(value) <= MAX_MAGNITUDE:
            raise SceneError(field, f"a number in {_short(text)} overflows (limit {MAX_MAGNITUDE:g})")
        return float(value)
    if isinstance(node, ast.Name):
        return CONSTANTS.get(node.id)
    if isinstance(node, ast.UnaryOp):
        v = _constant_value(field, text, node.operand)
        return None if v is None else (-v if isinstance(node.op, ast.USub) else v)
    if isinstance(node, ast.BinOp):
        left = _constant_value(field, text, node.left)
        right = _constant_value(field, text, node.right)
        if isinstance(node.op, ast.Pow) and right is not None and abs(right) > MAX_EXPONENT:
            raise SceneError(field, f"exponent {right:.6g} exceeds {MAX_EXPONENT} in {_short(text)}")
        if left is None or right is None:
            return None
        return _checked(field, text, lambda: _apply(node.op, left, right))
    if isinstance(node, ast.Call):
        args = [_constant_value(field, text, a) for a in node.args]
        if any(a is None for a in args):
            return None
        return _checked(field, text, lambda: _FLOAT_FUNCS[node.func.id](*args))
    return None


def _apply(op, a, b):
    if isinstance(op, ast.Add):
        return a + b
    if isinstance(op, ast.Sub):
        return a - b
    if isinstance(op, ast.Mult):
        return a * b
    if isinstance(op, ast.Div):
        return a / b
    return a**b


def _checked(field, text, compute):
    try:
        value = compute()
    except ZeroDivisionError:
        raise SceneError(field, f"division by zero in {_short(text)}") from None
    except OverflowError:
        raise SceneError(field, f"constant part of {_short(text)} overflows (limit {MAX_MAGNITUDE:g})") from None
    except ValueError:
        raise SceneError(field, f"constant part of {_short(text)} is undefined (e.g. log(0), sqrt of a "
                                "negative number)") from None
    if isinstance(value, complex):
        raise SceneError(field, f"complex value {value} in {_short(text)}")
    if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
        raise SceneError(field, f"constant part of {_short(text)} overflows ({value:g})")
    return value


def symbol(name: str):
    """The sympy symbol a variable ``name`` stands for (real)."""
    import sympy as sp

    return sp.Symbol(name, real=True)


def parse(field: str, text, variables, constants=None):
    """sympy expression of ``text`` in ``variables`` (names, see :func:`symbol`); ``constants``
    maps user names to numbers. SceneError naming ``field`` for anything refused."""
    import sympy as sp

    constants = constants or {}
    root = tree(field, text, list(variables) + list(constants))
    values = {v: symbol(v) for v in variables}
    values.update({k: sp.Float(v) for k, v in constants.items()})
    values.update({"pi": sp.pi, "E": sp.E})
    funcs = {"abs": sp.Abs, "atan2": sp.atan2, **{f: getattr(sp, f) for f in FUNCTIONS if f not in ("abs", "atan2")}}

    def build(node):
        if isinstance(node, ast.Expression):
            return build(node.body)
        if isinstance(node, ast.Constant):
            return sp.Integer(node.value) if isinstance(node.value, int) else sp.Float(node.value)
        if isinstance(node, ast.Name):
            return values[node.id]
        if isinstance(node, ast.UnaryOp):
            return -build(node.operand) if isinstance(node.op, ast.USub) else build(node.operand)
        if isinstance(node, ast.BinOp):
            a, b = build(node.left), build(node.right)
            return {ast.Add: lambda: a + b, ast.Sub: lambda: a - b, ast.Mult: lambda: a * b,
                    ast.Div: lambda: a / b, ast.Pow: lambda: a**b}[type(node.op)]()
        return funcs[node.func.id](*(build(a) for a in node.args))

    expr = build(root)
    if expr.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise SceneError(field, f"{_short(text)} is infinite or undefined (e.g. a division by zero or log(0))")
    if expr.has(sp.I):
        raise SceneError(field, f"{_short(text)} has a complex value ({expr})"[:300])
    return expr


def derivatives(field: str, expr, variable: str, order: int, divide=None) -> list:
    """[expr, d/dx expr, ..., d^order/dx^order expr] (each divided by ``divide`` when given, as
    for a change of parameter); SceneError naming ``field`` when one grows beyond
    ``MAX_DERIVED_NODES`` tree nodes — symbolic differentiation of, e.g., a power tower
    grows without bound."""
    import sympy as sp

    x = symbol(variable)
    out = [expr]
    for k in range(1, order + 1):
        d = sp.diff(out[-1], x)
        out.append(d / divide if divide is not None else d)
        size = sum(1 for _ in sp.preorder_traversal(out[-1]))
        if size > MAX_DERIVED_NODES:
            raise SceneError(field, f"derivative {k} of {_short(str(expr))} has {size} terms (at most "
                                    f"{MAX_DERIVED_NODES}); write the expression more simply")
    return out


def check_domain(field: str, expr, variable: str, lo: float, hi: float, samples: int = 2001,
                 unit: str = "", guards: bool = True) -> None:
    """Raise SceneError naming ``field`` and the value of ``variable`` in [lo, hi] where ``expr``
    (sympy, in ``variable`` only) is singular, complex or overflows.

    Dense sampling catches non-finite values; with ``guards`` every sub-expression with
    a restricted domain is checked for a violation between samples (a sign change, or a
    local minimum refined by a bounded search, of its guard function).
    """
    x = symbol(variable)
    grid = np.linspace(lo, hi, samples)
    with np.errstate(all="ignore"):
        values = _evaluate(expr, x, grid)
    bad = ~(np.abs(values) <= MAX_MAGNITUDE)
    if bad.any():
        k = int(np.argmax(bad))
        what = "is undefined or complex" if np.isnan(values[k]) else "is infinite or overflows"
        at = _boundary(expr, x, grid[k - 1], grid[k]) if k else grid[k]
        raise SceneError(field, f"{_short(str(expr))} {what} at {variable} = {at:.6g}"
                                f"{' ' + unit if unit else ''} (domain [{lo:g}, {hi:g}])")
    for guard, what, strict in _guards(expr) if guards else ():
        if x not in guard.free_symbols:
            continue
        where = _violation(guard, x, grid, strict)
        if where is not None:
            raise SceneError(field, f"{what} at {variable} = {where:.6g}{' ' + unit if unit else ''} "
                                    f"(domain [{lo:g}, {hi:g}])")


def _evaluate(expr, x, grid):
    import sympy as sp

    # numpy's real functions give nan for a complex result and inf for a pole.
    f = sp.lambdify([x], expr, modules="numpy")
    return np.broadcast_to(np.asarray(f(grid), dtype=float), grid.shape)


def _boundary(expr, x, good, bad):
    """Where the expression stops being finite between a good and a bad sample (bisection)."""
    import sympy as sp

    f = sp.lambdify([x], expr, modules="numpy")
    with np.errstate(all="ignore"):
        for _ in range(60):
            mid = 0.5 * (good + bad)
            if abs(float(f(mid))) <= MAX_MAGNITUDE:
                good = mid
            else:
                bad = mid
    return bad


def _guards(expr):
    """(guard g(x), message, strict) for every sub-expression whose domain needs g > 0 (strict)
    or g >= 0, or, for denominators, g != 0 (strict=None)."""
    import sympy as sp

    out = []
    for node in sp.preorder_traversal(expr):
        if isinstance(node, sp.Pow):
            base, p = node.args
            if p.is_negative:
                out.append((base, f"division by zero in {_short(str(node))}", None))
            if not p.is_integer:
                out.append((base, f"{_short(str(node))} has a negative base (complex value)", bool(p.is_negative)))
        elif isinstance(node, sp.log):
            out.append((node.args[0], f"log of a non-positive number in {_short(str(node))}", True))
        elif isinstance(node, sp.tan):
            out.append((sp.cos(node.args[0]), f"tan is singular in {_short(str(node))}", None))
        elif isinstance(node, (sp.asin, sp.acos)):
            out.append((1 - node.args[0] ** 2, f"argument outside [-1, 1] in {_short(str(node))}", False))
        elif isinstance(node, sp.acosh):
            out.append((node.args[0] - 1, f"argument below 1 in {_short(str(node))}", False))
        elif isinstance(node, sp.atanh):
            out.append((1 - node.args[0] ** 2, f"argument outside (-1, 1) in {_short(str(node))}", True))
    return out


def _violation(guard, x, grid, strict):
    """First x of ``grid``'s range where ``guard`` violates its condition, else None."""
    import sympy as sp
    from scipy.optimize import brentq, minimize_scalar

    f = sp.lambdify([x], guard, modules="numpy")
    with np.errstate(all="ignore"):
        g = np.broadcast_to(np.asarray(f(grid), dtype=float), grid.shape)
    scale = max(float(np.nanmax(np.abs(g))), 1e-300)
    tiny = 1e-12 * scale
    if strict is None:  # a denominator: no zero, i.e. no sign change and no touching of zero
        hit = np.abs(g) <= tiny
        if hit.any():
            return float(grid[np.argmax(hit)])
        change = np.nonzero(np.sign(g[1:]) != np.sign(g[:-1]))[0]
        if change.size:
            k = change[0]
            return float(brentq(lambda v: float(f(v)), grid[k], grid[k + 1], xtol=1e-14))
        target = np.abs(g)
    else:
        low = g <= tiny if strict else g < -tiny
        if low.any():
            return float(grid[np.argmax(low)])
        target = g
    # A minimum between samples may dip through the bound: refine around each local minimum.
    for k in np.nonzero((target[1:-1] <= target[:-2]) & (target[1:-1] <= target[2:]))[0] + 1:
        res = minimize_scalar(lambda v: float(np.abs(f(v))) if strict is None else float(f(v)),
                              bounds=(grid[k - 1], grid[k + 1]), method="bounded", options={"xatol": 1e-13})
        if (res.fun <= tiny) if strict is not False else (res.fun < -tiny):
            return float(res.x)
    return None


def _short(text: str) -> str:
    text = str(text)
    return repr(text) if len(text) <= 60 else repr(text[:57] + "...")
