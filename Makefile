# Two commands matter: `make test` and `make demo`. Both create .venv when it is missing.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
MTT := $(BIN)/mtt
STAMP := $(VENV)/.installed-stamp
MODELS := $(wildcard models/*.bg)

.PHONY: all test demo lint format check clean compile figures dc_drive absorber absorber_filter \
	absorber_cost dc_motor rlc3 FORCE

all: test

$(STAMP): pyproject.toml
	@echo "Installing mtt and its test tools into $(VENV) (the first time: a few minutes)..."
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $(STAMP)
	@echo "Installed. To type \`mtt\` in this shell: source $(VENV)/bin/activate"
	@echo "(or run $(CURDIR)/$(BIN)/mtt; optional extras: $(BIN)/pip install -e '.[control]')"

# about 1500 tests over every core (pytest-xdist); on 2 cores about 3 minutes: a dot per test, the percentage done
test: $(STAMP)
	@echo "Running the tests (about 3 minutes on 2 cores; a dot per test passed)..."
	$(BIN)/python -m pytest -q -n auto --durations=5

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(STAMP)
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

check: $(STAMP)
	$(MTT) check --identifiability $(MODELS)

demo: $(STAMP)
	$(MTT) check $(MODELS)
	@for model in $(MODELS); do $(MTT) show $$model; echo; done
	$(MAKE) --no-print-directory compile figures REPORT=true
	@echo; echo "Final estimates (tables in $(FIGURES)/*.txt):"
	@for table in $(TABLES); do echo; cat $$table; done
	@echo; echo "To type \`mtt\` yourself: source $(VENV)/bin/activate (or run $(MTT))"

# Estimators ----------------------------------------------------------------------------
# `mtt compile` options per model. The absorber keeps tau and l symbolic, so that its
# Theta is exactly the paper's eq. (27) with tau = 2, l = 0.5 supplied at run time
# (substituting them first would give a canonical Theta scaled by 2, and with the same
# S0 a different trajectory). Its experiments below pass the same option.
COMPILE_OPTIONS_absorber := --keep tau,l
COMPILE_OPTIONS_absorber_stages := --keep tau,l
# dc_motor (ra, jl) and rlc3 (r, l, c) identify all their unknowns together.
# The nonlinear models (issue 19) compile the estimator of their small-signal model about
# an operating point: the tanks below the upper tank's rim, the pendulum hanging (branch 1
# of 2: mtt equilibrium models/pendulum.bg --u 1), the clipper with its diode conducting.
COMPILE_OPTIONS_two_tanks := --at u=10
COMPILE_OPTIONS_pendulum := --at u=1 --branch 1
COMPILE_OPTIONS_diode_clipper := --at u=1
GENERATED := $(patsubst models/%.bg,generated/%.py,$(MODELS))

compile: $(GENERATED)

generated/%.py: models/%.bg $(STAMP) FORCE
	$(MTT) compile $< -o $@ $(COMPILE_OPTIONS_$*)

FORCE:

# The paper's experiments (sections 6 and 7), one command line each --------------------
# Figures land in figures/, the table of final estimates beside them (.txt).
# Every experiment: unit step input sampled every 0.01 s, beta = 0.1, S0 = 1e-4.
FIGURES := figures
PAPER := --beta 0.1 --S0 1e-4
ABSORBER := models/absorber.bg $(COMPILE_OPTIONS_absorber) --t-end 4 --noise-uniform 0.02
# How each experiment shows its table; `make demo` shows them all once, at the end.
REPORT ?= cat
# (absorber_cost.txt is not shown: Fig. 8 runs Fig. 7's estimates, the same table)
TABLES := $(addprefix $(FIGURES)/,dc_drive.txt absorber.txt absorber_filter.txt dc_motor.txt \
	rlc3.txt)

figures: dc_drive absorber absorber_filter absorber_cost dc_motor rlc3

# Fig. 2: DC drive, k = 10, 10 s, C(s) = (1 + s)^5, from k0 = 0, 5 and 20.
dc_drive: $(STAMP)
	@mkdir -p $(FIGURES)
	$(MTT) estimate models/dc_drive.bg --t-end 10 $(PAPER) --filter "(1+s)^5" --k0 0 5 20 \
		--plot $(FIGURES)/fig2_dc_drive.png > $(FIGURES)/dc_drive.txt
	@$(REPORT) $(FIGURES)/dc_drive.txt

# Figs. 5 and 6: absorber, k = 0.72, 4 s, output noise uniform in [-0.02, 0.02],
# C(s) = (1 + s)^4, from k0 = 0, 0.25, 0.5, 0.75 and 1.
absorber: $(STAMP)
	@mkdir -p $(FIGURES)
	$(MTT) estimate $(ABSORBER) $(PAPER) --filter "(1+s)^4" --k0 0 0.25 0.5 0.75 1 \
		--data-plot $(FIGURES)/fig5_absorber_data.png \
		--plot $(FIGURES)/fig6_absorber_estimates.png > $(FIGURES)/absorber.txt
	@$(REPORT) $(FIGURES)/absorber.txt

# Fig. 7: absorber, k0 = 1, C(s) = (1 + sT)^4 for T = 0.5, 1 and 2.
absorber_filter: $(STAMP)
	@mkdir -p $(FIGURES)
	$(MTT) estimate $(ABSORBER) $(PAPER) --filter-T 0.5 1 2 --k0 1 \
		--plot $(FIGURES)/fig7_absorber_filter.png > $(FIGURES)/absorber_filter.txt
	@$(REPORT) $(FIGURES)/absorber_filter.txt

# Fig. 8: the normalised cost at t = 4 against k, for the three filters of Fig. 7.
absorber_cost: $(STAMP)
	@mkdir -p $(FIGURES)
	$(MTT) estimate $(ABSORBER) $(PAPER) --filter-T 0.5 1 2 --k0 1 --cost-range -1 1 \
		--cost-plot $(FIGURES)/fig8_absorber_cost.png > $(FIGURES)/absorber_cost.txt
	@$(REPORT) $(FIGURES)/absorber_cost.txt

# Several unknowns (beyond the paper, issue 11): a PRBS held between switches, white
# Gaussian output noise at 20 dB, every unknown fitted together (refined instrumental
# variables, the global minimum within the default box: the file's values within a factor
# of 10), with its standard error; the compare plot beside the table.
NOISY := --signal prbs --noise-snr 20 --hold zoh

# The DC motor's armature resistance ra and load inertia jl (true 1 and 10).
dc_motor: $(STAMP)
	@mkdir -p $(FIGURES)
	$(MTT) fit models/dc_motor.bg $(NOISY) --period 0.5 --t-end 60 --dt 0.01 \
		--plot $(FIGURES)/fit_dc_motor.png > $(FIGURES)/dc_motor.txt
	@$(REPORT) $(FIGURES)/dc_motor.txt

# The series RLC circuit's r, l and c (true 2, 0.5 and 0.1).
rlc3: $(STAMP)
	@mkdir -p $(FIGURES)
	$(MTT) fit models/rlc3.bg $(NOISY) --period 0.2 --t-end 10 --dt 0.002 \
		--plot $(FIGURES)/fit_rlc3.png > $(FIGURES)/rlc3.txt
	@$(REPORT) $(FIGURES)/rlc3.txt

# Benchmarks: each bench/*.py prints its table (bench/README.md keeps the current ones).
.PHONY: bench
bench: $(STAMP)
	@for script in bench/[!_]*.py; do echo "== $$script"; $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) build dist .pytest_cache .ruff_cache
