"""Compiled kernels cached across processes, keyed on every source file (posekit._jit): a fresh process loads the
kernels a previous one compiled, and any change to the package's sources uses another cache folder."""

import os
import shutil
import subprocess
import sys

import pytest

from posekit import _jit

pytestmark = pytest.mark.skipif(not _jit.HAVE_NUMBA, reason="numba is not installed")

PROBE = """
from posekit.data import load_sample
from posekit.ik import Pose, effector_set, make_solver
from posekit.ik import ccd
from posekit import _jit
m = load_sample()
start = Pose(m.global_pos[0], m.local_rot[0], m.root_pos[0])
make_solver("ccd", m.skeleton).solve(start, effector_set(m.skeleton, "2", m.global_pos[5]))
print(_jit._CACHE, sum(ccd._ccd.stats.cache_hits.values()), sum(ccd._ccd.stats.cache_misses.values()))
"""


def _run(env):
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    folder, hits, misses = out.stdout.split()
    return folder, int(hits), int(misses)


def test_a_second_process_loads_the_kernels_the_first_compiled(tmp_path):
    env = {**os.environ, "POSEKIT_NUMBA_CACHE": str(tmp_path)}
    folder, hits, misses = _run(env)
    assert folder.startswith(str(tmp_path)) and hits == 0 and misses == 1  # compiled and written
    assert any(p.suffix == ".nbi" for p in tmp_path.rglob("*"))  # numba's index of the cached kernels
    again = _run(env)
    assert again == (folder, 1, 0)  # loaded, not compiled
    off = _run({**env, "POSEKIT_NUMBA_CACHE": "0"})
    assert off[0] == "None" and off[1] == 0  # caching off: compiled in the process


def test_any_source_change_moves_the_cache(tmp_path, monkeypatch):
    copy = tmp_path / "posekit"
    shutil.copytree(_jit._PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(_jit, "_PACKAGE", copy)
    before = _jit.source_hash()
    assert before == _jit.source_hash()
    helper = copy / "ik" / "_rigid.py"  # a helper other kernels call: numba's own cache would not notice
    helper.write_text(helper.read_text() + "\n# changed\n")
    assert _jit.source_hash() != before
    monkeypatch.setenv("POSEKIT_NUMBA_CACHE", str(tmp_path / "cache"))
    assert _jit.cache_dir().name == f"numba-{_jit.source_hash()}"
    monkeypatch.setenv("POSEKIT_NUMBA_CACHE", "off")
    assert _jit.cache_dir() is None


WARM = """
import json, sys
from posekit import warm
from posekit.ik import registry

def broken(skeleton):
    raise RuntimeError("no weights here")

registry.register("broken-for-test", broken, description="a solver that cannot be made")
registry.solver_names = lambda: ["ccd", "broken-for-test"]  # what this test compiles ahead (ccd: a few seconds)
first, second = warm.warm(workers=1), warm.warm(workers=1)
print(json.dumps([first, second]))
"""


def test_warm_compiles_ahead_so_the_next_process_only_loads_and_reports_what_it_could_not(tmp_path):
    import json

    env = {**os.environ, "POSEKIT_NUMBA_CACHE": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", WARM], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    first, second = json.loads(out.stdout)
    assert not first["done"] and first["solvers"] == 1 and first["cache"].startswith(str(tmp_path))
    assert first["skipped"] == {"broken-for-test": "RuntimeError: no weights here"}
    assert second["done"] and second["cache"] == first["cache"]  # warm already: nothing compiled again
    folder, hits, misses = _run(env)
    assert folder == first["cache"] and (hits, misses) == (1, 0)  # the next process loads ccd, compiles nothing
