# The README's two commands: `make run` and `make test`. Both install what they need on a
# fresh Debian machine with Python 3.11 (a venv in .venv, the package in editable mode).

PYTHON ?= $(shell command -v python3.11 2>/dev/null || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp

# Debian packages the project needs; installed only when their command is missing.
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
APT_INSTALL := DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q --no-install-recommends

.PHONY: run test lint check-python system-deps test-deps web web-test dist clean

system-deps:
	@command -v dot >/dev/null || { $(SUDO) apt-get update -q && $(APT_INSTALL) graphviz; }

# Only the tests need a browser: the e2e tests drive Debian's chromium through Playwright;
# and poppler's pdftoppm, a second program that opens the PDF pictures `xabsl picture` writes.
test-deps: system-deps
	@test -x /usr/bin/chromium || { $(SUDO) apt-get update -q && $(APT_INSTALL) chromium; }
	@command -v pdftoppm >/dev/null || { $(SUDO) apt-get update -q && $(APT_INSTALL) poppler-utils; }

# The studio UI (web/): `npm ci` when node_modules is missing or package-lock.json changed,
# then a Vite build into web/dist, which `xabsl serve` serves at `/`.
WEB_STAMP   := web/node_modules/.xabsl-ci-stamp
WEB_SOURCES := $(shell find web/src web/index.html web/vite.config.ts web/tsconfig.json -type f 2>/dev/null)

$(WEB_STAMP): web/package-lock.json web/package.json
	@command -v npm >/dev/null || { echo "npm (Node.js >= 20.19) is required to build the studio UI" >&2; exit 1; }
	cd web && npm ci --no-audit --no-fund --loglevel=error
	touch $(WEB_STAMP)

web/dist/index.html: $(WEB_STAMP) $(WEB_SOURCES)
	cd web && npm run build --silent

web: web/dist/index.html

web-test: $(WEB_STAMP)
	cd web && npm test --silent

check-python:
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "Python >= 3.11 is required, found " + sys.version' 

$(STAMP): pyproject.toml | check-python
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -e '.[test,bench]'
	touch $(STAMP)

# The tests also need the optional Ray extra (the tournament's Ray test); `make run` does not.
RAY_STAMP := $(VENV)/.ray-installed-stamp
$(RAY_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -e '.[test,bench,ray]'
	touch $(RAY_STAMP)

# The studio on http://127.0.0.1:8000 with the soccer example (Ctrl+C stops it).
run: $(STAMP) system-deps web
	$(BIN)/xabsl serve examples/soccer

# ruff (lint, docstrings of public names, formatting) and mypy (strict on every package).
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: $(STAMP) $(RAY_STAMP) test-deps lint web web-test
	$(BIN)/python -m pytest

# The sdist and, built from it, the wheel (with the studio UI inside) into dist/; tests/install
# builds and installs the same into a fresh venv as part of `make test`.
dist: $(STAMP) web
	$(BIN)/python -m build --outdir dist .

clean:
	rm -rf $(VENV) build dist *.egg-info
