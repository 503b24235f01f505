"""Generation of the estimator modules: committed bytes, names, numbers, safety, standalone use."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy

from mtt import files
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import theta_for
from mtt.derivation.theta import Theta
from mtt.estimator import codegen
from mtt.language.diagnostics import ModelError

ROOT = Path(__file__).resolve().parent.parent
k, s, tau, l = sympy.symbols("k s tau l")  # noqa: E741 - the paper's names

# The committed modules and the `mtt compile` options they are made with (see the Makefile).
COMMITTED = {"dc_drive": (), "absorber": ("tau", "l"), "rlc": ()}


def dc_drive_theta(**changes) -> Theta:
    """Theta of the DC drive as method.md section 5.1 states it, made by hand."""
    matrix = [[10, 0], [10, 10], [1, 11], [0, 10], [0, 1], [-10, 0], [0, 0], [0, -10]]
    theta = Theta(
        model="dc_drive",
        description="voltage-driven DC motor with a flexible shaft",
        source_name="dc_drive.bg",
        input="Se:v",
        output="Df:vm",
        unknowns=("k",),
        symbols=(),
        defaults={},
        assumed={"ra": sympy.Integer(1), "ia": sympy.Rational(1, 10)},
        true_values={"k": sympy.Integer(10)},
        num=10 * k * s**2 + 10,
        den=k * s**4 + 10 * k * s**3 + (11 * k + 1) * s**2 + (10 * k + 10) * s + 10,
        n=4,
        m=2,
        monomials=((0,), (1,)),
        matrix=sympy.Matrix(matrix),
    )
    return dataclasses.replace(theta, **changes)


def absorber_theta(**changes) -> Theta:
    """Theta of the absorber, eq. (27), with tau and l kept symbolic."""
    matrix = [
        [l, l, l, l],
        [3 * l * tau, 4 * l * tau, 3 * l * tau, 0],
        [3 * l * tau**2, 3 * l * tau**2, 0, 0],
        [l * tau**3, 0, 0, 0],
        [0, 0, 0, -1],
    ]
    theta = Theta(
        model="absorber",
        description="three-stage absorber",
        source_name="absorber.bg",
        input="Sf:feed",
        output="De:x_l",
        unknowns=("k",),
        symbols=("tau", "l"),
        defaults={"tau": sympy.Integer(2), "l": sympy.Rational(1, 2)},
        assumed={},
        true_values={"k": sympy.Rational(18, 25)},
        num=k**3,
        den=l * ((k + s * tau + 1) * (3 * s * tau + 1) * k + (s * tau + 1) ** 3 + k**3),
        n=3,
        m=0,
        monomials=((0,), (1,), (2,), (3,)),
        matrix=sympy.Matrix(matrix),
    )
    return dataclasses.replace(theta, **changes)


@pytest.mark.parametrize("model", sorted(COMMITTED))
def test_committed_modules_are_what_mtt_generates(model, monkeypatch):
    monkeypatch.chdir(ROOT)  # the source is named as the Makefile names it
    theta = theta_for(f"models/{model}.bg", ParameterChoice(keep=frozenset(COMMITTED[model])))
    assert codegen.render(theta) == (ROOT / "generated" / f"{model}.py").read_text("utf-8")


def test_generation_does_not_depend_on_hash_seeds():
    program = (
        "import sys; from mtt.estimator import codegen; "
        "from mtt.derivation.parameters import ParameterChoice; "
        "from mtt.derivation.pipeline import theta_for; "
        "choice = ParameterChoice(keep=frozenset({'tau', 'l'})); "
        "sys.stdout.write(codegen.render(theta_for('models/absorber.bg', choice)))"
    )
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    done = subprocess.run(
        [sys.executable, "-c", program], cwd=ROOT, env=env, capture_output=True, text=True
    )
    assert done.stdout == (ROOT / "generated" / "absorber.py").read_text("utf-8")


def test_theta_of_the_generated_module_is_the_papers():
    module = codegen.load(absorber_theta())
    expected = [[0.5] * 4, [3, 4, 3, 0], [6, 6, 0, 0], [4, 0, 0, 0], [0, 0, 0, -1]]
    np.testing.assert_array_equal(module.theta(), expected)
    np.testing.assert_array_equal(module.theta(l=1.0, tau=1.0)[1], [3, 4, 3, 0])
    assert (module.n, module.m, module.N, module.PARAMETERS) == (3, 0, 3, ("tau", "l"))
    assert module.DEFAULTS == {"tau": 2.0, "l": 0.5} and module.TRUE_VALUE == 0.72
    dc = codegen.load(dc_drive_theta())
    np.testing.assert_array_equal(dc.theta(), np.array(dc_drive_theta().matrix, dtype=float))
    num, den = dc.transfer_function(10.0)
    np.testing.assert_array_equal(num, [100, 0, 10])
    np.testing.assert_array_equal(den, [10, 100, 111, 110, 10])


def test_numbers_are_printed_exactly_or_as_floats():
    matrix = absorber_theta().matrix.copy()
    matrix[0, 0] = tau / 3 - sympy.Rational(7, 2)
    matrix[0, 1] = sympy.sqrt(2) * l
    module = codegen.load(absorber_theta(matrix=matrix))
    source = codegen.render(absorber_theta(matrix=matrix))
    assert "1 / 3 * p['tau'] - 7 / 2" in source
    assert module.theta()[0, 0] == 2 / 3 - 7 / 2
    assert module.theta()[0, 1] == pytest.approx(np.sqrt(2) * 0.5, rel=1e-15)


def test_parameter_names_cannot_collide_with_the_modules_own_names():
    np_, theta_ = sympy.symbols("np theta")
    matrix = absorber_theta().matrix.subs({tau: np_, l: theta_}, simultaneous=True)
    changed = absorber_theta(
        symbols=("np", "theta"),
        defaults={"np": sympy.Integer(3), "theta": sympy.Integer(2)},
        matrix=matrix,
    )
    module = codegen.load(changed)
    assert module.theta()[3, 0] == 2 * 3**3
    assert module.theta(np=1.0)[3, 0] == 2.0


def test_the_module_is_imported_without_writing_a_file(monkeypatch, tmp_path):
    import linecache
    import tempfile
    import warnings

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "missing"))  # no temporary files
    monkeypatch.chdir(tmp_path)
    module = codegen.load(dc_drive_theta(model="drive_in_memory"))
    assert sys.modules["_mtt_generated_drive_in_memory"] is module
    assert module is codegen.load(dc_drive_theta(model="drive_in_memory"))
    assert list(tmp_path.iterdir()) == []
    # its lines are there for tracebacks, warnings and inspect, under a name that is no file
    assert module.__file__ == "<_mtt_generated_drive_in_memory>"
    assert inspect.getsource(module.fit).startswith("def fit(t, u, y, *")
    t = np.linspace(0.0, 10.0, 201)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        module.fit(t, np.ones_like(t), module.simulate(t, np.ones_like(t), 10.0))
    warning = next(w for w in caught if w.category is module.EstimationWarning)
    assert warning.filename == module.__file__
    line = linecache.getline(warning.filename, warning.lineno)
    assert line.strip() and line == module._mtt_source.splitlines(True)[warning.lineno - 1]


def test_kept_parameters_without_a_value_must_be_given():
    module = codegen.load(absorber_theta(defaults={"tau": None, "l": sympy.Rational(1, 2)}))
    assert module.DEFAULTS == {"tau": None, "l": 0.5}
    with pytest.raises(ValueError, match=r"no value for the known parameter 'tau'.*tau=VALUE"):
        module.theta()
    assert module.theta(tau=2.0)[3, 0] == 4.0


@pytest.mark.parametrize(
    "changes,kind",
    [
        (dict(symbols=("beta", "l")), "reserved_name"),
        (dict(symbols=("k0", "l")), "reserved_name"),
        (dict(symbols=("lambda", "l")), "bad_name"),
        (dict(model="class"), "bad_name"),
        (dict(unknowns=("k-1",)), "bad_name"),
        (dict(unknowns=("k", "x"), monomials=((0, 0), (1, 0), (2, 0), (3, 0))), "no_dependence"),
        (dict(monomials=((0,),)), "no_dependence"),
    ],
)
def test_names_and_systems_the_generator_refuses(changes, kind):
    theta = absorber_theta(**changes)
    if "symbols" in changes:
        renamed = sympy.Symbol(changes["symbols"][0])
        theta = dataclasses.replace(
            theta,
            defaults={renamed.name: sympy.Integer(2), "l": sympy.Rational(1, 2)},
            matrix=theta.matrix.subs(tau, renamed),
        )
    with pytest.raises(ModelError) as caught:
        codegen.render(theta)
    assert caught.value.kinds() == [kind]
    assert "absorber.bg: error[" in caught.value.render()


def test_a_theta_that_is_not_polynomial_in_the_kept_parameters_is_refused():
    matrix = absorber_theta().matrix.copy()
    matrix[0, 0] = 1 / tau
    with pytest.raises(ModelError) as caught:
        codegen.render(absorber_theta(matrix=matrix))
    assert caught.value.kinds() == ["unsupported_theta"]


def _taking_known(module) -> dict[str, set[str]]:
    """Every function and method of a generated module that takes the kept parameters as
    keyword arguments (**known), with the names of its other arguments."""
    found = {}
    for name, value in vars(module).items():
        owners = [(name, value)]
        if inspect.isclass(value) and value.__module__ == module.__name__:
            owners += [(f"{name}.{attr}", member) for attr, member in vars(value).items()]
        for label, function in owners:
            if not inspect.isfunction(function) or function.__module__ != module.__name__:
                continue
            parameters = inspect.signature(function).parameters.values()
            if any(p.kind is p.VAR_KEYWORD for p in parameters):
                found[label] = {p.name for p in parameters if p.kind is not p.VAR_KEYWORD}
    return found


@pytest.mark.parametrize("theta", [dc_drive_theta, absorber_theta])
def test_reserved_names_cover_the_generated_functions_arguments(theta):
    taking = _taking_known(codegen.load(theta()))
    # the public API with **known is all there (a rename would leave this test empty)
    assert {"theta", "transfer_function", "simulate", "fit", "fit_records", "moments"} <= set(
        taking
    ) and {"estimate", "prior_weight", "Tracker.__init__"} <= set(taking)
    for label, names in taking.items():
        assert names <= codegen.RESERVED, (label, names - codegen.RESERVED)


@pytest.mark.parametrize("name", ["records", "keep", "fraction"])
def test_a_kept_parameter_named_like_an_argument_of_fit_records_or_prior_weight(name):
    # fit_records(records, keep=...) and prior_weight(fraction=...) took these names: a
    # kept parameter `keep` was silently the argument, `records` a TypeError
    renamed = sympy.Symbol(name)
    theta = dataclasses.replace(
        absorber_theta(symbols=(name, "l")),
        defaults={name: sympy.Integer(2), "l": sympy.Rational(1, 2)},
        matrix=absorber_theta().matrix.subs(tau, renamed),
    )
    with pytest.raises(ModelError) as caught:
        codegen.render(theta)
    assert caught.value.kinds() == ["reserved_name"]
    assert f"the parameter {name!r} cannot be kept symbolic" in str(caught.value)


@pytest.mark.parametrize("name", ["__init__", "__main__", "sitecustomize", "usercustomize"])
def test_module_names_python_runs_or_treats_specially_are_refused(name):
    # generated/__init__.py would make a package of the directory, sitecustomize.py run
    # at every interpreter start where it is on the path
    with pytest.raises(ModelError) as caught:
        codegen.render(dc_drive_theta(model=name))
    assert caught.value.kinds() == ["reserved_name"]
    assert f"the model name {name!r} is the name of a Python module" in str(caught.value)


@pytest.mark.parametrize("file", ["numpy.py", "json.py", "__init__.py"])
def test_an_output_file_named_as_a_module_is_refused(tmp_path, file):
    with pytest.raises(ModelError) as caught:
        codegen.output_path(str(tmp_path / file), dc_drive_theta())
    assert caught.value.kinds() == ["reserved_name"]
    assert f"{Path(file).stem} is the name of a Python module" in str(caught.value)
    assert not (tmp_path / file).exists()
    # other names, and files that are no module, are written as asked
    for name in ("drive.py", "my-drive.py", "numpy.txt"):
        assert codegen.output_path(str(tmp_path / name), dc_drive_theta()) == tmp_path / name


def test_model_text_reaches_the_module_only_as_string_literals():
    hostile = 'x""" + __import__("os").system("false") + """\\ \' \'\'\' end ' * 3
    theta = dc_drive_theta(description=hostile)
    source = codegen.render(theta)
    tree = ast.parse(source)
    assert repr(hostile) in ast.get_docstring(tree, clean=False)
    module = codegen.load(theta)
    assert hostile == module.DESCRIPTION
    calls = [node for node in ast.walk(tree) if isinstance(node, ast.Call)]
    assert not any(getattr(call.func, "id", None) == "__import__" for call in calls)


def test_generated_modules_are_standalone(tmp_path):
    """Import the committed module where mtt (and sympy, jinja2, ...) cannot be imported."""
    (tmp_path / "dc_drive.py").write_bytes((ROOT / "generated" / "dc_drive.py").read_bytes())
    program = f"""
import json, pickle, runpy, sys
for name in ("mtt", "sympy", "jinja2", "lark", "networkx", "matplotlib"):
    sys.modules[name] = None  # importing any of them now fails
sys.path.insert(0, {str(tmp_path)!r})
import numpy as np
import dc_drive
t = np.linspace(0.0, 10.0, 1001)
u = np.ones_like(t)
y = dc_drive.simulate(t, u, 10.0)
np.savetxt("data.csv", np.column_stack([t, u, y]), delimiter=",", header="t,u,y", comments="")
result = dc_drive.estimate(t, u, y, k0=5.0)
tracker = pickle.loads(pickle.dumps(dc_drive.Tracker(k0=5.0)))
tracker.update(t, u, y)
print(json.dumps({{"k": result.k, "ok": result.ok, "fit": dc_drive.fit(t, u, y).k,
                  "tracker": tracker.k}}))
sys.argv = ["dc_drive.py", "data.csv", "--k0", "0", "20", "--json", "--bounds", "0", "100"]
try:
    runpy.run_path({str(tmp_path / "dc_drive.py")!r}, run_name="__main__")
except SystemExit as exit:
    assert exit.code == 0, exit.code
"""
    done = subprocess.run(
        [sys.executable, "-I", "-c", program], cwd=tmp_path, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    api, script = (json.loads(line) for line in done.stdout.splitlines())
    assert api["ok"] and abs(api["k"] - 10.0) < 0.1
    assert abs(api["fit"] - 10.0) < 1e-3 and api["tracker"] == pytest.approx(api["k"], rel=1e-9)
    assert [run["k0"] for run in script["runs"]] == [0.0, 20.0]
    assert all(abs(run["k"] - 10.0) < 0.1 for run in script["runs"])
    assert all(run["ok"] and run["global_k"] == pytest.approx(run["k"]) for run in script["runs"])


def test_write_atomic_replaces_whole_files_or_nothing(tmp_path, monkeypatch):
    target = tmp_path / "module.py"
    files.write_atomic(target, "old\n")
    files.write_atomic(target, "new\n")
    assert target.read_text() == "new\n"

    def refuse(*_):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(OSError):
        files.write_atomic(target, "partial")
    assert target.read_text() == "new\n"
    assert [path.name for path in tmp_path.iterdir()] == ["module.py"]


def test_model_unknown_and_parameter_names_of_the_modules_own_names_work(tmp_path):
    """A model named like a module-level name of its estimator, with its unknown and a
    kept parameter named like others (n, m, N are the module's degrees): all still work."""
    import mtt

    text = (
        "model theta\nparam N = 2\nparam m = 0.5\nunknown n = 0.1\n"
        "Se:v -> 1:loop\n1:loop -> R:N\n1:loop -> I:m\n1:loop -> C:n\n1:loop -> Df:i\n"
    )
    model = mtt.load(text, keep="m")
    path = model.compile(tmp_path)
    assert path.name == "theta.py"
    program = (
        "import numpy as np, theta\n"
        "t = np.linspace(0.0, 10.0, 501); u = np.ones_like(t)\n"
        "y = theta.simulate(t, u, 0.1, m=0.25)\n"
        "fit = theta.fit(t, u, y, offset=False, initial_state=False, m=0.25)\n"
        "print(theta.n, theta.m, theta.N, theta.UNKNOWN, theta.PARAMETERS, round(fit.k, 4))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", program], cwd=tmp_path, capture_output=True, text=True, check=True
    )
    assert done.stdout.split() == ["2", "1", "1", "n", "('m',)", "0.1"]


RLC = """# a series RLC circuit
model {model}
param r = 2
param t = 1
unknown {unknown} = 0.1
Se:v -> 1:loop
1:loop -> R:r
1:loop -> I:t
1:loop -> C:{capacitance}
1:loop -> Df:i
"""


@pytest.mark.parametrize(
    "model, unknown, capacitance, options, kind, place",
    [
        ("numpy", "c", "c", [], "reserved_name", (2, 7)),  # the model's name
        ("mymod", "c", "c", ["--keep", "t"], "reserved_name", (4, 7)),  # the kept parameter
        ("mymod", "lambda", "lambda", [], "bad_name", (5, 9)),  # a keyword as the unknown
        ("mymod", "c", "cap(r + c - c)", [], "no_dependence", (5, 9)),  # c cancels out
    ],
)
def test_the_generated_codes_names_are_refused_where_the_model_names_them(
    tmp_path, capsys, model, unknown, capacitance, options, kind, place
):
    from mtt.cli.main import main

    path = tmp_path / f"{model}.bg"
    path.write_text(RLC.format(model=model, unknown=unknown, capacitance=capacitance))
    assert main(["compile", str(path), "-o", str(tmp_path / "out.py"), *options, "--json"]) == 2
    out, err = capsys.readouterr()
    (found,) = json.loads(out)["errors"]
    assert (found["kind"], found["line"], found["column"], found["file"]) == (
        kind,
        *place,
        str(path),
    )
    line = RLC.format(model=model, unknown=unknown, capacitance=capacitance).splitlines()[
        place[0] - 1
    ]
    assert f"{path}:{place[0]}:{place[1]}: error[{kind}]" in err and f" | {line}\n" in err
    assert not (tmp_path / "out.py").exists()
