"""The plotting style: labelled axes with units, PNG (and SVG when asked), no pyplot, only the
plots a scene asks for, and what each kind's figures show (impact markers, phase portrait,
overloads in g, modes)."""
import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from symmech.cli import main
from symmech.core import plotting

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"


@pytest.fixture
def figures(monkeypatch):
    """Every figure saved during the test, by stem, as it was just before saving."""
    saved = {}
    original = plotting.save

    def save(fig, folder, stem, formats=("png",)):
        saved[stem] = fig
        fig.canvas.draw()  # legends and texts laid out
        return original(fig, folder, stem, formats)

    monkeypatch.setattr(plotting, "save", save)
    return saved


def test_save_writes_png_and_svg(tmp_path):
    fig, axes = plotting.figure()
    axes[0, 0].plot([0, 1], [0, 2])
    plotting.set_labels(axes[0, 0], ("time t", "s"), ("distance", "m"))
    png, svg = plotting.save(fig, tmp_path, "demo", ("png", "svg"))
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert ET.parse(svg).getroot().tag.endswith("svg")


def test_save_refuses_an_axis_without_a_unit(tmp_path):
    fig, axes = plotting.figure(1, 2)
    for ax in axes[0]:
        plotting.set_labels(ax, ("time t", "s"), ("distance", "m"))
    axes[0, 1].set_ylabel("distance")
    with pytest.raises(ValueError, match=r"axes 1 .*y label 'distance'"):
        plotting.save(fig, tmp_path, "bad")
    assert not list(tmp_path.iterdir())


def test_shared_x_is_labelled_once(tmp_path):
    fig, axes = plotting.figure(2, 1, sharex=True)
    for ax in axes[:, 0]:
        ax.set_ylabel(plotting.label("force", "N"))
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    assert plotting.unlabelled(fig) == []
    axes[-1, 0].set_xlabel("time")
    assert len(plotting.unlabelled(fig)) == 2


def test_drawing_needs_no_pyplot_and_leaves_the_backend_alone(tmp_path):
    """Figures are drawn on the Agg canvas: pyplot is never imported and the backend a user
    or a notebook chose (here MPLBACKEND=pdf) is what matplotlib reports afterwards."""
    code = ("import sys; from pathlib import Path; from symmech.core import plotting; import matplotlib; "
            "fig, ax = plotting.figure(); ax[0, 0].plot([0, 1]); "
            "plotting.set_labels(ax[0, 0], ('t', 's'), ('x', 'm')); "
            f"print(len(plotting.save(fig, Path({str(tmp_path)!r}), 'f', ('png', 'svg'))), "
            "'matplotlib.pyplot' in sys.modules, matplotlib.get_backend())")
    env = {k: v for k, v in __import__("os").environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    out = subprocess.run([sys.executable, "-c", code], env={**env, "MPLBACKEND": "pdf"}, capture_output=True,
                         text=True, check=True).stdout
    assert out.split() == ["2", "False", "pdf"]
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_colorbar_names_its_quantity_and_unit(tmp_path):
    fig, axes = plotting.figure()
    mesh = axes[0, 0].pcolormesh([0.0, 1.0], [0.0, 1.0], np.ones((2, 2)))
    plotting.set_labels(axes[0, 0], ("amplitude", "m"), ("angle", "deg"))
    bar = fig.colorbar(mesh, ax=axes[0, 0], label="mean velocity")
    assert plotting.unlabelled(fig) == ["axes 1 (colorbar): label 'mean velocity'"]
    bar.set_label(plotting.label("mean velocity", "m/s"))
    assert plotting.unlabelled(fig) == []
    assert [p.suffix for p in plotting.save(fig, tmp_path, "bar", ("png", "svg"))] == [".png", ".svg"]


SWEEP_PLOTS = """
import numpy as np, matplotlib
from symmech.grain import sweep_report
axes = [("vibration amplitude", "m", False), ("vibration angle", "deg", False)]
values = [np.array([1e-3, 2e-3]), np.array([20.0, 40.0])]
stats = [{"mean_vx": np.array([[0.1, 0.2], [0.3, 0.4]]), "hop_fraction": np.array([[0.0, 0.5], [1.0, 1.0]])}]
charts = sweep_report.charts(["crop"], stats, None)
paths = sweep_report.plots(axes, values, np.array([[0.5, 1.0], [1.5, 2.0]]), charts, [[]] * 4, None,
                           __import__("pathlib").Path(FOLDER))
print(matplotlib.get_backend(), " ".join(sorted(p.name for p in paths)))
"""


def test_sweep_plots_use_the_plotting_style_and_keep_the_backend(tmp_path):
    """The sweep's charts go through plotting.save (PNG, units on every axis and colorbar)
    and leave a user's backend (MPLBACKEND=svg) as it is."""
    clean = {k: v for k, v in __import__("os").environ.items() if k not in ("DISPLAY", "MPLBACKEND", "WAYLAND_DISPLAY")}
    out = subprocess.run([sys.executable, "-c", SWEEP_PLOTS.replace("FOLDER", repr(str(tmp_path)))],
                         env={**clean, "MPLBACKEND": "svg"}, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["svg", "crop_hop_fraction.png", "crop_mean_vx.png"]


def test_draw_builds_only_the_asked_plots_in_the_asked_formats(tmp_path):
    built = []

    def builder(name):
        def build():
            built.append(name)
            fig, axes = plotting.figure()
            plotting.set_labels(axes[0, 0], ("time t", "s"), (name, "m"))
            return fig
        return build

    figures = {name: builder(name) for name in ("a", "b", "c")}
    paths = plotting.draw(figures, {"plots": ["c", "a"], "formats": ["svg"]}, tmp_path)
    assert built == ["c", "a"]
    assert [p.name for p in paths] == ["c.svg", "a.svg"] and sorted(os.listdir(tmp_path)) == ["a.svg", "c.svg"]
    assert plotting.draw({**figures, "b": lambda: None}, {"plots": ["b"], "formats": ["png"]}, tmp_path) == []


def _columns(path: Path, *names: str) -> list[np.ndarray]:
    """Numeric columns of a CSV by name (header cells may carry ``[unit]``; ``#`` lines skipped)."""
    rows = [l.split(",") for l in path.read_text().splitlines() if not l.startswith("#")]
    header = [h.split(" [")[0] for h in rows[0]]
    return [np.array([float(r[header.index(n)]) for r in rows[1:]]) for n in names]


def _lines(ax):
    return [l for l in ax.get_lines() if len(l.get_xdata())]


def test_grain_impacts_are_markers_and_phase_portrait(tmp_path, figures):
    text = re.sub(r"(?m)^duration = .*$", "duration = 0.3", (SCENES / "grain_default.toml").read_text())
    (tmp_path / "g.toml").write_text(text + '[output]\nplots = ["path", "velocity", "phase"]\nformats = ["png", "svg"]\n')
    assert main(["run", str(tmp_path / "g.toml"), "--out", str(tmp_path / "o")]) == 0
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    t_hit, z_hit, vz_before, vz_after = _columns(tmp_path / "o" / "impacts.csv", "t", "z", "vz_before", "vz_after")
    assert summary["bounces"] == len(t_hit) > 3
    for stem in ("path", "velocity", "phase"):
        assert (tmp_path / "o" / f"{stem}.svg").stat().st_size > 0
    ax = figures["velocity"].axes[0]
    # no vertical lines: every drawn line has distinct x values or is a marker series
    assert not any(len(l.get_xdata()) == 2 and l.get_xdata()[0] == l.get_xdata()[1] for l in ax.get_lines())
    markers = [l for l in _lines(ax) if l.get_linestyle() == "None"]
    assert len(markers) == 1
    np.testing.assert_allclose(markers[0].get_xdata(), t_hit, rtol=1e-11)
    np.testing.assert_allclose(markers[0].get_ydata(), vz_after, rtol=1e-9, atol=1e-15)
    phase = figures["phase"].axes[0]
    # heights of a few mm and speeds of a few hundred mm/s, shown in a readable scale (the data stay SI)
    assert phase.get_xlabel() == "relative height z [mm]" and phase.get_ylabel() == "normal velocity v_z [mm/s]"
    assert phase.xaxis.get_major_formatter()(2e-3, 0) == "2"
    trajectory = np.column_stack(_columns(tmp_path / "o" / "trajectory.csv", "z", "vz"))
    np.testing.assert_allclose(_lines(phase)[0].get_xydata(), trajectory, rtol=1e-10, atol=1e-15)
    # each impact is a jump at fixed height from the v_z before to the v_z after (impacts.csv)
    before, after = _lines(phase)[1:]
    np.testing.assert_allclose(before.get_xydata(), np.column_stack([z_hit, vz_before]), rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(after.get_xydata(), np.column_stack([z_hit, vz_after]), rtol=1e-9, atol=1e-15)


def _span(patch):
    """(low, high) data y of an axhspan (a Rectangle from matplotlib 3.9, a Polygon before)."""
    if hasattr(patch, "get_height"):
        return patch.get_y(), patch.get_y() + patch.get_height()
    ys = np.asarray(patch.get_xy())[:, 1]
    return ys.min(), ys.max()


def test_trolley_overloads_in_g_against_the_envelope(tmp_path, figures):
    assert main(["run", str(SCENES / "trolley_helix.toml"), "--out", str(tmp_path)]) == 0
    fig = figures["overloads"]
    n1 = np.column_stack(_columns(tmp_path / "case1_overload.csv", "t", "n1", "n2", "n3"))
    envelope = {"x1": (-2, 2), "x2": (-1.5, 6), "x3": (-2, 2)}  # docs/scenes-trolley.md defaults
    for i, (ax, (axis, (lo, hi))) in enumerate(zip(fig.axes, envelope.items())):
        assert ax.get_ylabel() == f"overload n along {axis} [g]"
        band = [p for p in ax.patches if p.get_label().startswith("comfort envelope")]
        assert len(band) == 1
        assert _span(band[0]) == pytest.approx((lo, hi), abs=1e-12)
        np.testing.assert_allclose(_lines(ax)[0].get_ydata(), n1[:, i + 1], rtol=1e-9)
    assert fig.axes[-1].get_xlabel() == "time t [s]"


def test_mode_shapes_are_titled_by_their_frequencies(tmp_path, figures):
    """One panel a mode (the lowest six), in rows of at most three, each titled by the frequency summary.json
    records and without a legend over the shape."""
    assert main(["run", str(SCENES / "smm_rotor_boom.toml"), "--out", str(tmp_path)]) == 0
    hz = json.loads((tmp_path / "summary.json").read_text())["frequencies_hz"]
    fig = figures["modes"]
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert len(shown) == min(len(hz), 6)
    assert len({round(ax.get_position().y0, 6) for ax in shown}) == math.ceil(len(shown) / 3)
    for i, ax in enumerate(shown):
        assert ax.get_title() == f"mode {i + 1}: f = {hz[i]:.4g} Hz"
        assert ax.get_legend() is None
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [m]", "y [m]")
        assert math.isfinite(hz[i]) and hz[i] > 0


def test_save_refuses_a_legend_over_data(tmp_path):
    """A legend inside the axes hides curves: refused, as an unlabelled axis is; beside or below them it is drawn."""
    fig, axes = plotting.figure()
    axes[0, 0].plot([0, 1], [0, 2], label="a curve")
    plotting.set_labels(axes[0, 0], ("time t", "s"), ("distance", "m"))
    axes[0, 0].legend(loc="upper left")
    with pytest.raises(ValueError, match=r"axes 0 .*legend over the data of axes 0"):
        plotting.save(fig, tmp_path, "bad")
    assert not list(tmp_path.iterdir())
    for place in (plotting.legend_beside, plotting.legend_below):
        place(axes[0, 0])
        fig.tight_layout()
        assert plotting.covering_legends(fig) == []


def test_a_legend_beside_the_left_panel_is_over_the_right_one(tmp_path):
    """Beside is not enough when a neighbour's data are there: the legend of the left of two panels is refused."""
    fig, axes = plotting.figure(1, 2)
    for ax in axes[0]:
        ax.plot([0, 1], [0, 2], label="a curve with a long name to reach the next panel")
        plotting.set_labels(ax, ("time t", "s"), ("distance", "m"))
    plotting.legend_beside(axes[0, 0])
    fig.subplots_adjust(wspace=0.3)
    assert plotting.covering_legends(fig) == ["axes 0 (untitled): legend over the data of axes 1"]


@pytest.mark.parametrize("value, unit, text", [
    (-2.0e-4, "m", "-0.2 mm"), (23337.3, "N", "23.3 kN"), (901.8, "N", "902 N"), (0.068, "m/s", "68 mm/s"),
    (7.0e-5, "rad", "0.07 mrad"), (4.0e-3, "s", "4 ms"), (2.27e-5, "J", "22.7 µJ"), (625.0, "m", "625 m"),
    (4.04, "g", "4.04 g"), (0.45, "1", "0.45"), (3.0e-6, "m^2", "3e-06 m^2"), (0.0, "m", "0 m"),
    (2.0e-3, "m or rad", "0.002 m or rad"), (0.3, "m/s^2", "300 mm/s^2")])
def test_readable_unit_of_a_value(value, unit, text):
    """Lengths stop at mm and angles at mrad; powers of a unit and units without prefixes keep SI."""
    from symmech.core import units

    assert units.format(value, unit) == text


def test_plot_axes_in_a_readable_unit(tmp_path):
    """A roller deflection of 0.2 mm is drawn on an axis in mm (ticks 0.2, not 0.0002); time stays in s,
    a log axis keeps its unit, and the data themselves stay SI."""
    fig, axes = plotting.figure(2, 1, sharex=True)
    axes[0, 0].plot([0.0, 3.0], [0.0, -2.0e-4])
    plotting.set_labels(axes[0, 0], ("time t", "s"), ("roller deflection d", "m"))
    axes[1, 0].loglog([1e-4, 1e-2], [1e-9, 1e-3])
    axes[1, 0].set_ylabel("error [m]")
    axes[1, 0].set_xlabel("time t [s]")
    plotting.save(fig, tmp_path, "d")
    top, bottom = axes[0, 0], axes[1, 0]
    assert top.get_ylabel() == "roller deflection d [mm]" and bottom.get_ylabel() == "error [m]"
    assert bottom.get_xlabel() == "time t [s]"
    assert top.yaxis.get_major_formatter()(-1.5e-4, 0) == "-0.15"
    np.testing.assert_array_equal(top.get_lines()[0].get_ydata(), [0.0, -2.0e-4])


def test_mixed_coordinates_get_one_panel_per_unit(tmp_path, figures):
    """The excavator has slides (m) and angles (rad): its free and frequency responses draw each set in its own
    panel labelled with its own unit, never "m or rad"; every coordinate's curve is in the panel of its type
    (types as the scene file declares them)."""
    import tomllib

    text = (SCENES / "smm_excavator.toml").read_text()
    types = {c["name"]: c["type"] for c in tomllib.loads(text)["coordinates"]}
    scene = tmp_path / "excavator.toml"
    scene.write_text(text + '\n[initial]\nq = [0.001, 0.0, 0.0, 0.0, 0.0]\nduration = 0.5\nsteps = 50\n'
                            '\n[forcing]\nQ = [1.0, 0.0, 0.0, 0.0, 0.0]\nomega = [1.0, 50.0]\nsamples = 20\n'
                            '\n[output]\nplots = ["free_response", "frequency_response"]\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    unit_of = {"slide": ("m", "mm", "µm"), "angle": ("rad", "mrad")}
    for stem in ("free_response", "frequency_response"):
        panels = figures[stem].axes
        assert len(panels) == 2
        for ax in panels:
            names = [line.get_label() for line in ax.get_lines()]
            kinds = {types[n] for n in names}
            assert len(kinds) == 1, (stem, names)
            unit = re.search(r"\[([^\]]+)\]$", ax.get_ylabel()).group(1)
            assert unit in unit_of[kinds.pop()] and " or " not in ax.get_ylabel()
        assert sorted(line.get_label() for ax in panels for line in ax.get_lines()) == sorted(types)


@pytest.mark.parametrize("module, table", [("symmech.trolley.plots", "FIGURES"), ("symmech.smm.plots", "FIGURES"),
                                           ("symmech.grain.plots", "MOTION"), ("symmech.grain.plots", "IMPACT")])
def test_every_plot_caption_is_a_sentence(module, table):
    """The caption of every plot of every kind (the elastic trolley's too, not run by the report tests) is a
    sentence, not a file name: it starts with a capital, has several words and ends with a full stop."""
    import importlib

    for name, caption in getattr(importlib.import_module(module), table).items():
        assert caption[0].isupper() and caption.endswith(".") and len(caption.split()) >= 6, (name, caption)
        assert not re.search(rf"\b{name}\.(png|svg)\b", caption), (name, caption)


def test_campbell_legend_names_beam_planes_in_words():
    """The mode groups of the Campbell diagram read "beam 0, plane 1", not the raw id ``beam0_plane1``."""
    from symmech.trolley import plots

    modes = {"label": [["beam0_plane1_mode1", "beam0_plane2_mode1", "roller_1"]], "s": np.array([0.0, 1.0]),
             "V0": np.array([1.0, 2.0]), "f": np.array([[10.0, 20.0, 30.0], [10.0, 20.0, 30.0]]),
             "forcing": np.ones((2, 3))}
    fig = plots.campbell(modes)
    texts = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert texts[:3] == ["beam 0, plane 1", "beam 0, plane 2", "rollers"]
    assert not any("_plane" in t for t in texts)


def test_a_large_plane_writes_each_limit_once_a_small_one_in_every_cell():
    """20 x 20 cells cannot hold 'lift-off' each (the bundled elastic sweep wrote 180 overlapping labels): a plane
    larger than LABELLED_CELLS per axis names each limit once, on the cell of its points nearest their middle; a
    3 x 3 plane labels every limited cell."""
    from symmech.core import sweep as core_sweep

    big = [("lift-off" if i >= 12 else "") for i in range(20) for _ in range(20)]  # x-major: the last 8 columns
    big[0] = "comfort"
    fig, axes = plotting.figure()
    xs, ys = np.arange(20.0), np.arange(20.0)
    core_sweep.cell_labels(axes[0, 0], xs, ys, big, (20, 20))
    placed = {t.get_text(): t.xy for t in axes[0, 0].texts}
    assert placed.keys() == {"lift-off", "comfort"} and placed["comfort"] == (0.0, 0.0)
    x, y = placed["lift-off"]
    assert x in (15.0, 16.0) and y in (9.0, 10.0)  # the middle of columns 12-19, rows 0-19
    fig, axes = plotting.figure()
    small = ["", "hops", "", "too slow", "", "", "hops", "", "hops, too slow"]
    core_sweep.cell_labels(axes[0, 0], np.arange(3.0), np.arange(3.0), small, (3, 3))
    assert [(t.get_text(), t.xy) for t in axes[0, 0].texts] == [
        ("hops", (0.0, 1.0)), ("too slow", (1.0, 0.0)), ("hops", (2.0, 0.0)), ("hops\ntoo slow", (2.0, 2.0))]


def test_a_colour_bar_is_in_a_readable_unit():
    """Roller deflections of 0.1 to 0.5 mm coloured on a bar read 0.1 ... 0.5 [mm], not 0.0001 ... 0.0005 [m]."""
    fig, axes = plotting.figure()
    mesh = axes[0, 0].pcolormesh(np.arange(4.0), np.arange(3.0), np.array([[1e-4, 2e-4, 3e-4], [4e-4, 5e-4, 1e-4]]))
    fig.colorbar(mesh, ax=axes[0, 0], label=plotting.label("largest roller deflection", "m"))
    plotting.set_labels(axes[0, 0], ("speed scale", "1"), ("roller stiffness", "N/m"))
    plotting.readable_units(fig)
    bar = fig.axes[1]
    assert bar.get_ylabel() == "largest roller deflection [mm]"
    assert bar.yaxis.get_major_formatter()(2e-4, 0) == "0.2"


def test_campbell_leaves_out_forcing_far_below_every_mode():
    """Modes at 10-30 Hz are drawn down to 10/20 = 0.5 Hz: a forcing at 0.1 Hz would be a legend entry with no
    line in sight, so it is neither drawn nor listed; one at 5 Hz is both."""
    from symmech.trolley import plots
    from symmech.trolley.elastic.body import FORCING

    modes = {"label": [["beam0_plane1_mode1", "roller_1"]], "s": np.array([0.0, 1.0]), "V0": np.array([1.0, 2.0]),
             "f": np.array([[10.0, 30.0], [10.0, 30.0]]), "forcing": np.array([[5.0, 0.1, 0.1], [6.0, 0.1, 0.1]])}
    fig = plots.campbell(modes)
    texts = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert texts == ["beam 0, plane 1", "rollers", FORCING[0][1]]
    assert all(len(ax.get_lines()) == 3 for ax in fig.axes)
