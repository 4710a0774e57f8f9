
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

from posekit.paths import shared_data_dir
from tests import browser_artifacts

EXPORTS_VAR = "POSEKIT_EXPORTS_DIR"
"""Where the studio writes when no folder is given (:func:`posekit.paths.exports_dir`): a temporary folder here."""


@pytest.fixture(scope="session")
def sample():
    from posekit.data import load_sample

    return load_sample()


@pytest.fixture(scope="session")
def skel(sample):
    return sample.skeleton


@pytest.fixture(scope="session")
def shared_data():
    """The Bandai folders; the test skips only when they are absent."""
    d = shared_data_dir()
    if d is None or not (d / "bandai-namco-1").is_dir():
        pytest.skip("POSEKIT_DATA_DIR with bandai-namco-1/ is not available")
    return d


@pytest.fixture(scope="session")
def mini():
    """The Bandai mini set (shipped in data_samples/, its own train/val/test split)."""
    from posekit.data.bandai_mini import load_bandai_mini

    return load_bandai_mini()


@pytest.fixture
def rng():
    return np.random.default_rng(0)


@pytest.fixture(scope="module")
def chromium():
    """Debian's Chromium driven by Playwright, headless, with the project's flags (:func:`posekit.bench.browser.
    launch_chromium`; Playwright cannot download a browser of its own here): one browser per test module. A module
    whose tests start Playwright themselves (``posekit bench studio``'s own runs) does not use it: two sync
    Playwright instances cannot run in one thread at once."""
    from playwright.sync_api import sync_playwright

    from posekit.bench.browser import chromium_missing, launch_chromium

    missing = chromium_missing()
    if missing:
        pytest.fail(missing)
    with sync_playwright() as p:
        browser = launch_chromium(p)
        try:
            yield browser
        finally:
            browser.close()


# ---- running on both cores (pytest-xdist: `make test` passes -n 2 --dist loadfile) ------------------------
# A notebook's cells share one kernel and must run in order on one worker; the tests that serve
# notebooks (JupyterLab, Voila) to Chromium share one worker too, so two servers and two browsers never
# compete for the same two cores. Every other test module stays whole on one worker with its module
# fixtures. The longest groups are handed out first, so neither worker waits on a late long one.
# (A scheduler rather than xdist_group marks: pytest 9 no longer reads the node ids those marks rewrite.
# Without this file -- `pytest notebooks/...` -- plain loadfile still keeps each notebook on one worker.)
_BROWSER_MODULES = {"test_browser.py", "test_slides_fit.py", "test_studio_browser.py", "test_studio_class_browser.py",
                    "test_hub_browser.py", "test_one_screen_browser.py"}
# measured on 2 cores, longest first; groups not listed come after, in collection order
_FIRST = ["test_nbgrader.py", "browser", "04_aegan_latent_space.ipynb", "05_protores.ipynb",
          "02_inverse_rig_mapping.ipynb", "03_autoencoder_solvers.ipynb", "01_fabrik.ipynb"]


def _group(path: str) -> str:
    name = path.split("::", 1)[0].rsplit("/", 1)[-1]
    return "browser" if name in _BROWSER_MODULES else name


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """A failed browser test leaves its pages' screenshots and consoles and the servers' logs
    (tests/browser_artifacts.py) and its report says where."""
    outcome = yield
    browser_artifacts.runtest_makereport(item, call, outcome.get_result())


def pytest_terminal_summary(terminalreporter):
    browser_artifacts.terminal_summary(terminalreporter)


def _exports_in_a_temporary_folder(config) -> None:
    """Every studio the tests make writes under a temporary ``studio_exports/`` (``$POSEKIT_EXPORTS_DIR``,
    :func:`posekit.paths.exports_dir`), not in a student's ``notebooks/studio_exports/``: the tests' own studios, the
    notebooks nbval runs and the servers the browser tests start all inherit it (their kernels start after this).
    The folder goes when the run ends."""
    root = Path(tempfile.mkdtemp(prefix="posekit-test-exports-"))
    before = os.environ.get(EXPORTS_VAR)
    os.environ[EXPORTS_VAR] = str(root / "studio_exports")

    def restore():
        if before is None:
            os.environ.pop(EXPORTS_VAR, None)
        else:
            os.environ[EXPORTS_VAR] = before
        shutil.rmtree(root, ignore_errors=True)

    config.add_cleanup(restore)


def pytest_configure(config):
    browser_artifacts.install()
    _exports_in_a_temporary_folder(config)
    # two workers on two cores: one torch thread each, not two each fighting for the same cores
    if os.environ.get("PYTEST_XDIST_WORKER"):
        import torch

        torch.set_num_threads(1)


def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class GroupedFiles(LoadScopeScheduling):
        """loadfile, with the browser modules as one unit and the units in the collection's order."""

        def __init__(self, config, log=None):
            super().__init__(config, log)
            config.option.loadscopereorder = False  # keep pytest_collection_modifyitems' order

        def _split_scope(self, nodeid: str) -> str:
            return _group(nodeid)

    return GroupedFiles(config, log)


def pytest_collection_modifyitems(config, items):
    rank = {g: k for k, g in enumerate(_FIRST)}
    items.sort(key=lambda it: rank.get(_group(it.nodeid), len(rank)))  # stable: cells keep their order
