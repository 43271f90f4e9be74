# The two set-up commands of the README: `make examples` and `make test`.
# Both build .venv from requirements.lock (exact pins) on first use.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= build

.PHONY: examples test bench clean

$(VENV)/.installed: requirements.lock pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --disable-pip-version-check -r requirements.lock
	$(BIN)/pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .
	touch $@

examples: $(VENV)/.installed
	$(BIN)/wiris cdf build --all -o $(OUT)/cdf --base-url http://127.0.0.1:8000/cdf
	$(BIN)/wiris cdf validate $(OUT)/cdf/*.xml
	for f in examples/*.yaml; do $(BIN)/wiris mission compile $$f -o $(OUT)/missions || exit 1; done
	$(BIN)/wiris mission preview examples/solar-park.yaml -o $(OUT)/missions/solar-park.png
	$(BIN)/wiris mission preview examples/solar-park.yaml -o $(OUT)/missions/solar-park.html

test: $(VENV)/.installed
	$(BIN)/python -m pytest -q

bench: $(VENV)/.installed
	for f in bench/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(OUT) $(VENV)
