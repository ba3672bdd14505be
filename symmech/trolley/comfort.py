"""The comfort envelope of the overloads: its default and the one warning text of leaving it (rigid cases and
the elastic model's report points alike)."""

# Default comfort envelope [g] per body axis (tangential, normal, lateral).
COMFORT = {"x1": (-2.0, 2.0), "x2": (-1.5, 6.0), "x3": (-2.0, 2.0)}


def comfort_warning(subject: str, axis: str, envelope, t: float) -> str:
    """The warning of an overload leaving the comfort envelope (lo, hi) [g] along ``axis``, first at t [s]."""
    lo, hi = envelope
    return f"{subject} along {axis} leaves the comfort envelope [{lo:g}, {hi:g}] g from t = {t:.4g} s"
