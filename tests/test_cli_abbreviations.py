"""Options are taken only as spelled: an abbreviation argparse would expand is refused."""

from pathlib import Path

from inprocess import run_mtt

ROOT = Path(__file__).resolve().parent.parent


def test_an_abbreviated_option_is_not_another_option(capsys, tmp_path):
    status, _, err = run_mtt(
        capsys, "simulate", str(ROOT / "models" / "rlc.bg"), "--data", str(tmp_path / "f.csv")
    )
    assert status == 2
    assert "unrecognized arguments: --data" in err
    assert "Format" not in err and not (tmp_path / "f.csv").exists()
