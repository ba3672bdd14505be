"""Helpers for the trolley tests: scenes as dicts, validated and prepared like `symmech run`."""
import copy

from symmech.core import pipeline
from symmech.trolley import scene


def setup(**over):
    """A scene dict with sensible defaults, updated section by section from ``over``."""
    data = {
        "kind": "trolley",
        "frame": "twist",
        "track": {"type": "expression", "x": "s", "y": "0", "z": "0"},
        "trolley": {"mass": 100.0, "com": [0.0, 0.0, 0.0], "axle_distance": 2.0, "half_gauge": 1.0},
        "motion": {"speed": "10"},
        "time": {"t_end": 2.0, "steps": 20},
        "effects": {"gravity": True, "local_curvature": False},
    }
    for key, value in over.items():
        if key not in ("track", "motion") and isinstance(value, dict) and isinstance(data.get(key), dict):
            data[key] = {**data[key], **value}
        else:
            data[key] = value
    return data


def prepared(data):
    """The trolley Setup of a scene dict."""
    return pipeline.load(copy.deepcopy(data)).setup


def compute(data, conventions=None):
    st = prepared(data)
    return st, scene.compute(st, conventions)
