"""Brent's root finder and bounded minimiser (scipy's ``brentq`` and ``minimize_scalar(method="bounded")``),
in numba, for any jitted function ``f(x, args) -> float``; :func:`newton`, the safeguarded Newton root finder of
:mod:`symmech.numerics.newton`, for a jitted ``fdf(x, args) -> (f, f')``."""
import math
from types import SimpleNamespace

from symmech.numerics.jit import closure
from symmech.numerics.newton import ITERATIONS, RTOL, bracketed_root

BOUNDED_MAXFUN = 500  # function evaluations of the bounded minimiser at most (scipy's default)


def roots(f) -> SimpleNamespace:
    """Brent's root finder and bounded minimiser of the jitted ``f(x, args) -> float``, compiled on first call:

    - ``brentq(a, b, xtol, args)``: the root in [a, b] (a sign change) to xtol + 4 eps |x| (scipy's ``brentq``);
    - ``bracketed(a, b, fa, fb, xtol, args)``: the same when the caller holds fa = f(a), fb = f(b) already;
    - ``bounded_min(a, b, xatol, args)``: (x, f(x)) minimising f over [a, b] (scipy's
      ``minimize_scalar(method="bounded")``, at most BOUNDED_MAXFUN evaluations)."""

    @closure
    def bracketed(a, b, fa, fb, xtol, args):
        xpre, xcur = a, b
        fpre, fcur = fa, fb
        xblk = fblk = spre = scur = 0.0
        if fpre == 0.0:
            return xpre
        if fcur == 0.0:
            return xcur
        for _ in range(ITERATIONS):
            if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
                xblk, fblk = xpre, fpre
                spre = scur = xcur - xpre
            if abs(fblk) < abs(fcur):
                xpre, xcur, xblk = xcur, xblk, xcur
                fpre, fcur, fblk = fcur, fblk, fcur
            delta = (xtol + RTOL * abs(xcur)) / 2
            sbis = (xblk - xcur) / 2
            if fcur == 0.0 or abs(sbis) < delta:
                return xcur
            if abs(spre) > delta and abs(fcur) < abs(fpre):
                if xpre == xblk:
                    stry = -fcur * (xcur - xpre) / (fcur - fpre)
                else:
                    dpre = (fpre - fcur) / (xpre - xcur)
                    dblk = (fblk - fcur) / (xblk - xcur)
                    stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
                if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                    spre, scur = scur, stry
                else:
                    spre = scur = sbis
            else:
                spre = scur = sbis
            xpre, fpre = xcur, fcur
            xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
            fcur = f(xcur, args)
        return xcur

    @closure
    def brentq(a, b, xtol, args):
        return bracketed(a, b, f(a, args), f(b, args), xtol, args)

    @closure
    def bounded_min(a, b, xatol, args):
        sqrt_eps = math.sqrt(2.2e-16)
        golden_mean = 0.5 * (3.0 - math.sqrt(5.0))
        fulc = a + golden_mean * (b - a)
        nfc, xf = fulc, fulc
        rat = e = 0.0
        fx = f(xf, args)
        num = 1
        ffulc = fnfc = fx
        xm = 0.5 * (a + b)
        tol1 = sqrt_eps * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        while abs(xf - xm) > (tol2 - 0.5 * (b - a)):
            golden = True
            if abs(e) > tol1:  # parabolic fit
                golden = False
                r = (xf - nfc) * (fx - ffulc)
                q = (xf - fulc) * (fx - fnfc)
                pp = (xf - fulc) * q - (xf - nfc) * r
                q = 2.0 * (q - r)
                if q > 0.0:
                    pp = -pp
                q = abs(q)
                r = e
                e = rat
                if abs(pp) < abs(0.5 * q * r) and pp > q * (a - xf) and pp < q * (b - xf):
                    rat = pp / q
                    x = xf + rat
                    if (x - a) < tol2 or (b - x) < tol2:
                        rat = tol1 * (1.0 if xm - xf >= 0 else -1.0)
                else:
                    golden = True
            if golden:
                e = a - xf if xf >= xm else b - xf
                rat = golden_mean * e
            si = 1.0 if rat >= 0 else -1.0
            x = xf + si * max(abs(rat), tol1)
            fu = f(x, args)
            num += 1
            if fu <= fx:
                if x >= xf:
                    a = xf
                else:
                    b = xf
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = xf, fx
                xf, fx = x, fu
            else:
                if x < xf:
                    a = x
                else:
                    b = x
                if fu <= fnfc or nfc == xf:
                    fulc, ffulc = nfc, fnfc
                    nfc, fnfc = x, fu
                elif fu <= ffulc or fulc == xf or fulc == nfc:
                    fulc, ffulc = x, fu
            xm = 0.5 * (a + b)
            tol1 = sqrt_eps * abs(xf) + xatol / 3.0
            tol2 = 2.0 * tol1
            if num >= BOUNDED_MAXFUN:
                break
        return xf, fx

    return SimpleNamespace(brentq=brentq, bracketed=bracketed, bounded_min=bounded_min)


def newton(fdf):
    """:func:`symmech.numerics.newton.bracketed_root` of the jitted ``fdf(x, args) -> (f, f')``, compiled on first
    call: ``newton(fdf)(a, b, fa, fb, xtol, args)``."""
    return closure(bracketed_root(fdf))
