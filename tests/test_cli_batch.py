"""`mtt fit --data PATTERN`: one fit per record (a table, --json, --csv), --jobs, --pooled.

The numbers are checked against the module's own fit of each file (batch_records); the
commands run in this process (`mtt` as a child process is tested elsewhere).
"""

from __future__ import annotations

import csv
import json
from types import SimpleNamespace

from batch_records import CORRUPT, direct_fits, logs

from mtt.cli.main import main

__all__ = ["logs"]  # the fixture

MODEL = "models/dc_drive.bg"


def run_here(capsys, commands: list[list[str]]) -> list[SimpleNamespace]:
    """`mtt ARGS` for each ARGS, in this process: exit status, stdout, stderr."""
    runs = []
    for args in commands:
        try:
            status = main(args)
        except SystemExit as exit:
            status = exit.code
        out, err = capsys.readouterr()
        runs.append(SimpleNamespace(returncode=status, stdout=out, stderr=err))
    return runs


def test_a_pattern_fits_each_record(capsys, logs, dc_drive, tmp_path):
    pattern = str(logs / "run_*.csv")
    table = tmp_path / "records.csv"
    here, processes, text = run_here(capsys, [
        ["fit", MODEL, "--data", pattern, "--hold", "zoh", "--json", "--csv", str(table)],
        ["fit", MODEL, "--data", pattern, "--hold", "zoh", "--json", "--jobs", "2"],
        ["fit", MODEL, "--data", pattern, "--hold", "zoh"],
    ])  # fmt: skip
    assert here.returncode == processes.returncode == text.returncode == 1  # one record failed
    result = json.loads(here.stdout)
    assert result == json.loads(processes.stdout)  # the same numbers with 2 processes
    assert set(result) == {"ok", "records"} and result["ok"] is False
    paths = sorted(str(path) for path in logs.glob("run_*.csv"))
    assert [record["file"] for record in result["records"]] == paths
    direct = direct_fits(dc_drive, paths, hold="zoh")
    for record in result["records"]:
        assert set(record) == {"file", "k", "k_se", "fit_percent", "warnings", "error"}
        if record["file"].endswith(CORRUPT):
            assert record["k"] is None
            assert record["error"] == f"{record['file']}:18: column 'y' holds 'oops', not a number"
        else:
            assert record["error"] is None and record["k"] == direct[record["file"]].k
            assert record["k_se"] == direct[record["file"]].k_se
    errors = [line for line in text.stderr.splitlines() if "error" in line]
    assert errors == [f"mtt fit: error: {logs / CORRUPT}:18: column 'y' holds 'oops', not a number"]
    lines = text.stdout.splitlines()
    assert (
        lines[0] == "dc_drive: 12 records, one fit each (exact prediction error, in this process)"
    )
    assert lines[-1] == "  11 of 12 records fitted; 1 failed"
    assert f"{direct[paths[0]].k:.6g}" in lines[2] and "failed" in lines[2 + 7]
    with open(table, newline="") as file:
        rows = list(csv.DictReader(file))
    assert [row["file"] for row in rows] == paths
    assert (
        float(rows[0]["k"]) == direct[paths[0]].k
        and rows[7]["error"] == result["records"][7]["error"]
    )


def test_pooled_by_workers_equals_the_pooled_fit_here(capsys, logs):
    files = [str(logs / f"run_{i:02d}.csv") for i in (0, 1, 2)]
    data = [option for path in files for option in ("--data", path)]
    bad_data = ["--data", str(logs / "run_0[6-8].csv"), "--pooled", "--hold", "zoh", "--json"]
    here, processes, per_record, bad, bad_here = run_here(capsys, [
        ["fit", MODEL, *data, "--hold", "zoh", "--json"],
        ["fit", MODEL, "--data", str(logs / "run_0[0-2].csv"), "--pooled", "--jobs", "2",
         "--hold", "zoh", "--json"],
        ["fit", MODEL, *data, "--per-record", "--hold", "zoh", "--json"],
        ["fit", MODEL, *bad_data, "--jobs", "2"],
        ["fit", MODEL, *bad_data],
    ])  # fmt: skip
    assert here.returncode == processes.returncode == per_record.returncode == 0
    pooled, alone = json.loads(here.stdout), json.loads(processes.stdout)
    for name in ("k", "k_se", "fit_percent", "residual_rms"):
        assert abs(alone[name] - pooled[name]) <= 1e-9 * abs(pooled[name])
    assert alone["data"] == files and alone["ok"] and alone["iterations"] == pooled["iterations"]
    assert [record["file"] for record in json.loads(per_record.stdout)["records"]] == files
    # as in one process, a bad record in a pooled fit is the error, named (also in --json)
    assert bad.returncode == bad_here.returncode == 2
    message = f"mtt fit: error: {logs / CORRUPT}:18: column 'y' holds 'oops', not a number\n"
    assert bad.stderr == bad_here.stderr == message
    assert bad.stdout == bad_here.stdout and json.loads(bad.stdout)["ok"] is False


def test_usage_errors(capsys, logs):
    pattern = str(logs / "run_*.csv")
    runs = run_here(capsys, [
        ["fit", MODEL, "--data", pattern, "--plot", "fit.png"],
        ["fit", MODEL, "--data", str(logs / "none_*.csv")],
        ["fit", MODEL, "--data", pattern, "--jobs", "0"],
        ["fit", MODEL, "--jobs", "2"],
    ])  # fmt: skip
    assert [run.returncode for run in runs] == [2, 2, 2, 2]
    assert "--plot draws the fitted outputs, which stay with the workers" in runs[0].stderr
    assert f"no file matches '{logs / 'none_*.csv'}'" in runs[1].stderr
    assert "--jobs must be at least 1, not 0" in runs[2].stderr
    assert "apply to --data" in runs[3].stderr
