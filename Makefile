# The two set-up commands of the README: `make examples` and `make test`.
# `make examples` builds .venv from requirements.lock (the run-time pins only); `make test` adds
# requirements-test.lock (pytest, hypothesis and the real peers: MAVSDK, MAVProxy, lupa, playwright).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= build
PIP := $(BIN)/pip install --quiet --disable-pip-version-check
CHROMIUM ?= chromium
CHROMIUM_FLAGS := --headless --no-sandbox --disable-gpu --disable-background-networking \
	--disable-component-update --disable-sync --no-first-run --hide-scrollbars

.PHONY: examples test bench clean

$(VENV)/.installed: requirements.lock pyproject.toml
	$(PY) -m venv $(VENV)
	$(PIP) -r requirements.lock
	$(PIP) --no-deps --no-build-isolation -e .
	touch $@

$(VENV)/.installed-test: $(VENV)/.installed requirements-test.lock
	$(PIP) -r requirements.lock -r requirements-test.lock
	touch $@

examples: $(VENV)/.installed
	$(BIN)/wiris cdf build --all -o $(OUT)/cdf --base-url http://127.0.0.1:8000/cdf
	$(BIN)/wiris cdf validate $(OUT)/cdf/*.xml
	for f in examples/*.yaml; do $(BIN)/wiris mission compile $$f -o $(OUT)/missions || exit 1; done
	$(BIN)/wiris mission preview examples/solar-park.yaml -o $(OUT)/missions/solar-park.png
	$(BIN)/wiris mission preview examples/solar-park.yaml -o $(OUT)/missions/solar-park.html
	$(BIN)/wiris mission preview examples/powerline-corridor.yaml -o $(OUT)/missions/powerline-corridor.html
	@# a screenshot of the interactive map, taken by headless Chromium when it is installed
	@if command -v $(CHROMIUM) >/dev/null; then \
	  $(CHROMIUM) $(CHROMIUM_FLAGS) --window-size=1400,1000 --virtual-time-budget=5000 \
	    --screenshot=$(abspath $(OUT))/missions/solar-park.map.png file://$(abspath $(OUT))/missions/solar-park.html \
	    2>/dev/null && echo "wrote $(OUT)/missions/solar-park.map.png"; \
	else echo "no $(CHROMIUM) found: no screenshot of $(OUT)/missions/solar-park.html (apt-get install chromium)"; fi

test: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q

bench: $(VENV)/.installed-test
	for f in bench/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(OUT) $(VENV)
