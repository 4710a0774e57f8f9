# posekit — the two commands of the README:
#   make lab    set up (virtual environment, packages) and open JupyterLab on the notebooks
#   (make studio: the posing studio alone, served by Voila as a browser app)
#   make test   set up (and Chromium for the browser test) and run every test: unit tests,
#               every notebook under nbval, the headless-browser check of the 3D widget (both cores)
#   make test-unit        the inner loop: the unit tests only (no notebook, no browser)
#   make test-portable    every notebook under nbval as other CPUs would run it (tools/test_portable.py)
#   make test-latest      the lessons and widget tests against the newest notebook stack, ignoring pyproject's
#                         upper bounds, in .venv-latest (tools/test_latest.py; LATEST_ARGS=--pre for pre-releases)
#   instructors: make slides (reveal.js slides of every lesson), make solutions (the lessons with
#               their exercise solutions, executed), make course (one static page: lessons, slides,
#               benchmark report) -- all under build/, openable from disk; slides and course are the
#               students' (no solution in them) unless INSTRUCTOR=1
#   make hub    the lessons served to a class by JupyterHub on this machine (trial login; docs/hub.md)
#   make docs   rewrite the generated documentation pages: docs/cli.md (the argument parser) and docs/benchmarks.md
#               (the results files under data_samples/results)
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.posekit-installed
# larger real mocap, read by path (never copied): ../shared/data when it exists
export POSEKIT_DATA_DIR ?= $(if $(wildcard ../shared/data),$(abspath ../shared/data),)
ROOT_FLAG := $(if $(filter 0,$(shell id -u)),--allow-root,)

.PHONY: setup warm lab studio test test-unit test-portable test-latest browser-deps bench clean course-assets slides course solutions docs hub

# JupyterLab settings for this environment: no news pop-up, no update check (nothing is fetched)
LAB_OVERRIDES := $(VENV)/share/jupyter/lab/settings/overrides.json

$(STAMP): pyproject.toml tools/jupyterlab_overrides.json
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e ".[dev]"
	mkdir -p $(dir $(LAB_OVERRIDES)) && cp tools/jupyterlab_overrides.json $(LAB_OVERRIDES)
	@# nbgrader (a dev dependency: posekit course nbgrader and its tests) would add its menus, panels and server
	@# extensions to every JupyterLab this environment starts, the lessons' included; they are for an instructor's
	@# grading server (docs/nbgrader.md), so they are off here
	$(VENV)/bin/jupyter labextension disable --level=sys_prefix @jupyter/nbgrader >/dev/null 2>&1 || true
	for e in formgrader validate_assignment assignment_list course_list; do \
	  $(VENV)/bin/jupyter server extension disable --sys-prefix nbgrader.server_extensions.$$e >/dev/null 2>&1 || true; done
	touch $(STAMP)

setup: $(STAMP)

# every solver's numba kernels compiled into the on-disk cache once, before a lesson, the studio or the tests wait
# for them (25-30 s on 2 cores after a fresh clone or a source change; about 2 s once done)
warm: setup
	$(VENV)/bin/posekit warm

browser-deps:
	@if [ ! -x /usr/bin/chromium ]; then \
	  SUDO=$$([ "$$(id -u)" = 0 ] || echo sudo); \
	  echo "installing Debian's chromium and chromium-driver for the browser test"; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq chromium chromium-driver; \
	fi

# reveal.js and MathJax for the slides and the course page (npm registry; copied next to the pages)
COURSE_JS := tools/course/node_modules/.package-lock.json
$(COURSE_JS): tools/course/package.json tools/course/package-lock.json
	@if ! command -v npm >/dev/null; then \
	  SUDO=$$([ "$$(id -u)" = 0 ] || echo sudo); \
	  echo "installing Debian's nodejs and npm for reveal.js and MathJax"; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq nodejs npm; \
	fi
	cd tools/course && npm ci --no-audit --no-fund --loglevel=error
	touch $(COURSE_JS)

course-assets: $(COURSE_JS)

# the students' slides and course page hold no exercise solution; INSTRUCTOR=1 builds the instructor's version
# (solutions and notes in the speaker notes, the lessons' instructor pages) into build/course-instructor
COURSE_OUT ?= $(if $(INSTRUCTOR),build/course-instructor,build/course)
slides: setup course-assets
	$(VENV)/bin/posekit course slides --out $(COURSE_OUT) $(if $(INSTRUCTOR),--instructor)

course: setup course-assets
	$(VENV)/bin/posekit course build --out $(COURSE_OUT) $(if $(INSTRUCTOR),--instructor)

# every lesson's instructor version, executed (about as long as running all lessons: ~6 min on 2 cores)
solutions: setup course-assets
	$(VENV)/bin/posekit exercises solutions $(or $(LESSON),all) --html --out build/instructor

# the kernel's websocket sends each message at once, not after Nagle's wait (posekit/viz/websocket.py): a widget
# update reaches the browser about 30 ms sooner
NODELAY := kernel_websocket_connection_class=posekit.viz.websocket.NoDelayConnection

lab: setup warm
	$(VENV)/bin/jupyter lab notebooks/ $(ROOT_FLAG) --LabApp.news_url= \
	  --LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate $(NODELAY:%=--ServerApp.%) $(LAB_ARGS)

# the posing studio alone as a browser app (Voila, notebooks/studio.ipynb; lesson 06 teaches it), one kernel kept
# preheated for the next visitors (STUDIO_POOL=N keeps N, default 3 as posekit.viz.studio_app.STUDIO_POOL: about
# 0.25 GB each, so 0.75 GB waiting; set the class's size for a class arriving at once); Ctrl-C
# stops it and its kernels. STUDIO_DATA (a data set or BVH folder), STUDIO_WEIGHTS (your trained models),
# STUDIO_SOLVERS (2-4 names) choose what it poses, STUDIO_LICENCE (your data's licence) is shown with it; STUDIO_ANTIALIAS=0 draws the views without antialiasing, for
# browsers without a GPU (software WebGL). The page is Voila's lab page less its CDN stylesheets
# (posekit/viz/voila): it asks nothing of the internet
# A relative STUDIO_DATA / STUDIO_WEIGHTS is read from the folder you typed it in: the shell's $PWD, which make -C
# leaves as it was (make's own $(CURDIR) is this checkout); a data set name (bandai-mini) stays a name.
USER_DIR := $(or $(PWD),$(CURDIR))
user_path = $(if $(1),$(if $(filter /%,$(1)),$(1),$(if $(or $(wildcard $(USER_DIR)/$(1)),$(findstring /,$(1)),$(findstring .,$(1))),$(abspath $(USER_DIR)/$(1)),$(1))))
studio: setup warm
	cd notebooks && POSEKIT_STUDIO_DATA="$(call user_path,$(STUDIO_DATA))" POSEKIT_STUDIO_SOLVERS="$(STUDIO_SOLVERS)" \
	  $(if $(STUDIO_WEIGHTS),POSEKIT_WEIGHTS_DIR="$(if $(filter /%,$(STUDIO_WEIGHTS)),$(STUDIO_WEIGHTS),$(abspath $(USER_DIR)/$(STUDIO_WEIGHTS)))") \
	  $(if $(STUDIO_LICENCE),POSEKIT_STUDIO_LICENCE="$(STUDIO_LICENCE)") \
	  $(if $(STUDIO_ANTIALIAS),POSEKIT_ANTIALIAS="$(STUDIO_ANTIALIAS)") \
	  JUPYTER_PATH="../posekit/viz/voila$(if $(JUPYTER_PATH),:$(JUPYTER_PATH))" \
	  ../$(VENV)/bin/voila studio.ipynb --port=$(or $(STUDIO_PORT),8866) --template=posekit \
	  --preheat_kernel=True --pool_size=$(or $(STUDIO_POOL),3) \
	  --MappingKernelManager.cull_idle_timeout=600 --MappingKernelManager.cull_interval=60 $(NODELAY:%=--Voila.%) \
	  $(STUDIO_ARGS)

# both cores: tests grouped by module, each notebook on one worker, the browser tests together
# (tests/conftest.py); PYTEST_WORKERS=0 runs everything in one process
PYTEST_WORKERS ?= 2
XDIST = $(if $(filter 0,$(PYTEST_WORKERS)),,-n $(PYTEST_WORKERS) --dist loadfile)
test: setup browser-deps course-assets warm
	$(PY) -m pytest $(XDIST) --durations=15 $(PYTEST_ARGS)

test-unit: setup warm
	$(PY) -m pytest tests -m "not browser and not slow" $(XDIST) $(PYTEST_ARGS)

# PORTABLE_VARIANTS: a subset of `python tools/test_portable.py --list`
test-portable: setup
	$(PY) tools/test_portable.py $(PORTABLE_VARIANTS)

# the newest releases of jupyterlab, ipywidgets, pythreejs, voila, nbval, playwright, numpy ... (torch: the CPU wheel)
test-latest: browser-deps
	$(PYTHON) tools/test_latest.py $(LATEST_ARGS)

# a class on one machine, for trying it (docs/hub.md): JupyterHub with a trial login (any name, HUB_PASSWORD or
# "posekit-trial"), each student's server on their own copy of the lessons (run as root: each as their own system
# user in a sandbox; HUB_COURSE=posekit: nbgrader's Assignments panel on HUB_EXCHANGE), idle servers culled after HUB_CULL
# seconds (default 3600); http://localhost:8000 (HUB_PORT). Ctrl-C stops the hub, its proxy and every server
HUB_PROXY := deploy/jupyterhub/node_modules/.bin/configurable-http-proxy
hub: setup warm
	test -x $(VENV)/bin/jupyterhub || $(PY) -m pip install -q -e ".[hub]"
	test -x $(HUB_PROXY) || (cd deploy/jupyterhub && npm ci --no-audit --no-fund --loglevel=error)
	$(if $(HUB_PASSWORD),POSEKIT_HUB_PASSWORD="$(HUB_PASSWORD)") $(if $(HUB_CULL),POSEKIT_HUB_CULL_TIMEOUT="$(HUB_CULL)") \
	  $(if $(HUB_COURSE),POSEKIT_HUB_COURSE="$(HUB_COURSE)") $(if $(HUB_EXCHANGE),POSEKIT_HUB_EXCHANGE="$(abspath $(HUB_EXCHANGE))") \
	  $(if $(HUB_PORT),POSEKIT_HUB_PORT="$(HUB_PORT)") PATH="$(abspath $(VENV))/bin:$$PATH" \
	  $(VENV)/bin/jupyterhub -f deploy/jupyterhub/jupyterhub_config.py $(HUB_ARGS)

bench: setup
	$(VENV)/bin/posekit bench fk

# the documentation pages the code writes (tests/test_docs.py fails when the committed ones differ)
docs: setup
	$(VENV)/bin/posekit docs build

clean:
	rm -rf $(VENV) .pytest_cache build tools/course/node_modules
