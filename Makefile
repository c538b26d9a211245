# Two commands on a fresh machine: `make run` and `make test`.
VENV    ?= .venv
PY      := $(VENV)/bin/python
PIP     := $(VENV)/bin/pip
STAMP   := $(VENV)/.installed
TSTAMP  := $(VENV)/.installed-test
PYTHON  ?= python3

.PHONY: install install-test run test lint clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(PY)
	$(PIP) install --quiet -e .
	touch $@

install: $(STAMP)

$(TSTAMP): pyproject.toml | $(PY)
	$(PIP) install --quiet -e '.[test]'
	touch $(STAMP) $@

install-test: $(TSTAMP)

run: install
	$(VENV)/bin/hetros graph examples/talker_listener/project.yaml
	$(VENV)/bin/hetros launch examples/talker_listener/project.yaml --duration 5

lint: install-test
	$(VENV)/bin/ruff check src tests examples benchmarks
	$(VENV)/bin/mypy --strict src

test: lint
	$(VENV)/bin/pytest -q

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache
