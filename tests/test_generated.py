"""Every committed generated/MODEL.py is what `make compile` writes now: `mtt compile
models/MODEL.bg -o generated/MODEL.py` with the options the Makefile gives that model
(its `COMPILE_OPTIONS_MODEL := ...` lines, read here so that the two cannot drift)."""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
MAKEFILE = (ROOT / "Makefile").read_text("utf-8")
MODELS = sorted(path.stem for path in (ROOT / "models").glob("*.bg"))
OPTIONS = {
    name: shlex.split(value)
    for name, value in re.findall(r"^COMPILE_OPTIONS_(\w+)\s*:?=[ \t]*(.*?)[ \t]*$", MAKEFILE, re.M)
}


def test_the_makefile_compiles_every_model_with_its_options():
    assert "GENERATED := $(patsubst models/%.bg,generated/%.py,$(MODELS))" in MAKEFILE
    assert "\t$(MTT) compile $< -o $@ $(COMPILE_OPTIONS_$*)\n" in MAKEFILE
    assert set(OPTIONS) <= set(MODELS), "COMPILE_OPTIONS_ for a model that does not exist"
    assert OPTIONS["absorber"] == ["--keep", "tau,l"]  # the paper's eq. (27), symbolic
    assert {path.stem for path in (ROOT / "generated").glob("*.py")} == set(MODELS)


@pytest.mark.parametrize("model", MODELS)
def test_committed_module_is_what_make_compile_writes(model, tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # the source is named as the Makefile names it
    written = tmp_path / f"{model}.py"
    argv = ["compile", f"models/{model}.bg", "-o", str(written), *OPTIONS.get(model, [])]
    messages = io.StringIO()
    with contextlib.redirect_stdout(messages), contextlib.redirect_stderr(messages):
        status = main(argv)
    assert status == 0, messages.getvalue()
    committed = (ROOT / "generated" / f"{model}.py").read_text("utf-8")
    assert written.read_text("utf-8") == committed, f"stale: run `make compile` ({model})"
