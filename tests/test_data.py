"""mtt.data: records measured and simulated, as the API and the command line read them."""

from __future__ import annotations

import numpy as np
import pytest

import mtt
from mtt.cli.running import as_options
from mtt.data import DataError, default_hold, records


@pytest.fixture(scope="module")
def rlc():
    return mtt.load(mtt.example("rlc")).estimator()


def test_columns_are_three_different_names():
    assert records.columns(None) == ("t", "u", "y")
    assert records.columns(" time, volts ,speed") == ("time", "volts", "speed")
    assert records.columns(["a", "b", "c"]) == ("a", "b", "c")
    for bad in ("a,b", "a,a,b", "a,,b"):
        with pytest.raises(DataError, match="three different names") as caught:
            records.columns(bad)
        assert caught.value.names == ("columns",)


def test_a_record_read_names_its_file_and_the_rows_out_of_order(rlc, tmp_path):
    good = tmp_path / "good.csv"
    good.write_text("time,volts,speed\n0,1,0\n0.5,1,0.25\n1,1,0.5\n")
    record = records.read(rlc, str(good), ("time", "volts", "speed"))
    assert record.t.tolist() == [0, 0.5, 1] and record.y.tolist() == [0, 0.25, 0.5]
    assert record.note == f"3 samples from {good}" and record.clean is record.k is None
    late = tmp_path / "late.csv"
    late.write_text("t,u,y\n0,1,0\n1,1,0\n0.5,1,0\n")
    with pytest.raises(DataError, match=r"late.csv:4: the times \(column 't'\) must increase"):
        records.read(rlc, str(late))


def test_a_simulated_record_is_the_model_s_output_plus_the_noise_asked_for(rlc):
    t, u, source = records.input_signal(rlc, "prbs", t_end=2, dt=0.01, period=0.1, seed=3)
    assert t.size == 201 and set(np.unique(u)) == {-1.0, 1.0}
    assert source == "prbs, amplitude 1, period 0.1"
    clean = records.simulate(rlc, t, u, 0.1, source=source, hold="zoh")
    assert np.array_equal(clean.y, rlc.simulate(t, u, 0.1, hold="zoh")) and clean.k == 0.1
    noisy = records.simulate(rlc, t, u, 0.1, source=source, hold="zoh", noise_uniform=0.01)
    assert np.array_equal(noisy.clean, clean.y) and 0 < np.abs(noisy.y - clean.y).max() <= 0.01
    assert noisy.note.endswith("noise uniform in [-0.01, 0.01] (seed 0)")
    assert default_hold("prbs", measured=False) == "zoh"
    assert default_hold("multisine", measured=False) == default_hold(None, True) == "linear"


@pytest.mark.parametrize(
    "options, python, command_line",
    [
        ({"dt": 0}, "need 0 < dt <= t_end, not dt 0 and t_end 10.0",
         "need 0 < --dt <= --t-end, not --dt 0 and --t-end 10.0"),
        ({"signal": "step", "period": 2}, "period applies to prbs",
         "--period applies to prbs"),
        ({"signal": "in.csv", "t_end": 2}, "t_end, dt and period apply to the test signals "
         "(signal step", "--t-end, --dt and --period apply to the test signals (--signal step"),
    ],
)  # fmt: skip
def test_settings_errors_name_the_parameters_the_way_the_caller_spells_them(
    rlc, options, python, command_line
):
    with pytest.raises(DataError) as caught:
        records.input_signal(rlc, **options)
    assert str(caught.value).startswith(python)
    assert as_options(caught.value).startswith(command_line)


def test_a_spreadsheet_s_semicolons_or_tabs_are_read_and_a_missing_column_says_columns(
    rlc, tmp_path
):
    rows = [("0", "1", "0"), ("0.5", "1", "0.25"), ("1", "1", "0.5")]
    for delimiter in (";", "\t"):
        path = tmp_path / "semi.csv"
        path.write_text("\n".join(delimiter.join(row) for row in [("t", "u", "y"), *rows]))
        assert records.read(rlc, str(path)).y.tolist() == [0, 0.25, 0.5]
        assert rlc.read_csv(str(path))[2].tolist() == [0, 0.25, 0.5]  # the module's own reader
    bars = tmp_path / "bars.csv"
    bars.write_text("\ufeffy|t|u\n0|0|1\n0.5|1|1\n")  # a byte-order mark, columns in any order
    assert [column.tolist() for column in rlc.read_csv(str(bars))] == [[0, 1], [1, 1], [0, 0.5]]
    short = tmp_path / "short.csv"  # the checked reader splits as the header line is split
    short.write_text("t;u;y\n0;1;0\n1;1\n")
    with pytest.raises(ValueError, match=r"short.csv:3: 2 values where the header names 3 columns"):
        rlc.read_csv(str(short))
    wrong = tmp_path / "wrong.csv"
    wrong.write_text("time;volts;speed\n0;1;0\n1;1;0.5\n")
    with pytest.raises(DataError) as caught:
        records.read(rlc, str(wrong))
    assert str(wrong) in str(caught.value) and "(the header names time, volts, speed)" in str(
        caught.value
    )
    assert as_options(caught.value).endswith("output with --columns T,U,Y (now t,u,y)")
    assert records.read(rlc, str(wrong), ("time", "volts", "speed")).t.tolist() == [0, 1]


def test_the_api_reads_a_record_through_mtt_data(tmp_path):
    model = mtt.load(mtt.example("rlc"))
    path = tmp_path / "run.csv"
    path.write_text("time;volts;amps\n0;1;0\n0.5;1;0.25\n1;1;0.5\n")
    record = model.read_csv(path, columns="time,volts,amps")
    assert record.y.tolist() == [0, 0.25, 0.5] and record.note == f"3 samples from {path}"
    with pytest.raises(mtt.MttError, match="no column 't'") as caught:
        model.read_csv(path)
    assert caught.value.kind == "bad_data" and caught.value.file == str(path)  # as the CLI's
    assert caught.value.line == 1  # the header's line
