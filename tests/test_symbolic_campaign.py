"""A small bounded sample of bench/symbolic_campaign.py (issue 23 item 1): fully symbolic
ladders, meshes and bridges end with a result or with too_large, never by exhausting the
machine (the whole campaign, to 100 sections, is in bench/)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import mtt

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "bench"))

from symbolic_campaign import bridge, ladder, mesh  # noqa: E402


@pytest.mark.parametrize(
    ("generator", "size", "outcome"),
    [(ladder, 100, "too_large"), (ladder, 8, "result"), (mesh, 4, "result"), (bridge, 1, "result")],
)
def test_symbolic_models_end_with_a_result_or_too_large(generator, size, outcome):
    model = mtt.load(generator(size))
    try:
        found = model.transfer_function.den
    except mtt.MttError as exc:
        assert exc.kind == "too_large" and "--max-terms" in str(exc)
        found = "too_large"
    assert (found if found == "too_large" else "result") == outcome
