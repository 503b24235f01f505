"""Start-up time of the `mtt` command, against a bare Python start in the same run.

Run: .venv/bin/python bench/startup.py [--repeat 15]

Each command runs in a fresh interpreter (the way a user runs it), `--repeat` times; the
table gives the median and best wall time and the median as a multiple of `python -c pass`.
The last rows time libraries on their own: lark is all `mtt check` imports besides mtt
(the parser builds its own expression trees and the bond graph is plain records: sympy and
networkx are for the commands that compute, as `mtt tf`).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = 0.3  # seconds, issue 12 item 3
MTT = [sys.executable, "-m", "mtt"]
PYTHON = [sys.executable, "-c"]
COMMANDS = {
    "python -c pass (baseline)": [*PYTHON, "pass"],
    "mtt --help": [*MTT, "--help"],
    "mtt check models/rlc.bg": [*MTT, "check", str(ROOT / "models" / "rlc.bg")],
    "mtt check models/absorber_stages.bg": [
        *MTT,
        "check",
        str(ROOT / "models" / "absorber_stages.bg"),
    ],
    "mtt tf models/rlc.bg": [*MTT, "tf", str(ROOT / "models" / "rlc.bg")],
    "python -c 'import lark'": [*PYTHON, "import lark"],
    "python -c 'import sympy'": [*PYTHON, "import sympy"],
    "python -c 'import networkx'": [*PYTHON, "import networkx"],
}
TARGETED = ("mtt --help", "mtt check models/rlc.bg", "mtt check models/absorber_stages.bg")


def wall_times(argv: list[str], repeat: int) -> list[float]:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - start)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15, help="runs per command (default 15)")
    args = parser.parse_args()
    for argv in COMMANDS.values():  # warm the file cache and the .pyc files first
        wall_times(argv, 1)
    rows = {label: wall_times(argv, args.repeat) for label, argv in COMMANDS.items()}
    baseline = statistics.median(rows["python -c pass (baseline)"])
    print(f"{'command':42}  {'median':>8}  {'best':>8}  {'x python':>8}  target")
    for label, times in rows.items():
        median = statistics.median(times)
        target = ""
        if label in TARGETED:
            target = f"< {TARGET} s: {'met' if median < TARGET else 'NOT met'}"
        print(f"{label:42}  {median:7.3f}s  {min(times):7.3f}s  {median / baseline:8.1f}  {target}")


if __name__ == "__main__":
    main()
