# geofrac developer entry points. Each target creates the virtual environment on first use,
# with the locked versions of scripts/constraints.txt.
#   make quickstart   run jobs/quickstart.toml (1 rank), results in results/quickstart
#   make test         ruff, mypy, the test suite on 1 rank, then the MPI tests on 2 ranks
#   make test-robust  the runs under a different machine's round-off (perturbed input, a
#                     renumbered mesh, 2 ranks): the tests marked robust
#   make test-latest  make test in a fresh .venv-latest with the newest releases
#   make lock         write scripts/constraints.txt from .venv-latest (after test-latest)
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.geofrac-installed
NP ?= 2
LATEST := .venv-latest

.PHONY: quickstart test lint typecheck test-serial test-mpi test-robust test-latest lock bench clean

quickstart: $(STAMP)
	$(VENV)/bin/geofrac run jobs/quickstart.toml --overwrite

test: lint typecheck test-serial test-mpi

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

# the files of pyproject.toml's [tool.mypy] files
typecheck: $(STAMP)
	$(VENV)/bin/mypy

# the 1-rank tests on NP worker processes (pytest-xdist; one test module per worker at a
# time, so that a module's fixtures are built once)
test-serial: $(STAMP)
	$(PY) -m pytest --with-mpi -m "not robust" -n $(NP) --dist loadscope

test-mpi: $(STAMP)
	$(VENV)/bin/mpiexec -n $(NP) $(PY) -m mpi4py -m pytest --only-mpi -p no:cacheprovider -m "not robust"

test-robust: $(STAMP)
	$(PY) -m pytest --with-mpi -m robust -n $(NP) --dist loadscope
	$(VENV)/bin/mpiexec -n $(NP) $(PY) -m mpi4py -m pytest --only-mpi -p no:cacheprovider -m robust

test-latest:
	rm -rf $(LATEST)
	GEOFRAC_LATEST=1 bash scripts/bootstrap.sh $(LATEST)
	$(LATEST)/bin/pip freeze --all --exclude-editable | diff scripts/constraints.txt - \
		| grep '^[<>] [^#]' || echo "geofrac: the newest releases are the locked ones"
	$(MAKE) test VENV=$(LATEST)

lock:
	@test -x $(LATEST)/bin/pip || { echo "run make test-latest first" >&2; exit 1; }
	{ sed -n '/^#/p' scripts/constraints.txt; \
	  $(LATEST)/bin/pip freeze --all --exclude-editable; } > scripts/constraints.txt.new
	mv scripts/constraints.txt.new scripts/constraints.txt
	git diff --stat scripts/constraints.txt

bench: $(STAMP)
	$(VENV)/bin/geofrac bench cantilever --elements cst,p2,rgnt,gnt --out results/bench-cantilever

$(STAMP): pyproject.toml scripts/bootstrap.sh scripts/constraints.txt
	bash scripts/bootstrap.sh $(VENV)

clean:
	rm -rf results .pytest_cache
