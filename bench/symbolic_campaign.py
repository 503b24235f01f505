"""A campaign of fully symbolic models that grow: every file ends in time, with a result
or with too_large, never a MemoryError or a multi-GB process (issue 23 item 1).

Run: .venv/bin/python bench/symbolic_campaign.py [--sizes 2 5 10 20 50 100] [--timeout 60]
                                                [--memory-gb 2] [--kinds ladder mesh bridge]

Each model has every resistance and capacitance symbolic (no values) and one unknown: an
RC ladder of N sections, a square RC mesh of about N nodes (a capacitor from each node to
ground, a resistor between neighbours), and a chain of N bridges (two nodes a section, a
resistor from each node of one section to each node of the next and one across). Each runs
`mtt tf --json` in a fresh process with its address space capped (--memory-gb), killed at
--timeout; the table gives its outcome (result, too_large, or FAIL: anything else), its
wall time and its peak resident memory. tests/test_symbolic_campaign.py runs a small
bounded sample of the same generators in `make test`.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# the child reports its own peak memory (kB) on its last line of stderr
CHILD = """
import resource, sys
limit = int(sys.argv[1])
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
from mtt.cli.main import main
status = main(["tf", "--json", sys.argv[2]])
print("peak-kB", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)
sys.exit(status)
"""


def _model(name: str, parameters: list[str], bonds: list[str]) -> str:
    return "\n".join([f"model {name}", "unknown k", *(f"param {p}" for p in parameters), *bonds])


def ladder(n: int) -> str:
    """Series R, shunt C, n times; the load resistance k."""
    params = [f"{kind}{i}" for i in range(1, n + 1) for kind in "rc"]
    bonds = ["Se:v -> 1:s1"]
    for i in range(1, n + 1):
        bonds += [f"1:s{i} -> R:r{i}(r{i})", f"1:s{i} -> 0:n{i}", f"0:n{i} -> C:c{i}(c{i})"]
        bonds += [f"0:n{i} -> 1:s{i + 1}"] if i < n else []
    bonds += [f"0:n{n} -> R:load(k)", f"0:n{n} -> De:out"]
    return _model(f"ladder{n}", params, bonds) + "\n"


def _resistor(params: list[str], bonds: list[str], name: str, a: str, b: str) -> None:
    """A resistor between two 0-junctions, through a 1-junction."""
    params.append(name)
    bonds += [f"{a} -> 1:j{name}", f"1:j{name} -> {b}", f"1:j{name} -> R:{name}({name})"]


def mesh(n: int) -> str:
    """A side x side grid of nodes (side^2 about n), each with a capacitor to ground."""
    side = max(2, round(math.sqrt(n)))
    params, bonds = [], ["Se:v -> 1:in", "1:in -> R:rin(k)", "1:in -> 0:n0_0"]
    for i in range(side):
        for j in range(side):
            node = f"0:n{i}_{j}"
            params.append(f"c{i}_{j}")
            bonds.append(f"{node} -> C:c{i}_{j}(c{i}_{j})")
            if i + 1 < side:
                _resistor(params, bonds, f"rv{i}_{j}", node, f"0:n{i + 1}_{j}")
            if j + 1 < side:
                _resistor(params, bonds, f"rh{i}_{j}", node, f"0:n{i}_{j + 1}")
    bonds.append(f"0:n{side - 1}_{side - 1} -> De:out")
    return _model(f"mesh{side}x{side}", params, bonds) + "\n"


def bridge(n: int) -> str:
    """n bridge sections: nodes p_i and q_i with capacitors to ground, a resistor from each
    node of section i - 1 to each of section i, and one across p_i q_i."""
    params, bonds = [], ["Se:v -> 1:in", "1:in -> R:rin(k)", "1:in -> 0:p0", "0:p0 -> 1:link"]
    bonds += ["1:link -> R:rlink(k)", "1:link -> 0:q0"]
    for i in range(n + 1):
        for node in (f"p{i}", f"q{i}"):
            params.append(f"c{node}")
            bonds.append(f"0:{node} -> C:c{node}(c{node})")
        if i:
            for a in "pq":
                for b in "pq":
                    _resistor(params, bonds, f"r{a}{b}{i}", f"0:{a}{i - 1}", f"0:{b}{i}")
            _resistor(params, bonds, f"rx{i}", f"0:p{i}", f"0:q{i}")
    bonds.append(f"0:q{n} -> De:out")
    return _model(f"bridge{n}", params, bonds) + "\n"


KINDS = {"ladder": ladder, "mesh": mesh, "bridge": bridge}


def run(path: Path, timeout: float, memory: int) -> tuple[str, float, float | None, str]:
    """(outcome, seconds, peak MB or None, detail) of `mtt tf --json` on one file."""
    start = time.perf_counter()
    try:
        done = subprocess.run(
            [sys.executable, "-c", CHILD, str(memory), str(path)],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=ROOT,
        )
    except subprocess.TimeoutExpired:
        return "FAIL", time.perf_counter() - start, None, f"past {timeout:.0f} s"
    took = time.perf_counter() - start
    peak = next(
        (
            int(line.split()[1]) / 1024
            for line in done.stderr.splitlines()
            if line.startswith("peak-kB")
        ),
        None,
    )
    try:
        record = json.loads(done.stdout.splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        return "FAIL", took, peak, done.stderr.strip().splitlines()[-1:] or ["no output"]
    if done.returncode == 0 and record.get("ok"):
        return "result", took, peak, f"{len(record['den'])} characters in den"
    kinds = [e["kind"] for e in record.get("errors", [])]
    if done.returncode == 2 and kinds == ["too_large"]:
        return "too_large", took, peak, record["errors"][0]["message"][:60]
    return "FAIL", took, peak, f"exit {done.returncode}: {sorted(set(kinds))}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[2, 5, 10, 20, 50, 100])
    parser.add_argument("--kinds", nargs="+", choices=sorted(KINDS), default=list(KINDS))
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--memory-gb", type=float, default=2.0)
    args = parser.parse_args()
    memory = int(args.memory_gb * (1 << 30))
    failures, slowest, heaviest = 0, 0.0, 0.0
    print(f"{'model':<14}{'outcome':>10}{'seconds':>9}{'peak MB':>9}  detail")
    with tempfile.TemporaryDirectory() as tmp:
        for kind in args.kinds:
            for n in args.sizes:
                path = Path(tmp) / f"{kind}{n}.bg"
                path.write_text(KINDS[kind](n), encoding="utf-8")
                outcome, took, peak, detail = run(path, args.timeout, memory)
                failures += outcome == "FAIL"
                slowest, heaviest = max(slowest, took), max(heaviest, peak or 0.0)
                shown = f"{peak:9.0f}" if peak is not None else f"{'-':>9}"
                print(f"{kind + str(n):<14}{outcome:>10}{took:>9.2f}{shown}  {detail}", flush=True)
    print(f"\n{failures} failed; slowest {slowest:.1f} s (limit {args.timeout:.0f} s); "
          f"peak {heaviest:.0f} MB (cap {args.memory_gb:g} GB)")  # fmt: skip
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
