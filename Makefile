# make demo | make test | make bench | make lint  -- everything runs in a local virtual environment (.venv)
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: install demo test bench bench-paired lint clean

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(BIN)/stipple torus samples/astronaut256.png -M 30150 \
		-o out/astronaut.csv -o out/astronaut.svg -o out/astronaut.png
	$(BIN)/stipple sphere --config configs/fig5.5.toml --dot-radius 1.5mm \
		-o out/rbf-nodes.csv -o out/rbf-nodes.png -o out/rbf-nodes.geojson
	@echo "wrote out/astronaut.{csv,svg,png} and out/rbf-nodes.{csv,png,geojson}"

test: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python bench/run.py --output bench/results.json

# Whole commands against another version, e.g. make bench-paired OLD=../base/.venv/bin/stipple (docs/performance.md)
bench-paired: $(STAMP)
	$(BIN)/python bench/paired.py --old "$(OLD)" --output bench/paired.json

lint: $(STAMP)
	$(BIN)/ruff check stipple tests bench

clean:
	rm -rf $(VENV) out .pytest_cache
