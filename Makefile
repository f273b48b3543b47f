# One idempotent install, then the demo or the tests. See README.md.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# Off-screen OpenGL through EGL, no display needed (render/gl.py falls back to OSMesa).
export PYOPENGL_PLATFORM ?= egl

.PHONY: install demo test lint clean gl

install: gl $(STAMP)

gl:
	@bash tools/ensure_gl.sh

$(STAMP): requirements.txt pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.txt
	$(BIN)/python -m pip install --quiet --no-deps -e .
	touch $(STAMP)

demo: install
	$(BIN)/camtask demo --out out/demo

test: install
	$(BIN)/python -m pytest -q

lint: install
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out build *.egg-info
