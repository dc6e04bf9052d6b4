# Open Fleet: `make demo` runs the fleet with simulated robots; `make test` runs the whole suite.
PYTHON ?= python3.11
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: bench-faults demo test lint format venv browser clean bench-ingest bench-dispatch bench-routing bench-energy bench-reports bench-traffic bench-traffic-control bench-load

$(STAMP): requirements.txt requirements-dev.txt
	@command -v $(PYTHON) >/dev/null || { echo "Python 3.11 is required ($(PYTHON) not found)"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements-dev.txt
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)  ## run the fleet with simulated vehicles (embedded defaults unless URLs are set)
	$(PY) manage.py run_demo $(DEMO_ARGS)

# The system Chromium for page tests (Debian package; Playwright never downloads a browser).
browser:
	@command -v chromium >/dev/null || { \
	  if [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
	      || echo "could not install chromium: browser tests will be skipped"; \
	  else echo "chromium not installed: browser tests will be skipped"; fi; }

test: $(STAMP) browser  ## the whole suite; real services when they answer (FLEET_REQUIRE_SERVICES=1 insists)
	$(PY) -m pytest $(PYTEST_ARGS)

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/lint-imports
	$(VENV)/bin/mypy .
	$(PY) manage.py makemigrations --check --dry-run

bench-ingest: $(STAMP)  ## control's in-process cost per state message (bench/results/ingest.json)
	$(PY) -m bench.ingest $(BENCH_ARGS)

bench-routing: $(STAMP)  ## LIF import of a 5,000-node site and route times (bench/results/routing.json)
	$(PY) -m bench.routing $(BENCH_ARGS)

bench-dispatch: $(STAMP)  ## one dispatch cycle, batch assignment vs greedy (bench/results/dispatch.json)
	$(PY) -m bench.dispatch $(BENCH_ARGS)

bench-energy: $(STAMP)  ## 10 vehicles, 2 shared chargers, 8 simulated hours (bench/results/energy.json)
	$(PY) -m bench.energy $(BENCH_ARGS)

bench-reports: $(STAMP)  ## report pages over 30 days of 100 vehicles (bench/results/reports.json)
	$(PY) -m bench.reports $(BENCH_ARGS)

bench-traffic-control: $(STAMP)  ## release decisions inside control, simulated vehicles (bench/results/traffic_control.json)
	DJANGO_SETTINGS_MODULE=fleet.settings $(PY) -m bench.traffic_control $(BENCH_ARGS)

bench-load: $(STAMP)  ## 1,000 vehicles against the real processes, 120 s (bench/results/load.json, docs/LOAD.md)
	nice -n 5 $(PY) -m bench.load $(BENCH_ARGS)

bench-faults: $(STAMP)  ## the fault suite, each row on its own services (bench/results/faults_*.json; BENCH_ARGS="broker --full")
	$(PY) -m bench.faults $(BENCH_ARGS)

.PHONY: bench-live-map
bench-live-map: $(STAMP)  ## the live map with 1,000 vehicles in headless Chromium; needs REDIS_URL (bench/results/live_map.json)
	nice -n 5 $(PY) -m bench.live_map $(BENCH_ARGS)

bench-traffic: $(STAMP)  ## SIPP + ADG traffic in simulation, S1-S3 (bench/results/traffic_s*.json)
	$(PY) -m bench.traffic $(BENCH_ARGS)

format: $(STAMP)
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

clean:
	rm -rf $(VENV) staticfiles db.sqlite3*
