"""Long tables in xarray's own shape: a table that declares its grid (one row per instant and mode, one per
point of a swept plane) becomes a Dataset over those dimensions, its key columns the coordinates and its text
columns coordinates over them, so that ``ds.f.sel(mode=1)`` picks a mode."""
import numpy as np
import pytest

from symmech.core.results import Column, Result, Table
from symmech.trolley.elastic import scene as elastic_scene
from symmech.trolley.elastic.body import FORCING


def modes(n_s=3, n=2, names=("tip",)):
    """A modes record of n_s samples and n modes: f = 10 sample + mode number [Hz], every other entry distinct."""
    k = np.arange(n_s)[:, None] + 0.0
    m = np.arange(1, n + 1)[None, :] + 0.0
    record = {"t": 0.5 * np.arange(n_s), "s": 2.0 + np.arange(n_s), "V0": 3.0 + np.arange(n_s),
              "f": 10 * k + m, "zeta": 0.01 * (10 * k + m), "shape": np.zeros((n_s, n, len(names), 3)),
              "forcing": 100.0 + np.arange(n_s * len(FORCING)).reshape(n_s, len(FORCING)),
              "label": [[f"beam {j} at sample {i}" for j in range(1, n + 1)] for i in range(n_s)]}
    for key, _, _ in elastic_scene.MODE_KEYS:
        record[key] = 1000 * k + m
    return record


def test_the_modes_table_is_a_dataset_over_time_and_mode():
    table = elastic_scene._modes_table(modes(), ["tip"])
    ds = table.to_xarray()
    assert ds.f.dims == ("t", "mode") and ds.sizes == {"t": 3, "mode": 2}
    assert ds.t.values.tolist() == [0.0, 0.5, 1.0] and ds.mode.values.tolist() == [1.0, 2.0]
    assert ds.f.sel(mode=1).values.tolist() == [1.0, 11.0, 21.0]  # f = 10 sample + mode
    assert ds.f.sel(mode=2, t=0.5).item() == 12.0
    assert ds.zeta.attrs == {"units": "1", "long_name": "damping ratio"} and ds.mode.attrs["units"] == "1"
    assert ds.component.dims == ("t", "mode") and ds.component.sel(mode=2, t=1.0).item() == "beam 2 at sample 2"
    assert ds.s.sel(mode=2).values.tolist() == [2.0, 3.0, 4.0]  # per sample, repeated over the modes
    assert "mode_id" not in ds  # it is the mode coordinate


def test_a_result_hands_out_its_long_table_in_the_same_shape():
    result = Result("probe", {}, {"modes": elastic_scene._modes_table(modes(n_s=2, n=3), ["tip"])})
    ds = result.to_xarray("modes")
    assert ds.f.shape == (2, 3) and ds.attrs["table"] == "modes"
    assert ds.f.sel(mode=3).values.tolist() == [3.0, 13.0]


def grid_table(x, y):
    X, Y = np.meshgrid(x, y, indexing="ij")
    cols = (Column("x", "m"), Column("y", "N"), Column("z", "J", "x y"))
    return Table(cols, np.column_stack([X.ravel(), Y.ravel(), (X * Y).ravel()]), grid={"x": "x", "y": "y"})


def test_a_swept_plane_keeps_the_order_of_its_axes():
    ds = grid_table([3.0, 1.0], [5.0, 7.0, 6.0]).to_xarray()  # axes as swept, not sorted
    assert ds.x.values.tolist() == [3.0, 1.0] and ds.y.values.tolist() == [5.0, 7.0, 6.0]
    assert ds.z.sel(x=1.0).values.tolist() == [5.0, 7.0, 6.0] and ds.z.attrs["units"] == "J"
    assert grid_table([3.0, 1.0], [5.0]).to_xarray(index=False).z.dims == ("row",)  # the rows, on request


def test_rows_that_are_not_the_declared_grid_are_refused():
    good = grid_table([1.0, 2.0], [5.0, 6.0])
    swapped = Table(good.columns, good.data[[0, 2, 1, 3]], grid=good.grid)  # y-major
    with pytest.raises(ValueError, match=r"not the grid \{'x': 2, 'y': 2\} over x, y in row-major order"):
        swapped.to_xarray()
    with pytest.raises(ValueError, match="not the grid"):
        Table(good.columns, good.data[:3], grid=good.grid).to_xarray()  # a point missing
