# geofrac developer entry points. Each target creates the virtual environment on first use.
#   make quickstart   run jobs/quickstart.toml (1 rank), results in results/quickstart
#   make test         ruff, the test suite on 1 rank, then the MPI tests on 2 ranks
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.geofrac-installed
NP ?= 2

.PHONY: quickstart test lint test-serial test-mpi bench clean

quickstart: $(STAMP)
	$(VENV)/bin/geofrac run jobs/quickstart.toml

test: lint test-serial test-mpi

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

test-serial: $(STAMP)
	$(PY) -m pytest --with-mpi

test-mpi: $(STAMP)
	$(VENV)/bin/mpiexec -n $(NP) $(PY) -m mpi4py -m pytest --only-mpi -p no:cacheprovider

bench: $(STAMP)
	$(VENV)/bin/geofrac bench cantilever --elements cst,p2,rgnt,gnt --out results/bench-cantilever

$(STAMP): pyproject.toml scripts/bootstrap.sh
	bash scripts/bootstrap.sh $(VENV)

clean:
	rm -rf results .pytest_cache
