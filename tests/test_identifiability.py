"""Structural identifiability: verdicts on textbook cases and the shipped models, each
claim checked against the transfer function itself (the values said to be
indistinguishable give the same one; those said to differ do not)."""

from __future__ import annotations

import doctest
import json
import re
from pathlib import Path

import numpy as np
import pytest
import sympy

import mtt
from mtt.cli.main import EXIT_MODEL_ERROR, EXIT_OK, main
from mtt.derivation.identifiability import expression_text

ROOT = Path(__file__).resolve().parent.parent
CASES = Path(__file__).resolve().parent / "data" / "identifiability"
r1, r2, k, r, c, km, jl, jm = sympy.symbols("r1 r2 k r c km jl jm")


def run(capsys, *argv) -> tuple[int, str, str]:
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def normalised(model: mtt.Model, values: dict) -> np.ndarray:
    """The transfer function's coefficients at `values`, scaled so the denominator's
    highest coefficient is 1: equal arrays, equal transfer functions."""
    num, den = model.transfer_function.at(**{n: float(v) for n, v in values.items()})
    return np.concatenate([num, den]) / den[0]


def assert_same_transfer_function(model: mtt.Model, a: dict, b: dict) -> None:
    np.testing.assert_allclose(normalised(model, a), normalised(model, b), rtol=1e-9)


@pytest.mark.parametrize(
    ("name", "options"),
    [("absorber", {}), ("absorber", {"keep": "tau,l"}), ("absorber_stages", {}),
     ("dc_drive", {}), ("dc_motor", {}), ("rlc", {}), ("rlc3", {})],
)  # fmt: skip
def test_the_shipped_models_are_globally_identifiable(name, options):
    model = mtt.load(mtt.example(name), **options)
    result = model.identifiability()
    assert (result.verdict, result.solutions) == ("global", 1)
    assert result.identified == model.unknowns
    assert result.rank == len(model.unknowns)


def test_the_series_rlc_circuit_determines_r_l_and_c():
    """i/v = c s / (l c s^2 + r c s + 1): the ratios give c, r c and l c."""
    model = mtt.load(mtt.example("rlc3"))
    assert model.identifiability().verdict == "global"
    base = {"r": 2, "l": 0.5, "c": 0.1}
    for name in base:
        other = dict(base, **{name: base[name] * 1.1})
        assert not np.allclose(normalised(model, base), normalised(model, other))


def test_an_rc_ladder_has_two_solutions_swapping_its_time_constants():
    """1/(r1 r2 s^2 + (2 r1 + r2) s + 1) with unit capacitances: (r1, r2) and (r2/2, 2 r1)."""
    model = mtt.load(CASES / "ladder.bg")
    result = model.identifiability()
    assert (result.verdict, result.solutions, result.rank) == ("local", 2, 2)
    assert result.maps == ({"r1": r1, "r2": r2}, {"r1": r2 / 2, "r2": 2 * r1})
    assert result.point == {"r1": 1, "r2": 3}
    assert result.points == ({"r1": 1, "r2": 3}, {"r1": sympy.Rational(3, 2), "r2": 2})
    assert (result.real, result.positive) == (2, 2)
    assert set(result.combinations) == {r1 * r2, 2 * r1 + r2}
    assert result.identified == ()
    assert_same_transfer_function(model, {"r1": 1, "r2": 3}, {"r1": 1.5, "r2": 2})
    assert_same_transfer_function(model, {"r1": 0.7, "r2": 5}, {"r1": 2.5, "r2": 1.4})


def test_a_gyrator_modulus_is_known_up_to_its_sign():
    model = mtt.load(CASES / "gyrator.bg")
    result = model.identifiability()
    assert (result.verdict, result.solutions) == ("local", 2)
    assert result.maps == ({"k": k}, {"k": -k})
    assert result.points == ({"k": 2}, {"k": -2})
    assert (result.real, result.positive) == (2, 1)
    assert result.combinations == (k**2,)
    assert_same_transfer_function(model, {"k": 2}, {"k": -2})


def test_an_rc_filter_determines_only_the_product_rc():
    model = mtt.load(CASES / "rc.bg")
    result = model.identifiability()
    assert (result.verdict, result.solutions, result.rank) == ("none", None, 1)
    assert result.combinations == (r * c,)
    assert result.identified == ()
    assert_same_transfer_function(model, {"r": 1000, "c": 1e-6}, {"r": 500, "c": 2e-6})


def test_two_resistors_in_series_determine_only_their_sum():
    model = mtt.load(CASES / "series_resistors.bg")
    result = model.identifiability()
    assert (result.verdict, result.rank, result.combinations) == ("none", 1, (r1 + r2,))
    assert_same_transfer_function(model, {"r1": 1, "r2": 2}, {"r1": 2.5, "r2": 0.5})
    with_l = mtt.load(CASES / "series_resistors.bg", unknowns="r1,r2,l").identifiability()
    assert (with_l.verdict, with_l.rank, with_l.identified) == ("none", 2, ("l",))
    assert set(with_l.combinations) == {sympy.Symbol("l"), r1 + r2}


def test_inertias_on_one_shaft_determine_only_their_sum():
    model = mtt.load(mtt.example("dc_motor"), unknowns="jm,jl")
    result = model.identifiability()
    assert (result.verdict, result.combinations) == ("none", (jl + jm,))
    assert_same_transfer_function(model, {"jm": 1, "jl": 10}, {"jm": 4, "jl": 7})


def test_the_dc_drive_with_every_parameter_unknown_has_a_scaling_symmetry():
    """km, k ra, ia k, jm/k and ks/k: scaling k by a, ra and ia by 1/a, jm and ks by a
    leaves the transfer function as it is."""
    names = "ra,ia,jm,km,ks,k"
    model = mtt.load(mtt.example("dc_drive"), unknowns=names)
    result = model.identifiability()
    assert (result.verdict, result.rank, result.identified) == ("none", 5, ("km",))
    assert {expression_text(h) for h in result.combinations} == {
        "km", "k*ra", "ia*k", "jm/k", "ks/k"
    }  # fmt: skip
    base = {"ra": 1, "ia": 0.1, "jm": 1, "km": 1, "ks": 1, "k": 10}
    a = 3.0
    scaled = dict(base, ra=1 / a, ia=0.1 / a, jm=a, ks=a, k=10 * a)
    assert_same_transfer_function(model, base, scaled)
    assert not np.allclose(normalised(model, base), normalised(model, dict(base, km=2)))


def test_the_dc_motor_with_its_constant_unknown_has_algebraic_solutions():
    """Three values give each transfer function; only the true values are rational in
    them; at the model's values all three are real, and two positive."""
    model = mtt.load(mtt.example("dc_motor"), unknowns="ra,jl,km")
    result = model.identifiability()
    assert (result.verdict, result.solutions) == ("local", 3)
    assert result.maps == ({"ra": sympy.Symbol("ra"), "jl": jl, "km": km},)
    assert result.point == {"ra": 1, "jl": 10, "km": 1}
    assert (len(result.points), result.real, result.positive) == (3, 3, 2)
    for point in result.points[1:]:
        assert_same_transfer_function(model, result.point, point)


def test_the_absorber_cannot_tell_k_from_1_over_k_with_tau_and_l_unknown():
    """(tau, l, k) and (tau/k, l/k^3, 1/k) (docs/identifiability.md), checked here on the
    transfer function alone, without the identifiability stage."""
    model = mtt.load(mtt.example("absorber"), unknowns="tau,l,k")
    for tau, flow, k_ in ((2, 0.5, 0.72), (1.3, 2.0, 2.5)):
        other = {"tau": tau / k_, "l": flow / k_**3, "k": 1 / k_}
        assert_same_transfer_function(model, {"tau": tau, "l": flow, "k": k_}, other)
    assert not np.allclose(
        normalised(model, {"tau": 2, "l": 0.5, "k": 0.72}),
        normalised(model, {"tau": 2, "l": 0.5, "k": 1 / 0.72}),
    )


def test_an_unknown_that_cancels_out_is_determined_in_no_way():
    """Two transformers of moduli k and 1/k: the load sees r whatever k."""
    model = mtt.load("model cancel\nunknown k = 2\nparam r = 3\nSe:v -> 1:a\n"
                     "1:a -> TF:t1(k) -> 1:b\n1:b -> TF:t2(1/k) -> R:r\n1:a -> Df:i\n")  # fmt: skip
    result = model.identifiability()
    assert (result.verdict, result.rank, result.combinations) == ("none", 0, ())


def test_identifiability_prints_the_solutions_and_combinations(capsys):
    status, out, err = run(capsys, "identifiability", CASES / "ladder.bg")
    assert (status, err) == (EXIT_OK, "")
    assert out.splitlines() == [
        "model ladder: from Se:v to De:y; unknowns r1, r2",
        "locally identifiable: for generic true values (r1, r2), 2 values give the same "
        "transfer function:",
        "  (r1, r2)",
        "  (r2/2, 2*r1)",
        "for the model's values (r1, r2) = (1, 3) they are (2 real, 2 positive):",
        "  (1, 3)",
        "  (3/2, 2)",
        "the data determine: r1*r2, 2*r1 + r2",
        "identified on their own: none",
    ]
    status, out, _ = run(capsys, "identifiability", CASES / "rc.bg")
    assert out.splitlines()[1:] == [
        "not identifiable: for generic true values, a 1-parameter family of values of "
        "(r, c) gives the same transfer function",
        "the data determine: c*r",
        "identified on their own: none",
    ]


def test_identifiability_json(capsys):
    status, out, _ = run(capsys, "identifiability", CASES / "ladder.bg", "--json")
    record = json.loads(out)
    assert status == EXIT_OK
    assert record == {
        "ok": True, "model": "ladder", "input": "Se:v", "output": "De:y",
        "unknowns": ["r1", "r2"], "verdict": "local", "rank": 2, "solutions": 2,
        "identified": [], "combinations": ["r1*r2", "2*r1 + r2"],
        "maps": [{"r1": "r1", "r2": "r2"}, {"r1": "r2/2", "r2": "2*r1"}],
        "point": {"r1": "1", "r2": "3"},
        "points": [{"r1": "1", "r2": "3"}, {"r1": "3/2", "r2": "2"}],
        "real": 2, "positive": 2,
    }  # fmt: skip
    _, out, _ = run(capsys, "identifiability", ROOT / "models" / "rlc3.bg", "--json")
    record = json.loads(out)
    assert (record["verdict"], record["solutions"], record["combinations"]) == (
        "global", 1, ["r", "l", "c"]
    )  # fmt: skip
    _, out, _ = run(capsys, "identifiability", CASES / "series_resistors.bg", "--json")
    record = json.loads(out)
    assert (record["verdict"], record["solutions"], record["combinations"]) == (
        "none", None, ["r1 + r2"]
    )  # fmt: skip
    _, out, _ = run(capsys, "identifiability", ROOT / "models" / "dc_motor.bg", "--json",
                    "--unknown", "ra,jl,km")  # fmt: skip
    points = json.loads(out)["points"]
    assert points[0] == {"ra": "1", "jl": "10", "km": "1"}
    assert float(points[2]["ra"]) == pytest.approx(0.991733999516112, rel=1e-12)


def test_identifiability_takes_the_model_options(capsys):
    rlc3 = ROOT / "models" / "rlc3.bg"
    status, out, _ = run(capsys, "identifiability", rlc3, "--unknown", "r,c", "--set", "l=2")
    assert status == EXIT_OK
    assert out.splitlines()[0] == "model rlc3: from Se:v to Df:i; unknowns r, c"
    status, _, err = run(capsys, "identifiability", ROOT / "models" / "rlc.bg", "--unknown", "q")
    assert status == EXIT_MODEL_ERROR and "error[undeclared_parameter]" in err


def test_identifiability_of_a_model_without_unknown_is_an_error(capsys, tmp_path):
    path = tmp_path / "known.bg"
    path.write_text((ROOT / "models" / "rlc.bg").read_text().replace("unknown c", "param c"))
    status, out, err = run(capsys, "identifiability", path, "--json")
    assert status == EXIT_MODEL_ERROR
    assert json.loads(out)["ok"] is False and "error[no_unknown]" in err


def test_check_identifiability_warns_about_unknowns_not_globally_identifiable(capsys):
    files = (CASES / "rc.bg", CASES / "gyrator.bg", ROOT / "models" / "rlc3.bg")
    status, out, err = run(capsys, "check", *files)
    assert (status, err) == (EXIT_OK, "")  # structure only, by default: no algebra
    status, out, err = run(capsys, "check", "--identifiability", *files)
    assert status == EXIT_OK  # a warning does not fail a check
    assert len(out.splitlines()) == 3
    assert err.splitlines() == [
        f"{CASES / 'rc.bg'}:4:9: warning[not_identifiable]: r, c cannot be identified: a "
        "continuum of values gives the same transfer function; the data determine c*r "
        "(see mtt identifiability)",
        ' 4 | unknown r = 1000 "resistance [ohm]"',
        "   |         ^",
        f"{CASES / 'gyrator.bg'}:5:9: warning[not_identifiable]: k is only locally "
        "identifiable: k and -k give the same transfer function (see mtt identifiability)",
        ' 5 | unknown k = 2 "gyrator modulus"',
        "   |         ^",
    ]
    _, out, _ = run(capsys, "check", "--json", "--identifiability", CASES / "series_resistors.bg")
    (warning,) = json.loads(out)["files"][0]["warnings"]
    assert (warning["kind"], warning["line"], warning["column"]) == ("not_identifiable", 5, 9)
    _, out, _ = run(capsys, "check", "--json", "--identifiability",
                    CASES / "series_resistors.bg", "--unknown", "r1")  # fmt: skip
    assert json.loads(out)["files"][0]["warnings"] == []


def test_compile_warns_about_an_unknown_that_is_only_locally_identifiable(capsys, tmp_path):
    status, out, err = run(capsys, "compile", CASES / "gyrator.bg", "-o", tmp_path)
    assert status == EXIT_OK and out.startswith("wrote ")
    assert "warning[not_identifiable]: k is only locally identifiable" in err
    status, _, err = run(capsys, "compile", ROOT / "models" / "rlc.bg", "-o", tmp_path)
    assert (status, err) == (EXIT_OK, "")


def test_a_coefficient_not_rational_in_a_kept_parameter_is_a_message(capsys, tmp_path):
    """2^z with z kept symbolic (no value), or sqrt(5): identifiability cannot decide, and says
    so (both were internal errors of compile, found by tests/test_fuzz.py)."""
    model = tmp_path / "powered.bg"
    model.write_text("model powered\nunknown k = 3\nparam z\nSe:u -> 1:a\n1:a -> R:k\n"
                     "1:a -> I:m(2 ^ z)\n1:a -> Df:y\n")  # fmt: skip
    status, _, err = run(capsys, "identifiability", model)
    assert status == EXIT_MODEL_ERROR and "error[unsupported_theta]: a coefficient" in err
    assert "2**z, is not a rational function" in err
    status, _, err = run(capsys, "compile", model, "-o", tmp_path)
    assert status == EXIT_MODEL_ERROR and "error[unsupported_theta]: the Theta entry 2**z" in err
    surd = tmp_path / "surd.bg"  # an irrational constant: the algebra is over Q
    surd.write_text("model surd\nunknown k = 3\nSe:u -> 1:a\n1:a -> R:k\n1:a -> I:m(sqrt(5))\n"
                    "1:a -> Df:y\n")  # fmt: skip
    status, _, err = run(capsys, "identifiability", surd)
    assert status == EXIT_MODEL_ERROR and "hold an irrational constant (such as sqrt(5))" in err
    status, _, err = run(capsys, "compile", surd, "-o", tmp_path)
    assert status == EXIT_OK and err == ""  # compile goes on, without the warning


def test_the_commands_in_the_docs_print_what_the_docs_show(capsys, monkeypatch):
    """Each `$ mtt ...` in docs/identifiability.md, run here: standard error (the
    warnings come first), then standard output."""
    monkeypatch.chdir(ROOT)
    text = (ROOT / "docs" / "identifiability.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```\n\$ mtt (.*?)\n(.*?)```", text, re.DOTALL)
    assert len(blocks) >= 8
    for command, shown in blocks:
        status, out, err = run(capsys, *command.split())
        assert status == EXIT_OK, command
        assert err + out == shown, command
    results = doctest.testfile(str(ROOT / "docs" / "identifiability.md"),
                               module_relative=False, optionflags=doctest.ELLIPSIS)  # fmt: skip
    assert (results.attempted, results.failed) == (4, 0)
