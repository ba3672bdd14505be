"""Newton's root finder safeguarded by a bracket, in plain Python: the Python loop calls it as it is, and
:func:`symmech.numerics.brent.newton` compiles the same function with numba for the compiled loop."""
import sys

# both root finders' (this one's and symmech.numerics.brent's): iterations at most, and the relative part of the
# tolerance, scipy's brentq's
ITERATIONS = 100
RTOL = 4 * sys.float_info.epsilon


def bracketed_root(fdf):
    """The root finder of ``fdf(x, args) -> (f, f')``: ``bracketed_root(fdf)(a, b, fa, fb, xtol, args)`` is a root
    in [a, b], where fa = f(a) and fb = f(b) differ in sign (or one is zero), to xtol + 4 eps |x|.

    Numerical Recipes' ``rtsafe``: a Newton step from the last iterate where it lands inside the bracket and at
    least halves the step before last, else bisection; the first iterate is the secant point of the ends. On a
    simple root it converges quadratically, so its last step leaves an error far below ``xtol``, where Brent's
    method stops within ``xtol``; where the derivative comes with f at little cost it also takes fewer
    evaluations."""

    def bracketed(a, b, fa, fb, xtol, args):
        if fa == 0.0:
            return a
        if fb == 0.0:
            return b
        lo, hi = (a, b) if fa < 0.0 else (b, a)  # f(lo) < 0 < f(hi)
        x = a - fa * (b - a) / (fb - fa)
        step = abs(b - a)
        for _ in range(ITERATIONS):
            fx, dfx = fdf(x, args)
            if fx == 0.0:
                return x
            if fx < 0.0:
                lo = x
            else:
                hi = x
            before = step
            if ((x - hi) * dfx - fx) * ((x - lo) * dfx - fx) >= 0.0 or abs(2.0 * fx) > abs(before * dfx):
                step = 0.5 * (hi - lo)  # Newton's step would leave the bracket or not halve the last: bisect
                x = lo + step
            else:
                step = fx / dfx
                x -= step
            if abs(step) < 0.5 * (xtol + RTOL * abs(x)):
                return x
        return x

    return bracketed
