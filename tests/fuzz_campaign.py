"""A fuzz campaign: the generators of tests/fuzzing.py, for as many models as you like.

Run: .venv/bin/python tests/fuzz_campaign.py --count 10000 --jobs 2 [--first 0] [--out DIR]
[--hostile]

Model i is drawn from random.Random(i): a random model when i % 3 is 0, a mutated example
when it is 1, a well-formed model with random expressions when it is 2; with --hostile,
a model whose values are hostile constants (tests/hostile_fuzzing.py: roots and logarithms
of negative numbers, deep nesting, chains of parameters, huge exponentials). Each runs every
command of `fuzzing.COMMANDS` (check, show, causality, ss, tf, theta, compile, and an import
of the generated estimator) and of `fuzzing.MORE_COMMANDS` (--symbolic, --keep, --set,
--unknown) in a worker process. The summary counts
the outcomes (all commands fine, a model error, an internal error, past 2 s, text from the
model run) and the kinds of error `mtt check` reported; the text of every bug, hang and
slow model is written to DIR (default fuzz-findings/) to reproduce it.
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing
import random
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fuzzing  # noqa: E402
import hostile_fuzzing  # noqa: E402

HOSTILE = False  # set by --hostile, before the workers fork


def warm() -> None:
    """Import what the commands import, so that no model pays for it."""
    with tempfile.TemporaryDirectory() as directory:
        fuzzing.run(
            fuzzing.Files((fuzzing.ROOT / "models" / "rlc.bg").read_text(), {}), Path(directory)
        )


def one(index: int) -> tuple[int, str, tuple, float, str]:
    """Model `index`: (index, outcome, check's kinds, seconds, report for a finding)."""
    rng = random.Random(index)
    if HOSTILE:
        files = fuzzing.Files(hostile_fuzzing.constant_model(rng), {})
    elif index % 3 == 0:
        files = fuzzing.random_model(rng)
    elif index % 3 == 1:
        files = fuzzing.example(rng)
    else:
        files = fuzzing.Files(fuzzing.valid_model(rng, expressions=True), {})
    with tempfile.TemporaryDirectory() as directory:
        try:
            outcome = fuzzing.run(files, Path(directory), fuzzing.COMMANDS + fuzzing.MORE_COMMANDS)
        except fuzzing.Hang:
            return index, "hang", (), 4 * fuzzing.HANG, files.model
    if outcome.executed:
        return index, "executed", outcome.kinds, outcome.seconds, files.model
    if outcome.bugs:
        return (
            index,
            "internal error",
            outcome.kinds,
            outcome.seconds,
            files.model + "\n" + "\n".join(outcome.bugs),
        )
    if outcome.seconds > fuzzing.HANG:
        return index, "slow", outcome.kinds, outcome.seconds, files.model
    label = "result" if all(s == 0 for s in outcome.statuses) else "model error"
    return index, label, outcome.kinds, outcome.seconds, ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="fuzz-findings")
    parser.add_argument("--hostile", action="store_true", help="models of hostile constants")
    args = parser.parse_args()
    global HOSTILE
    HOSTILE = args.hostile
    out = Path(args.out)
    outcomes, kinds = collections.Counter(), collections.Counter()
    slowest: list[tuple[float, int]] = []
    start = time.perf_counter()
    indices = range(args.first, args.first + args.count)
    context = multiprocessing.get_context("fork")
    with context.Pool(args.jobs, initializer=warm, maxtasksperchild=200) as pool:
        for done, (index, label, found, seconds, report) in enumerate(
            pool.imap_unordered(one, indices, chunksize=4), start=1
        ):
            outcomes[label] += 1
            kinds.update(found)
            slowest = sorted([*slowest, (seconds, index)], reverse=True)[:5]
            if report:
                out.mkdir(exist_ok=True)
                (out / f"{label.replace(' ', '_')}-{index}.txt").write_text(report)
            if done % 500 == 0:
                print(f"{done} models, {dict(outcomes)}", file=sys.stderr, flush=True)
    print(
        f"{args.count} models (seeds {args.first}..{args.first + args.count - 1}) in "
        f"{time.perf_counter() - start:.0f} s"
    )
    for label in ("result", "model error", "internal error", "slow", "hang", "executed"):
        print(f"  {label:15} {outcomes[label]}")
    print("kinds of error reported by mtt check:")
    for kind, count in kinds.most_common():
        print(f"  {kind:24} {count}")
    print("slowest: " + ", ".join(f"#{i} {s:.2f} s" for s, i in slowest))


if __name__ == "__main__":
    main()
