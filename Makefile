# Two commands matter: `make test` and `make demo`. Both create .venv when it is missing.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
MTT := $(BIN)/mtt
STAMP := $(VENV)/.installed-stamp
MODELS := $(wildcard models/*.bg)

.PHONY: all test demo lint format check clean

all: test

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(STAMP)
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

check: $(STAMP)
	$(MTT) check $(MODELS)

demo: $(STAMP)
	$(MTT) check $(MODELS)
	@for model in $(MODELS); do $(MTT) show $$model; echo; done

clean:
	rm -rf $(VENV) build dist .pytest_cache .ruff_cache
