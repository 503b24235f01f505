"""The option types for several unknowns (--k0 a=1,b=2, --true, --bounds a=LO:HI), as
the simulating and estimating commands declare them, and their check against a model's
unknowns."""

from __future__ import annotations

import argparse

import pytest

from mtt.cli.value_options import in_unknowns_order, named_bounds, named_values
from mtt.language.diagnostics import MttError


def parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mtt estimate", exit_on_error=False)
    parser.add_argument("--k0", type=named_values, nargs="+")
    parser.add_argument("--true", type=named_values)
    parser.add_argument("--bounds", type=named_bounds)
    return parser


def test_values_by_name_and_bare():
    args = parser().parse_args(["--k0", "ra=1,jl=2.5", "jl=1e-3,ra=-4", "--true", "ra=1, jl=10",
                                "--bounds", "ra=0:5,jl=1:20"])  # fmt: skip
    assert args.k0 == [{"ra": 1.0, "jl": 2.5}, {"jl": 0.001, "ra": -4.0}]
    assert args.true == {"ra": 1.0, "jl": 10.0}
    assert args.bounds == {"ra": (0.0, 5.0), "jl": (1.0, 20.0)}
    assert in_unknowns_order(args.k0[1], ("ra", "jl"), "--k0") == (-4.0, 0.001)
    assert in_unknowns_order(args.bounds, ("ra", "jl"), "--bounds") == ((0.0, 5.0), (1.0, 20.0))
    # a bare negative bound must be attached: argparse reads "-1:1" as an option
    one = parser().parse_args(["--k0", "0", "5", "--true", "10", "--bounds=-1:1", "--k0", "2"])
    assert (one.k0, one.true, one.bounds) == ([2.0], 10.0, (-1.0, 1.0))
    assert in_unknowns_order(one.true, ("k",), "--true") == (10.0,)
    assert in_unknowns_order(named_values("motor.ra=3"), ("motor.ra",), "--true") == (3.0,)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--k0", "ra=1,ra=2"], "ra is given twice"),
        (["--k0", "ra=x"], "'x' in 'ra=x' is not a number"),
        (["--true", "ra=nan"], "'nan' in 'ra=nan' is not finite"),
        (["--true", "1=2"], "expected NAME=VALUE"),
        (["--true", "ra=1,"], "expected NAME=VALUE"),
        (["--bounds", "ra=5:1"], "LO must be below HI"),
        (["--bounds", "ra=5"], "expected LO:HI"),
        (["--bounds", "0:inf"], "not finite"),
    ],
)
def test_malformed_values_are_refused_by_the_parser(argv, message):
    with pytest.raises(argparse.ArgumentError, match=message):
        parser().parse_args(argv)


def test_values_are_checked_against_the_unknowns():
    with pytest.raises(MttError, match="2 unknowns .ra, jl.: give each by name, --k0 ra=...,jl="):
        in_unknowns_order(5.0, ("ra", "jl"), "--k0")
    with pytest.raises(MttError, match="--true: k is not an unknown of the model"):
        in_unknowns_order({"ra": 1.0, "k": 2.0}, ("ra", "jl"), "--true")
    with pytest.raises(MttError, match="--true: no value for jl") as raised:
        in_unknowns_order({"ra": 1.0}, ("ra", "jl"), "--true")
    assert raised.value.kind == "bad_value"
    partial = in_unknowns_order({"jl": (0.0, 1.0)}, ("ra", "jl"), "--bounds", complete=False)
    assert partial == (None, (0.0, 1.0))


def test_negative_numbers_are_values_on_the_mtt_command_line(capsys):
    # argparse took -1e-3, -inf and -1:0 for options ("argument --k0: expected one argument")
    from mtt.cli.main import make_parser

    parse = make_parser().parse_args
    args = parse(["estimate", "m.bg", "--k0", "-1e-3", "-2", "-.5", "--bounds", "-1e3", "-1"])
    assert args.k0 == [-0.001, -2.0, -0.5] and args.bounds == (-1000.0, -1.0)
    assert parse(["fit", "m.bg", "--bounds", "-1:0"]).bounds == (-1.0, 0.0)
    assert parse(["fit", "m.bg", "--k0", "ra=-1,jl=2", "--true", "-1E+2"]).true == -100.0
    assert parse(["bode", "m.bg", "--k", "-1e3,2"]).k == [-1000.0, 2.0]
    for value in ("-inf", "-nan", "-Infinity"):
        with pytest.raises(SystemExit):
            parse(["estimate", "m.bg", "--k0", value])
        assert f"argument --k0: {value!r} in {value!r} is not finite" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # an option is still an option
        parse(["estimate", "m.bg", "--k0", "1", "-x"])
    assert "unrecognized arguments: -x" in capsys.readouterr().err


def test_lists_take_commas_and_spaces_alike(capsys):
    from mtt.cli.main import make_parser

    parse = make_parser().parse_args
    for words in (["0,5,20"], ["0", "5", "20"], ["0,5", "20"]):
        args = parse(["estimate", "m.bg", "--k0", *words, "--filter-T", *words])
        assert args.k0 == args.filter_T == [0.0, 5.0, 20.0]
        assert parse(["bode", "m.bg", "--k", *words]).k == [0.0, 5.0, 20.0]
    several = parse(["estimate", "m.bg", "--k0", "ra=1,jl=5", "ra=2,jl=9"]).k0
    assert several == [{"ra": 1.0, "jl": 5.0}, {"ra": 2.0, "jl": 9.0}]
    with pytest.raises(SystemExit):
        parse(["estimate", "m.bg", "--k0", "0,x"])
    assert "argument --k0: 'x' in '0,x' is not a number" in capsys.readouterr().err
    # a space inside one point of several unknowns: the message says how to write it
    with pytest.raises(MttError, match=r"joined by commas: --k0 ra=\.\.\.,jl=\.\.\.; a space"):
        in_unknowns_order({"ra": 1.0}, ("ra", "jl"), "--k0")


def test_names_take_commas_and_spaces_alike(capsys):
    """--unknown, --keep, --at and --columns read lists as --k0 does; --set a word each
    (a value may hold commas); a model file the list took is said to be one."""
    from mtt.cli.main import make_parser

    parse = make_parser().parse_args
    for names in (["tau,l"], ["tau", "l"], ["tau,", "l"]):
        args = parse(["tf", "m.bg", "--keep", *names, "--unknown", *names])
        assert args.keep == args.unknowns == ["tau", "l"]
        assert parse(["fit", "m.bg", "--columns", *names, "x"]).columns == ["tau", "l", "x"]
    args = parse(["tf", "m.bg", "--set", "r=3", "l=max(1, 2)", "--at", "u=1", "q=1/2,p=0"])
    assert [name for name, _ in args.overrides] == ["r", "l"] and str(args.overrides[1][1]) == "2"
    assert [name for name, _ in args.at] == ["u", "q", "p"]
    for option in ("--keep", "--unknown", "--columns"):
        with pytest.raises(SystemExit):
            parse(["fit", option, "tau", "l", "models/absorber.bg"])
        err = capsys.readouterr().err
        assert f"argument {option}: 'models/absorber.bg' is a model file, not an item" in err
        assert "put the model file before the option, or end the list with --" in err
    for signals in (["Df:i1,Df:i2"], ["Df:i1", "Df:i2"]):  # several outputs
        assert parse(["tf", "m.bg", "--output", *signals]).output == ["Df:i1", "Df:i2"]
    args = parse(["tf", "--keep", "tau", "l", "--", "models/absorber.bg"])
    assert (args.keep, args.file) == (["tau", "l"], "models/absorber.bg")
