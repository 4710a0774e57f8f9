
import numpy as np
import pytest

from posekit.paths import shared_data_dir


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


# ---- running on both cores (pytest-xdist, `make test` passes -n 2 --dist loadgroup) --------------------
# A notebook's cells share one kernel and must run in order on one worker; the tests that start a
# JupyterLab, a Voila server or Chromium share one worker too, so two servers and two browsers never
# compete for the same two cores; every other test module stays on one worker with its module fixtures.
# The longest groups are handed out first, so neither worker waits on a late long one.
_BROWSER_MODULES = {"test_browser.py", "test_studio_browser.py", "test_course.py"}
# measured minutes on 2 cores, heaviest first; groups not listed come after, in collection order
_FIRST = ["browser", "04_aegan_latent_space.ipynb", "05_protores.ipynb", "02_inverse_rig_mapping.ipynb",
          "03_autoencoder_solvers.ipynb", "01_fabrik.ipynb"]


def _group(item) -> str:
    name = item.path.name
    return "browser" if name in _BROWSER_MODULES else name


def pytest_collection_modifyitems(config, items):
    rank = {g: k for k, g in enumerate(_FIRST)}
    for item in items:
        item.add_marker(pytest.mark.xdist_group(_group(item)))
    items.sort(key=lambda it: rank.get(_group(it), len(rank)))  # stable: cells keep their order
