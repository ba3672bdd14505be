"""The mechanism's expressions (smm/model.py): a user's bad expression is one SymmechError line that names where it
stands, never another exception, and the functions a caller passes are the ones used."""
import pytest

from symmech.core.scene import SymmechError
from symmech.smm import model


def error_of(call):
    """The exception `call()` raises, whatever its type: a test of its type is an assertion, not a crash."""
    with pytest.raises(Exception) as info:
        call()
    return info


def test_a_division_by_zero_names_the_field():
    info = error_of(lambda: model.NumericArith({"a": 0.0})("1/a", "bodies[0].mass"))
    assert info.type is SymmechError
    assert str(info.value).startswith("bodies[0].mass: expression '1/a' cannot be evaluated")


@pytest.mark.parametrize("text", ["foo(1)", "math.sin(1)", "(lambda: 1)()", "1 < 2"])
def test_a_call_of_an_unknown_function_is_an_unsupported_expression(text):
    info = error_of(lambda: model.interpret(text, {}, "points.A"))
    assert info.type is SymmechError
    assert str(info.value) == f"points.A: unsupported expression {text!r}"


def test_evaluate_passes_the_field_on_and_says_expression_when_there_is_none():
    for call, where in [(lambda: model.evaluate("foo(1)", {}, "joints[2].angle"), "joints[2].angle"),
                        (lambda: model.evaluate("1/0", {}), "<expression>"),
                        (lambda: model.NumericArith({})("1/0"), "<expression>")]:
        info = error_of(call)
        assert info.type is SymmechError and str(info.value).startswith(f"{where}: ")


def test_the_functions_a_caller_passes_are_used():
    """smm.derive passes sympy's functions: a name only the caller's table holds is found, and it is the caller's."""
    try:
        value = model.interpret("triple(2) + sin(0)", {}, funcs={"triple": lambda x: 3 * x, "sin": lambda x: 7.0})
    except SymmechError as exc:  # the answer to assert on, not an error of the test
        value = exc
    assert value == 13.0


def test_the_structural_form_names_the_field_of_a_bad_value():
    """structural.values and vectors evaluate each text once and name the field in the message; the values are floats
    in the order of the texts."""
    from symmech.smm import structural

    ar = model.NumericArith({"a": 2.0, "z": 0.0})
    assert structural.values(ar, ["a", "3*a", "a"], "masses").tolist() == [2.0, 6.0, 2.0]
    assert structural.vectors(ar, [["a", "0", "1"], ["1/a", "a", "a**2"]], "com").tolist() == [[2.0, 0.0, 1.0],
                                                                                               [0.5, 2.0, 4.0]]
    info = error_of(lambda: structural.values(ar, ["a", "1/z"], "masses"))
    assert info.type is SymmechError and str(info.value).startswith("masses: expression '1/z' cannot be evaluated")
