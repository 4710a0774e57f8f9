"""The scaling curve's arithmetic (lesson 05): the compute frontier and the power law through it."""

import numpy as np
import pytest

from posekit.models.protores.scaling import compute_for, fit_power_law, frontier


def test_frontier_keeps_runs_that_beat_every_cheaper_one():
    compute = [4e9, 1e9, 2e9, 8e9, 3e9]
    error = [5.0, 9.0, 6.0, 5.5, 7.0]
    assert frontier(compute, error).tolist() == [1, 2, 0]  # 1e9: 9, 2e9: 6, then 4e9: 5; 3e9 and 8e9 do worse


def test_power_law_is_recovered_and_inverted():
    C = np.logspace(9, 12, 7)
    a, b = fit_power_law(C, 3.0 * C ** -0.3)
    assert a == pytest.approx(3.0, rel=1e-9) and b == pytest.approx(0.3, rel=1e-9)
    assert compute_for(3.0 * 1e13 ** -0.3, a, b) == pytest.approx(1e13, rel=1e-6)
    assert compute_for(1.0, 2.0, -0.1) == float("inf")  # a curve that does not fall never gets there


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="at least two runs"):
        fit_power_law([1e9], [1.0])
    with pytest.raises(ValueError, match="positive"):
        fit_power_law([1e9, 2e9], [1.0, 0.0])
    with pytest.raises(ValueError, match="same length"):
        frontier([1e9, 2e9], [1.0])
