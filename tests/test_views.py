"""`mtt draw` and `mtt bode`: what the pictures hold, checked as data and as files."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import sympy

import mtt
from mtt.cli.main import main
from mtt.present import bode

CONFLICT = "model two\ninput Se:a\nparam r = 1\nSe:a -> 0:n\nSe:b -> 0:n\n0:n -> R:r\n0:n -> De:v\n"


def run(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def test_mtt_draw_writes_every_label_and_bond_number(tmp_path, capsys):
    out = tmp_path / "rlc.svg"
    status, stdout, _ = run(capsys, "draw", str(mtt.example("rlc")), "-o", str(out))
    assert status == 0 and f"wrote {out}" in stdout
    svg = out.read_text()
    texts = set(re.findall(r">([^<>\n]+)</text>", svg))
    assert {"Se:v", "1:loop", "R:r", "I:l", "C:c", "Df:i"} <= texts
    assert {"1", "2", "3", "4", "5"} <= texts
    run(capsys, "draw", str(mtt.example("rlc")), "-o", str(tmp_path / "again.svg"))
    assert (tmp_path / "again.svg").read_bytes() == out.read_bytes()  # reproducible


@pytest.mark.parametrize("suffix", ["png", "pdf"])
def test_mtt_draw_other_formats(tmp_path, capsys, suffix):
    out = tmp_path / f"drive.{suffix}"
    status, stdout, _ = run(capsys, "draw", str(mtt.example("dc_drive")), "-o", str(out), "--json")
    record = json.loads(stdout)
    assert status == 0 and record["ok"] and record["causality"]
    magic = {"png": b"\x89PNG", "pdf": b"%PDF"}[suffix]
    assert out.read_bytes().startswith(magic)


def test_a_causal_conflict_is_drawn_without_strokes_and_said(tmp_path, capsys):
    model = tmp_path / "two.bg"
    model.write_text(CONFLICT)
    status, stdout, err = run(capsys, "draw", str(model), "-o", str(tmp_path / "two.png"))
    assert status == 0 and (tmp_path / "two.png").exists()
    assert "error[causal_conflict]" in err and "drawn without causal strokes" in err


def test_draw_refuses_an_unknown_format(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit:
        main(["draw", str(mtt.example("rlc")), "-o", str(tmp_path / "x.jpg")])
    assert exit.value.code == 2
    assert "must end in .svg, .png or .pdf" in capsys.readouterr().err


def test_model_repr_svg_is_the_drawing():
    svg = mtt.load(mtt.example("rlc"))._repr_svg_()
    assert svg.lstrip().startswith("<?xml") and ">1:loop</text>" in svg


def test_bode_data_are_the_exact_frequency_response(tmp_path):
    model = mtt.load(mtt.example("dc_drive"))
    values = [1.0, 10.0]
    data = bode.bode([(k, *model.transfer_function.at(k=k)) for k in values])
    s, k = sympy.symbols("s k")
    for row, value in enumerate(values):
        G = sympy.lambdify(s, model.transfer_function.expr.subs(k, value))
        response = G(1j * data.frequency)
        expected = 20 * np.log10(abs(response))
        np.testing.assert_allclose(data.magnitude_db[row], expected, atol=1e-9)
        # the zeros k s^2 + 1 put a notch at 1/sqrt(k) rad/s (below the roll-off)
        low = data.frequency < 3
        notch = data.frequency[low][np.argmin(data.magnitude_db[row][low])]
        assert notch == pytest.approx(1 / np.sqrt(value), rel=0.03)
    assert data.frequency[0] < 0.1 and data.frequency[-1] > 10  # both notches, the roll-off


def test_mtt_bode_figure_and_json(tmp_path, capsys):
    out = tmp_path / "bode.png"
    status, stdout, _ = run(
        capsys, "bode", str(mtt.example("absorber")), "--k", "0.25,0.72", "-o", str(out), "--json"
    )
    record = json.loads(stdout)
    assert status == 0 and record["ok"] and record["k"] == [0.25, 0.72]
    assert np.shape(record["magnitude_db"]) == (2, len(record["frequency"]))
    assert out.read_bytes().startswith(b"\x89PNG")
    # G(0) = k^3 / (l (k^3 + k^2 + k + 1)) with l = 1/2
    gains = [20 * np.log10(k**3 / (0.5 * (k**3 + k**2 + k + 1))) for k in (0.25, 0.72)]
    assert [row[0] for row in record["magnitude_db"]] == pytest.approx(gains, abs=0.01)


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--k", "x", "--json"], "expected numbers separated by commas"),
        (["--k", "1,nan", "--json"], "expected finite numbers"),
        # was an internal error (LinAlgError) after a RuntimeWarning on stderr
        (["--k", "1e-308", "--json"], "error[out_of_range]: the frequency response for 1e-308"),
        (["--k", "-1e-320,1", "--json"], "is beyond floating point"),
    ],
)
def test_mtt_bode_usage_errors(capsys, argv, says):
    try:
        status = main(["bode", str(mtt.example("dc_drive")), *argv])
    except SystemExit as exit:
        status = exit.code
    err = capsys.readouterr().err
    assert status == 2 and says in err and "Warning" not in err


def test_draw_and_bode_write_a_default_file_and_bode_takes_lists_either_way(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    assert main(["draw", str(mtt.example("rlc"))]) == 0
    assert (tmp_path / "rlc.svg").read_text().startswith("<?xml")
    assert main(["bode", str(mtt.example("rlc")), "--k", "0.1,0.2", "0.3"]) == 0
    assert "rlc_bode.svg: Bode diagram of rlc at c = 0.1; c = 0.2; c = 0.3" in (
        capsys.readouterr().out
    )
    assert (tmp_path / "rlc_bode.svg").stat().st_size > 1000
    # several unknowns: one curve at the file's values; --k needs one unknown chosen
    status, out, _ = run(capsys, "bode", str(mtt.example("dc_motor")), "--json")
    record = json.loads(out)
    assert status == 0 and record["unknowns"] == ["ra", "jl"] and record["k"] == [[1.0, 10.0]]
    status, _, err = run(capsys, "bode", str(mtt.example("dc_motor")), "--k", "2", "--json")
    assert status == 2 and "choose which with --unknown NAME" in err
    status, out, _ = run(capsys, "bode", str(mtt.example("dc_motor")), "--unknown", "jl",
                         "--k", "5", "--json")  # fmt: skip
    assert status == 0 and json.loads(out)["k"] == [5.0]


def test_mtt_bode_of_a_zero_transfer_function_is_an_error_without_warnings(tmp_path, capsys):
    # rlc's G(s) = 2cs / (cs^2 + 4cs + 2) is zero at c = 0: scipy warned and gave -inf dB,
    # which --json printed as -Infinity (not JSON)
    status, out, err = run(capsys, "bode", str(mtt.example("rlc")), "--k", "0,1", "--json")
    assert status == 2 and json.loads(out)["errors"][0]["kind"] == "bad_value"
    assert err == "error[bad_value]: G(s) is zero at c = 0: there is no Bode diagram\n"
    assert bode.json_lists(np.array([[1.5, -np.inf, np.nan]])) == [[1.5, None, None]]


def _png_size(path) -> tuple[int, int]:
    header = path.read_bytes()[:24]
    assert header[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(header[16:20], "big"), int.from_bytes(header[20:24], "big")


def test_every_command_that_draws_takes_dpi(tmp_path, capsys):
    # --dpi was an option of simulate, estimate and fit only; draw and bode drew at 150
    rlc = str(mtt.example("rlc"))
    for command, extra, inches in (
        ("draw", [], None),
        ("bode", [], (7.0, 5.6)),
        ("simulate", ["--t-end", "1"], None),
    ):
        sizes = []
        for dpi in ("60", "120"):
            out = tmp_path / f"{command}{dpi}.png"
            flag = "--data-plot" if command == "simulate" else "-o"
            status, _, err = run(capsys, command, rlc, flag, str(out), "--dpi", dpi, *extra)
            assert status == 0, err
            sizes.append(_png_size(out))
        low, high = np.array(sizes[0]), np.array(sizes[1])
        assert np.abs(high - 2 * low).max() <= 1  # the same figure, twice as fine (rounded)
        if inches:
            assert sizes[0] == (round(60 * inches[0]), round(60 * inches[1]))
    for command in ("draw", "bode"):
        with pytest.raises(SystemExit):
            main([command, rlc, "-o", str(tmp_path / "x.png"), "--dpi", "5"])
        assert "--dpi must be from 10 to 2400, not 5" in capsys.readouterr().err
