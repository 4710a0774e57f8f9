
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


@pytest.fixture
def rng():
    return np.random.default_rng(0)
