"""Options are taken only as spelled: an abbreviation argparse would expand is refused."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_an_abbreviated_option_is_not_another_option(tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "mtt", "simulate", str(ROOT / "models" / "rlc.bg"),
         "--data", str(tmp_path / "f.csv")],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert run.returncode == 2
    assert "unrecognized arguments: --data" in run.stderr
    assert "Format" not in run.stderr and not (tmp_path / "f.csv").exists()
