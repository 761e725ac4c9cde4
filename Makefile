# The two commands: `make demo` and `make test`. Each creates .venv when missing.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= results

.PHONY: demo test lint bench screenshot clean translations lupdate

# the desk's translations (app/i18n): `make lupdate` gathers the source strings into the
# .ts (for Qt Linguist), `make translations` compiles it to the .qm the package ships
TS := app/i18n/station_patrol_zh_CN.ts
QM := $(TS:.ts=.qm)

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "Python 3.11+ is needed, found " + sys.version.split()[0]'
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	# --no-compile: the modules are byte-compiled when first imported (the demo and the
	# tests let Python write them), not all of every package at install (≈ 20 s)
	$(BIN)/python -m pip install --quiet --no-compile -e '.[dev]'
	touch $(STAMP)

translations: $(QM)

$(QM): $(TS) | $(STAMP)
	$(BIN)/pyside6-lrelease -silent $(TS) -qm $(QM)

lupdate: $(STAMP)
	$(BIN)/pyside6-lupdate -extensions py -locations none -no-obsolete -target-language zh_CN app -ts $(TS)

demo: $(STAMP) $(QM)
	env -u PYTHONDONTWRITEBYTECODE $(BIN)/station-patrol --demo --patrol --out $(OUT)

lint: $(STAMP)
	$(BIN)/ruff check app sim_robot tests bench
	$(BIN)/lint-imports

# three workers on CI's 2 cores: the tests that start robots and desks wait on their
# processes a good part of their time, and a third worker fills it (fresh clones here:
# 553 s of pytest for 942 s of CPU with two workers; 467-554 s for 892-1048 s with
# three, this machine's speed drifting); --dist loadfile keeps each test module on one
# worker so a module's shared fixture (e.g. the headless demo's first run) runs once; a worker that
# dies (a crash in native code) ends the run at once with the test it was running named,
# instead of being replaced: a replaced worker can leave --dist loadfile waiting forever
# --no-loadscope-reorder: modules run in tests/conftest.py's order, the dearest (marked
# slow) first, so the workers end together
# env -u PYTHONDONTWRITEBYTECODE: where it is set, every robot and desk process the tests
# start (a few hundred) compiled the sources again (≈ 0.3-0.5 s each)
test: lint $(QM)
	QT_QPA_PLATFORM=offscreen env -u PYTHONDONTWRITEBYTECODE $(BIN)/python -m pytest -q -n 3 --dist loadfile --no-loadscope-reorder --max-worker-restart=0

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[bench]'
	$(BIN)/python bench/link_bench.py

screenshot: $(STAMP)
	QT_QPA_PLATFORM=offscreen $(BIN)/python bench/screenshot.py docs/screenshot.png

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
