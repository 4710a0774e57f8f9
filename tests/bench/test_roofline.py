"""``posekit bench protores``'s speed rows against the roofline: the multiply-adds counted from the layer sizes, and
the rows and results file the bench writes. Nothing here is timed: the timing loops run a round or two, and only
the rows' shape and the arithmetic are checked."""

import json

import pytest
import torch
from torch.utils.flop_counter import FlopCounterMode

from posekit.bench import protores as bench_protores
from posekit.bench.roofline import gemm_rate, gemm_shapes, macs_per_pose, weight_bytes
from posekit.data.metrics import body_joints
from posekit.models.protores.networks import PosingNet, ProtoResConfig


def test_macs_of_a_tiny_protores_equal_a_hand_count():
    """2 body joints, width 4, one block of one layer, embeddings of 1 (tokens of 6 + 1 + 2 = 9), 2 effectors."""
    cfg = ProtoResConfig(n_joints=2, width=4, blocks=1, layers=1, embed=1)
    encoder = 2 * (9 * 4 + 9 * 4 + 4 * 4)       # per effector: layer, skip, forecast
    gpd = 4 * 4 + 4 * 4 + 4 * (3 * 2)           # code -> 2 positions
    ikd = 10 * 4 + 10 * 4 + 4 * (6 * 2)         # code + positions -> 2 rotations in 6D
    assert macs_per_pose(cfg, 2) == encoder + gpd + ikd == 360
    assert weight_bytes(cfg, 2) == 4 * (encoder // 2 + gpd + ikd)  # each weight read once, whatever N is
    # the per-effector encoder grows with N, the decoders do not
    assert macs_per_pose(cfg, 3) - macs_per_pose(cfg, 2) == encoder // 2
    # a batch multiplies every product by its poses
    assert sum(n * m * k * q for n, m, k, q in gemm_shapes(cfg, 2, poses=7)) == 7 * 360


def test_a_tiny_transformer_counts_its_attention_by_hand():
    cfg = ProtoResConfig(n_joints=2, arch="transformer", width=4, blocks=1, layers=1, embed=1, d_model=4, heads=2,
                         enc_layers=1, dec_layers=1)
    N, J, d, dh, h = 3, 2, 4, 2, 2
    attn = lambda q, k: q * d * d + 2 * k * d * d + h * (q * dh * k + q * k * dh) + q * d * d  # noqa
    enc = N * 9 * d + attn(N, N) + 2 * N * d * 4 * d
    dec = attn(J, J) + attn(J, N) + 2 * J * d * 4 * d
    decoders = (4 * 4 + 4 * 4 + 4 * 6) + (10 * 4 + 10 * 4 + 4 * 12)
    assert macs_per_pose(cfg, N) == enc + dec + J * d * 4 + decoders


@pytest.mark.parametrize("arch", ["protores", "masked-fcr", "transformer"])
def test_the_counted_layers_are_the_products_torch_runs(mini, arch):
    """On a real (small, untrained) network of the Bandai skeleton, torch's own count of its fully connected
    products equals ours, layer by layer summed."""
    B = len(body_joints(mini.skeleton))
    cfg = ProtoResConfig(B, arch=arch, width=16, blocks=2, layers=2, embed=4, d_model=8, heads=2)
    net = PosingNet(mini.skeleton, cfg).eval()
    N = 5
    g = torch.Generator().manual_seed(0)
    joint = torch.randperm(B, generator=g)[:N][None]
    kind = torch.zeros(1, N, dtype=torch.long)
    value = torch.rand(1, N, 6, generator=g)
    tol = torch.full((1, N), 0.7)
    with FlopCounterMode(display=False) as fc:
        net(joint, kind, value, tol)
    counts = fc.get_flop_counts()["Global"]
    linear = sum(v for op, v in counts.items() if str(op) in ("aten.addmm", "aten.mm")) // 2
    ours = sum(n * m * k * q for n, m, k, q in gemm_shapes(cfg, N) if n == 1)
    assert linear == ours
    if arch != "transformer":
        assert macs_per_pose(cfg, N) == ours  # no attention: every product is a layer's


def test_bad_sizes_are_refused():
    cfg = ProtoResConfig(n_joints=2, width=4)
    with pytest.raises(ValueError, match="at least 1"):
        gemm_shapes(cfg, 0)


def test_gemm_rate_reports_the_products_it_ran():
    shapes = [(1, 8, 4, 2), (3, 2, 4, 5)]
    r = gemm_rate(shapes, rounds=2, between=lambda: 0.25)
    assert r["macs"] == 8 * 4 * 2 + 3 * 2 * 4 * 5
    assert r["macs_per_s"] == pytest.approx(r["macs"] / r["seconds_median"])
    assert r["between_median"] == 0.25


SPEED_KEYS = {"table", "method", "width", "effectors", "macs_per_pose", "weights_mb", "gemm_gmacs",
              "ideal_poses_per_s", "poses_per_s", "fraction_of_ideal", "goal_fraction", "fraction_met",
              "ms_products_one", "gemm_gmacs_one", "ms_solve_median", "goal_ms", "ms_met", "paper_ms"}


def test_speed_only_writes_its_rows_with_provenance(tmp_path, capsys, monkeypatch):
    """``--speed-only --out FILE``: one row per network with every column, goals judged, and the file carries
    the command, date and machine. Rounds cut to one or two: the values are not checked, only their kind."""
    from posekit.cli import main
    from posekit.docs import bench_page

    monkeypatch.setattr(bench_protores, "ROUNDS_ONE", 2)
    monkeypatch.setattr(bench_protores, "ROUNDS_BATCH", 1)
    monkeypatch.setattr(bench_protores, "BATCH", 4)
    monkeypatch.setattr(bench_protores, "ROUNDS_PAPER", 1)
    out = tmp_path / bench_protores.RESULTS_FILE
    assert main(["bench", "protores", "--speed-only", "--json", "--out", str(out)]) == 0
    every = json.loads(capsys.readouterr().out)
    rows, wide = every[:-1], every[-1]
    assert [r["method"] for r in rows] == ["ProtoRes", "Masked-FCR", "Transformer"]
    # the paper's width, timed on its own shapes: 1,024 wide, its multiply-adds counted like ours
    from dataclasses import replace

    from posekit.bench.roofline import macs_per_pose
    from posekit.data import load_bandai_mini
    from posekit.models.protores.solver import ProtoResSolver

    assert wide["table"] == "speed-paper" and wide["width"] == bench_protores.PAPER_WIDTH == 1024
    cfg = ProtoResSolver(load_bandai_mini().skeleton, arch="protores").net.config
    assert wide["macs_per_pose"] == macs_per_pose(replace(cfg, width=1024), 5) > 10 * rows[0]["macs_per_pose"]
    assert wide["ms_products_one"] > 0 and wide["paper_ms"] == bench_protores.PAPER_MS
    for r in rows:
        assert set(r) == SPEED_KEYS and r["table"] == "speed" and r["effectors"] == 5
        assert r["fraction_of_ideal"] == pytest.approx(r["poses_per_s"] / r["ideal_poses_per_s"], rel=0.01, abs=2e-3)
        assert r["fraction_met"] == (r["fraction_of_ideal"] >= r["goal_fraction"])
    pr = rows[0]
    assert pr["goal_ms"] == bench_protores.GOAL_MS and pr["ms_met"] == (pr["ms_solve_median"] <= pr["goal_ms"])
    assert all(r["goal_ms"] is None and r["ms_met"] is None for r in rows[1:])  # the goal is ProtoRes's
    d = json.loads(out.read_text())
    assert d["command"] == f"posekit bench protores --speed-only --out {out}"
    assert d["date"] and d["machine"]["processor"] and d["rows"] == every
    assert isinstance(d["load_avg_1min_before"], float)
    page = bench_page.markdown(tmp_path)
    assert "against the roofline" in page and "load average when the run began" in page and f"`posekit bench protores --speed-only --out {out}`" in page


def test_speed_only_and_no_speed_exclude_each_other(capsys):
    from posekit.cli import main

    assert main(["bench", "protores", "--speed-only", "--no-speed"]) != 0
    assert "exclude each other" in capsys.readouterr().err
