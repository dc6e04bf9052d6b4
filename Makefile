# Open Fleet: `make demo` runs the fleet with simulated robots; `make test` runs the whole suite.
PYTHON ?= python3.11
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
NATIVE := .native-build/stamp

.PHONY: bench-faults demo test lint format venv native browser clean bench-ingest bench-dispatch bench-routing bench-energy bench-reports bench-traffic bench-traffic-control bench-load bench-fuzz

$(STAMP): requirements.txt requirements-dev.txt
	@command -v $(PYTHON) >/dev/null || { echo "Python 3.11 is required ($(PYTHON) not found)"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements-dev.txt
	touch $(STAMP)

# The traffic planner's search loop compiled (Cython); without a compiler traffic plans in plain
# Python (same plans, about half the speed) and the build is tried again next time.
$(NATIVE): traffic/_holds.pyx traffic/_holds.pxd traffic/_search.pyx build_native.py $(STAMP)
	@mkdir -p .native-build
	@$(PY) build_native.py >.native-build/log 2>&1 && touch $(NATIVE) \
	  || { tail -20 .native-build/log; echo "compiled search loop not built: traffic plans in plain Python"; }

native: $(NATIVE)

venv: $(STAMP) $(NATIVE)

demo: $(STAMP) $(NATIVE)  ## run the fleet with simulated vehicles (embedded defaults unless URLs are set)
	$(PY) manage.py run_demo $(DEMO_ARGS)

# The system Chromium for page tests (Debian package; Playwright never downloads a browser).
browser:
	@command -v chromium >/dev/null || { \
	  if [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
	      || echo "could not install chromium: browser tests will be skipped"; \
	  else echo "chromium not installed: browser tests will be skipped"; fi; }

test: $(STAMP) $(NATIVE) browser  ## the whole suite; real services when they answer (FLEET_REQUIRE_SERVICES=1 insists)
	$(PY) -m pytest $(PYTEST_ARGS)

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/lint-imports
	$(VENV)/bin/mypy .
	$(PY) manage.py makemigrations --check --dry-run

bench-ingest: $(STAMP) $(NATIVE)  ## control's in-process cost per state message (bench/results/ingest.json)
	$(PY) -m bench.ingest $(BENCH_ARGS)

bench-routing: $(STAMP) $(NATIVE)  ## LIF import of a 5,000-node site and route times (bench/results/routing.json)
	$(PY) -m bench.routing $(BENCH_ARGS)

bench-dispatch: $(STAMP) $(NATIVE)  ## one dispatch cycle, batch assignment vs greedy (bench/results/dispatch.json)
	$(PY) -m bench.dispatch $(BENCH_ARGS)

bench-energy: $(STAMP) $(NATIVE)  ## 10 vehicles, 2 shared chargers, 8 simulated hours (bench/results/energy.json)
	$(PY) -m bench.energy $(BENCH_ARGS)

bench-reports: $(STAMP) $(NATIVE)  ## report pages over 30 days of 100 vehicles (bench/results/reports.json)
	$(PY) -m bench.reports $(BENCH_ARGS)

bench-traffic-control: $(STAMP) $(NATIVE)  ## release decisions inside control, simulated vehicles (bench/results/traffic_control.json)
	DJANGO_SETTINGS_MODULE=fleet.settings $(PY) -m bench.traffic_control $(BENCH_ARGS)

bench-load: $(STAMP) $(NATIVE)  ## 1,000 vehicles against the real processes, 120 s (bench/results/load.json, docs/LOAD.md)
	nice -n 5 $(PY) -m bench.load $(BENCH_ARGS)

bench-fuzz: $(STAMP)  ## control's inbound MQTT path under atheris, 1 h (bench/results/fuzz.json; BENCH_ARGS="--seconds 60")
	DJANGO_SETTINGS_MODULE=fleet.settings $(PY) -m bench.fuzz $(BENCH_ARGS)

bench-faults: $(STAMP) $(NATIVE)  ## the fault suite, each row on its own services (bench/results/faults_*.json; BENCH_ARGS="broker --full")
	$(PY) -m bench.faults $(BENCH_ARGS)

.PHONY: bench-live-map
bench-live-map: $(STAMP) $(NATIVE)  ## the live map with 1,000 vehicles in headless Chromium; needs REDIS_URL (bench/results/live_map.json)
	nice -n 5 $(PY) -m bench.live_map $(BENCH_ARGS)

bench-traffic: $(STAMP) $(NATIVE)  ## SIPP + ADG traffic in simulation, S1-S3 (bench/results/traffic_s*.json)
	$(PY) -m bench.traffic $(BENCH_ARGS)

format: $(STAMP)
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

clean:
	rm -rf $(VENV) staticfiles db.sqlite3* .native-build build traffic/*.so traffic/_holds.cpp traffic/_search.cpp
