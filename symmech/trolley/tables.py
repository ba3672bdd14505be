"""Tables 1 and 2 of the trolley paper (seed 002), transcribed by hand.

Helix example: R = 7 m, λ = 5/2π m, V0(t) = 3t + 7 sin(t/2) m/s, a = 1 m, l = 2 m,
m = 100 kg, r = [1, 0.5, 0] m, t ∈ [0, 20] s in 5000 steps. Case 1 without, case 2
with the local curvature between the axles. Values are moving-frame components.

Each entry is (value, decimals printed). The OCR shows Table 1, V3, case 1 at
t = 5 s as "8.017·3"; the same entry at t = 10 and 15 s reads 8.017·10⁻³, and the
constant V3 = ϰ r1 / 2 of case 1 confirms 8.017·10⁻³.
"""
from __future__ import annotations

import math

TIMES = (5.0, 10.0, 15.0)

# The example as a trolley scene (the bundled scenes/trolley_helix*.toml hold the same).
PAPER_EXAMPLE = {
    "kind": "trolley", "conventions": "paper", "frame": "frenet",
    "track": {"type": "helix", "radius": 7.0, "rise": 5 / (2 * math.pi)},
    "trolley": {"mass": 100.0, "com": [1.0, 0.5, 0.0], "axle_distance": 2.0, "half_gauge": 1.0},
    "constants": {"g0": 9.81},
    "motion": {"speed": "3*t + 7*sin(t/2)"},
    "time": {"t_end": 20.0, "steps": 5000},
    "effects": {"gravity": True, "local_curvature": True},
}

# Table 1: kinematic parameters; quantity -> case -> values at TIMES.
TABLE1 = {
    "V1": {1: ((19.119, 3), (23.217, 3), (51.495, 3)), 2: ((18.928, 3), (22.985, 3), (50.981, 3))},
    "V2": {1: ((0.141, 3), (0.141, 3), (0.141, 3)), 2: ((-0.239, 3), (-0.321, 3), (-0.879, 3))},
    "V3": {1: ((8.017e-3, 6), (8.017e-3, 6), (8.017e-3, 6)), 2: ((0.048, 3), (0.044, 3), (-0.058, 3))},
    "a1": {1: ((0.176, 3), (3.973, 3), (4.193, 3)), 2: ((0.227, 3), (3.998, 3), (4.293, 3))},
    "a2": {1: ((2.696, 3), (3.274, 3), (7.263, 3)), 2: ((2.639, 3), (3.131, 3), (7.036, 3))},
    "a3": {1: ((2.261e-3, 6), (2.261e-3, 6), (2.261e-3, 6)), 2: ((0.049, 3), (-0.112, 3), (-0.693, 3))},
}

# Table 2: reactions of the trolley [N]; quantity -> case -> values at TIMES.
TABLE2 = {
    "P1": {1: ((-134.335, 3), (223.449, 3), (494.055, 3)), 2: ((-129.267, 3), (221.546, 3), (469.680, 3))},
    "P2": {1: ((-182.455, 3), (181.821, 3), (520.960, 3)), 2: ((-178.614, 3), (186.080, 3), (530.626, 3))},
    "P3": {1: ((96.693, 3), (571.804, 3), (567.684, 3)), 2: ((103.757, 3), (562.907, 3), (541.930, 3))},
    "P4": {1: ((48.120, 3), (41.628, 3), (-26.905, 3)), 2: ((49.348, 3), (35.466, 3), (-60.946, 3))},
    "P5": {1: ((48.120, 3), (41.628, 3), (-26.905, 3)), 2: ((49.348, 3), (35.466, 3), (-60.946, 3))},
    "P0": {1: ((-826.967, 3), (-333.068, 3), (894.662, 3)), 2: ((-826.967, 3), (-310.563, 3), (916.751, 3))},
}


def entries():
    """Every printed entry as (table, quantity, case, time [s], value, decimals)."""
    out = []
    for name, table in (("Table 1", TABLE1), ("Table 2", TABLE2)):
        for quantity, cases in table.items():
            for case, values in cases.items():
                for time, (value, decimals) in zip(TIMES, values):
                    out.append((name, quantity, case, time, value, decimals))
    return out
