"""The declarative scene schema: resolution, defaults, variants and one-line errors naming the field."""
import pytest

from symmech.core import schema as s
from symmech.core.scene import SceneError

BODY = s.Table("the body", {
    "mass": s.Float("mass", unit="kg", lo=0.0, lo_open=True, hi=1e3),
    "axes": s.Vector("semi-axes", n=3, unit="m", lo=0.0, lo_open=True),
    "name": s.Str("name", pattern=r"[a-z]+", default=None),
})
SCENE = s.Table("scene", {
    "kind": s.Str("kind"),
    "body": BODY,
    "steps": s.Int("steps", lo=1, hi=100, default=10),
    "law": s.Choice("impact law", choices=("printed", "coulomb"), default="coulomb"),
    "springs": s.TableList("springs", item=s.Table("spring", {"k": s.Float("stiffness", unit="N/m", lo=0.0)}),
                           default=[]),
    "parameters": s.Mapping("named numbers", value=s.Float("value"), default={}),
    "options": s.Table("options", {"fast": s.Bool("fast", default=False)}, default={}),
}, variants=("law", {"printed": {"e": s.Float("restitution", lo=0.0, hi=1.0)}}))
GOOD = {"kind": "x", "body": {"mass": 1, "axes": [1, 2, 3]}}


def test_resolution_fills_defaults():
    r = s.validate(SCENE, GOOD)
    assert r == {"kind": "x", "body": {"mass": 1.0, "axes": [1.0, 2.0, 3.0], "name": None}, "steps": 10,
                 "law": "coulomb", "springs": [], "parameters": {}, "options": {"fast": False}}
    assert isinstance(r["body"]["mass"], float)


@pytest.mark.parametrize("change, field, words", [
    ({"body": {"mas": 1, "axes": [1, 2, 3]}}, "body.mas", "did you mean 'mass'"),
    ({"body": {"mass": -1, "axes": [1, 2, 3]}}, "body.mass", "(0, 1000] kg"),
    ({"body": {"mass": float("nan"), "axes": [1, 2, 3]}}, "body.mass", "not finite"),
    ({"body": {"mass": 10**400, "axes": [1, 2, 3]}}, "body.mass", "overflows"),
    ({"body": {"mass": True, "axes": [1, 2, 3]}}, "body.mass", "expected a number"),
    ({"body": {"mass": 1, "axes": [1, 2]}}, "body.axes", "list of 3"),
    ({"body": {"mass": 1, "axes": [1, 0, 2]}}, "body.axes[1]", "outside"),
    ({"body": {"mass": 1, "axes": [1, 2, 3], "name": "A1"}}, "body.name", "does not match"),
    ({"steps": 0}, "steps", "outside [1, 100]"),
    ({"steps": 1.5}, "steps", "expected an integer"),
    ({"law": "printd"}, "law", "did you mean 'printed'"),
    ({"law": "printed"}, "e", "missing"),
    ({"e": 0.5}, "e", "unknown field"),
    ({"springs": [{"k": 1}, {"k": -1}]}, "springs[1].k", "outside"),
    ({"springs": {"k": 1}}, "springs", "tables"),
    ({"parameters": {"2x": 1.0}}, "parameters.2x", "identifier"),
    ({"options": {"fast": "yes"}}, "options.fast", "true or false"),
    ({"body": 3}, "body", "expected a table"),
])
def test_errors_name_the_field(change, field, words):
    with pytest.raises(SceneError) as info:
        s.validate(SCENE, {**GOOD, **change})
    assert info.value.field == field
    assert words in str(info.value)
    assert "\n" not in str(info.value)


def test_cross_field_check_runs_on_resolved_values():
    def increasing(t, path):
        if not t["lo"] < t["hi"]:
            raise SceneError(f"{path}.hi", f"{t['hi']} must exceed lo = {t['lo']}")

    table = s.Table("range", {"lo": s.Float("lo", default=0.0), "hi": s.Float("hi")}, checks=(increasing,))
    assert s.validate(table, {"hi": 2}) == {"lo": 0.0, "hi": 2.0}
    with pytest.raises(SceneError, match="must exceed"):
        s.validate(table, {"hi": -1})


def test_markdown_lists_every_field_and_variant():
    text = s.markdown(SCENE)
    for name in ("`kind`", "`steps`", "`e`", "`mass`", "`k`", "[[springs]]"):
        assert name in text
    assert 'when `law = "printed"`' in text


def test_plot_output_validates_names_and_formats():
    out = s.plot_output({"path": "(a)", "phase": "(b)"}, default=("path",))
    assert s.validate(s.Table("scene", {"output": out}), {}) == {"output": {"plots": ["path"], "formats": ["png"]}}
    assert s.validate(out, {"plots": ["phase", "path"], "formats": ["svg", "png"]}) == \
        {"plots": ["phase", "path"], "formats": ["svg", "png"]}
    assert s.validate(out, {"plots": []})["plots"] == []
    for value, message in ((["phsae"], r"'output.plots\[0\]': unknown value 'phsae' \(did you mean 'phase'\?\); "
                                       "choose from path, phase"),
                           (["path", "path"], r"'output.plots\[1\]': 'path' is listed twice"),
                           ("path", r"'output.plots': expected a list of at least 0 of path, phase, got 'path'")):
        with pytest.raises(SceneError, match=message):
            s.validate(s.Table("scene", {"output": out}), {"output": {"plots": value}})
    with pytest.raises(SceneError, match=r"'formats': expected a list of at least 1 of png, svg, got \[\]"):
        s.validate(out, {"formats": []})
    with pytest.raises(SceneError, match=r"'formats\[0\]': unknown value 'pdf'"):
        s.validate(out, {"formats": ["pdf"]})
