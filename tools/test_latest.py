"""Run the browser tests and every notebook against the newest notebook stack: ``make test-latest``.

posekit's ``pyproject.toml`` bounds what it has tested (``pythreejs<2.5``, ``voila<0.6``, ``nbval<0.12`` ...),
so ``make test`` keeps passing while the ecosystem moves on; a student who installs next term may get releases
nobody here has run. This script builds a second virtual environment, ``.venv-latest``, in which the notebook
stack is installed at the newest release the package index offers, *ignoring posekit's upper bounds*, and runs
the tests that exercise that stack: every lesson under nbval and the headless-Chromium tests.

- The stack: jupyterlab, ipywidgets, jupyterlab-widgets, pythreejs, voila, nbval, playwright, numpy, ipykernel,
  jupyter-server, notebook, plus every other dependency of posekit, each unbounded above.
- torch is the exception: it stays at the CPU wheel this machine installs (``torch==2.13.0``; any newer
  release on the index is a multi-GB CUDA build), the same rule as ``pyproject.toml``.
- ``--pre`` admits pre-releases too (e.g. a JupyterLab alpha), for an early warning.

It writes what it installed and how the tests ended to ``build/test-latest/versions.json``; with ``--record``
also to ``docs/tested-versions.json`` and runs ``posekit docs build``, which renders ``docs/tested-versions.md``
from it (the page names the command, the date, the machine and the versions, so "which versions were tested
when" is never typed by hand). Exit status: pytest's.

    python tools/test_latest.py                 # stable releases; browser tests + notebooks
    python tools/test_latest.py --pre           # pre-releases admitted
    python tools/test_latest.py --record        # also record the run in docs/ and re-render the page
    python tools/test_latest.py --pytest-args "-k 01_fabrik"
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = ROOT / ".venv-latest"
OUT = ROOT / "build" / "test-latest"
RECORD = ROOT / "docs" / "tested-versions.json"  # docs/tested-versions.md is rendered from it (posekit docs build)

# the notebook stack whose newest releases are the point of the run (reported first, in this order)
STACK = ["jupyterlab", "ipywidgets", "jupyterlab-widgets", "pythreejs", "voila", "nbval", "playwright", "numpy",
         "ipykernel", "jupyter-server", "notebook", "torch"]
TORCH_CPU = "torch==2.13.0"  # the CPU wheel; pyproject.toml bounds torch the same way


def _requirement_names(pyproject: Path) -> list[str]:
    """posekit's runtime and dev requirements as bare names (no version bounds), from ``pyproject.toml``."""
    import tomllib

    data = tomllib.loads(pyproject.read_text())
    reqs = list(data["project"]["dependencies"]) + list(data["project"]["optional-dependencies"]["dev"])
    names = []
    for r in reqs:
        name = re.match(r"\s*([A-Za-z0-9_.\-]+)", r).group(1)
        if name.lower() != "torch" and name not in names:
            names.append(name)
    return names


def _run(cmd: list[str], **kw) -> int:
    print("+", " ".join(shlex.quote(str(c)) for c in cmd), flush=True)
    return subprocess.call([str(c) for c in cmd], **kw)


def install(pre: bool) -> None:
    """Create ``.venv-latest`` and install the newest stack into it (torch held at the CPU wheel)."""
    py = VENV / "bin" / "python"
    if not py.exists():
        if _run([sys.executable, "-m", "venv", VENV]) != 0:
            raise SystemExit("could not create .venv-latest")
    OUT.mkdir(parents=True, exist_ok=True)
    constraints = OUT / "constraints.txt"
    constraints.write_text(TORCH_CPU + "\n")
    pip = [py, "-m", "pip", "install", "-q", "--upgrade", "-c", constraints]
    if pre:
        pip.append("--pre")
    steps = [
        [py, "-m", "pip", "install", "-q", "--upgrade", "pip"],
        pip + [TORCH_CPU],
        pip + _requirement_names(ROOT / "pyproject.toml") + [s for s in STACK if s != "torch"],
        [py, "-m", "pip", "install", "-q", "--no-deps", "-e", ROOT],
    ]
    for cmd in steps:
        if _run(cmd) != 0:
            raise SystemExit(f"installing the newest stack failed at: {' '.join(map(str, cmd[3:8]))} ...")
    settings = VENV / "share" / "jupyter" / "lab" / "settings"
    settings.mkdir(parents=True, exist_ok=True)
    (settings / "overrides.json").write_text((ROOT / "tools" / "jupyterlab_overrides.json").read_text())


def installed_versions() -> dict[str, str]:
    out = subprocess.run([VENV / "bin" / "python", "-m", "pip", "list", "--format=json"], capture_output=True,
                         text=True, check=True).stdout
    return {p["name"].lower().replace("_", "-"): p["version"] for p in json.loads(out)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pre", action="store_true", help="admit pre-releases of the stack")
    ap.add_argument("--record", action="store_true", help="record this run in docs/tested-versions.json and "
                    "re-render docs/tested-versions.md")
    ap.add_argument("--skip-install", action="store_true", help="reuse .venv-latest as it is")
    ap.add_argument("--workers", default=os.environ.get("PYTEST_WORKERS", "2"), help="pytest-xdist workers")
    ap.add_argument("--pytest-args", default="", help="extra pytest arguments")
    args = ap.parse_args(argv)

    if not args.skip_install:
        install(args.pre)
    versions = installed_versions()
    stack = {name: versions.get(name, "not installed") for name in STACK}
    print("newest stack:", ", ".join(f"{k} {v}" for k, v in stack.items()), flush=True)

    py = VENV / "bin" / "python"
    # every lesson, and the widget tests (headless Chromium among them): the parts the notebook stack carries
    cmd = [py, "-m", "pytest", "notebooks", "tests/viz", "--durations=10"]
    if args.workers != "0":
        cmd += ["-n", args.workers, "--dist", "loadfile"]
    cmd += shlex.split(args.pytest_args)
    env = dict(os.environ, PATH=f"{VENV / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}")
    start = time.monotonic()
    rc = _run(cmd, cwd=ROOT, env=env)
    record = {
        "command": "python tools/test_latest.py" + (" --pre" if args.pre else ""),
        "date": _dt.date.today().isoformat(),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}",
        "result": "passed" if rc == 0 else f"failed (pytest exit {rc})",
        "seconds": round(time.monotonic() - start),
        "stack": stack,
    }
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "versions.json").write_text(json.dumps(record, indent=2) + "\n")
    print(f"test-latest: {record['result']} in {record['seconds']} s; {OUT / 'versions.json'}", flush=True)
    if args.record:
        RECORD.write_text(json.dumps(record, indent=2) + "\n")
        _run([py, "-m", "posekit", "docs", "build"], cwd=ROOT)
    return rc


if __name__ == "__main__":
    sys.exit(main())
