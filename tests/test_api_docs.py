"""Every example in the API's docstrings and in docs/api.md runs and prints what it says."""

from __future__ import annotations

import doctest
from pathlib import Path

import pytest

import mtt
import mtt.api.experiments
import mtt.api.loading
import mtt.api.matrix
import mtt.api.model
import mtt.api.results

ROOT = Path(__file__).resolve().parent.parent
OPTIONS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


MODULES = [
    mtt,
    mtt.api.experiments,
    mtt.api.loading,
    mtt.api.matrix,
    mtt.api.model,
    mtt.api.results,
]


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__)
def test_docstring_examples(module):
    results = doctest.testmod(module, optionflags=OPTIONS)
    assert results.attempted > 0
    assert results.failed == 0


def test_docs_api_md_examples():
    results = doctest.testfile(str(ROOT / "docs" / "api.md"), module_relative=False,
                               optionflags=OPTIONS)  # fmt: skip
    assert results.attempted > 20
    assert results.failed == 0
