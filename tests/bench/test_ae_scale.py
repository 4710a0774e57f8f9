"""``posekit bench ae-scale``: lesson 03 on the full Bandai datasets (a few clips, tiny training here)."""

import json
import math

import numpy as np
import pytest

TINY = dict(ae_epochs=1, solver_epochs=1, chain_epochs=1, pairs=2000)
NEURAL = {"neural", "neural-raw", "neural-chained", "neural-chained-raw", "neural-fabrik"}


@pytest.fixture(scope="module")
def sets(shared_data):
    from posekit.bench.ae_scale import scale_motions

    return {p: scale_motions(p, data_dir=shared_data, limit=3, progress=False) for p in ("full", "cross")}


def _clips(ms, name):
    return set(np.unique(ms.clip_id[ms.split.frames(name)]).tolist())


@pytest.mark.parametrize("protocol", ["full", "cross"])
def test_splits_disjoint_by_clip(sets, protocol):
    ms = sets[protocol]
    sp = ms.split
    tr, va, te = (_clips(ms, s) for s in ("train", "val", "test"))
    assert tr and va and te
    assert not (tr & va) and not (tr & te) and not (va & te)
    assert tr | va | te == set(range(ms.n_clips))
    for s in ("train", "val", "test"):
        f = sp.frames(s)
        assert np.all(np.diff(f) > 0)  # sorted, no repeats
    assert len(sp.train) + len(sp.val) + len(sp.test) == ms.n_frames
    assert ms.local_pos is None and ms.skeleton.n_joints == 22
    # at most `limit` clips per dataset, at the files' frame rates
    assert np.sum(sp.clip_dataset == 1) <= 3 and np.sum(sp.clip_dataset == 2) <= 3
    assert np.allclose(ms.frame_time[sp.clip_dataset == 1], 1 / 30, atol=1e-6)
    assert np.allclose(ms.frame_time[sp.clip_dataset == 2], 4 / 30, atol=1e-6)


def test_cross_is_dataset_2_to_dataset_1(sets):
    ms = sets["cross"]
    ds = ms.split.clip_dataset[ms.clip_id]
    assert np.all(ds[ms.split.test] == 1) and len(ms.split.test) == np.sum(ds == 1)
    assert np.all(ds[ms.split.train] == 2) and np.all(ds[ms.split.val] == 2)


def test_full_follows_held_out_rule(sets):
    from posekit.data.bandai_mini import held_out_split

    ms = sets["full"]
    assert [held_out_split(n) for n in ms.clip_names] == ms.split.clip_split.tolist()


def test_same_skeleton_and_poses_as_the_mini_set(sets):
    """The normalised set is the mini set's skeleton; its frames FK to the file's positions."""
    from posekit.data.bandai_mini import JOINTS, mini_path
    from posekit.data.sources import load_bvh_files
    from posekit.skeleton import Skeleton

    ms = sets["full"]
    assert tuple(ms.skeleton.names) == JOINTS
    if mini_path().is_file():
        with np.load(mini_path()) as z:
            assert Skeleton.from_arrays(z).same_as(ms.skeleton)
    name = ms.clip_names[0]
    from posekit.paths import shared_data_dir

    raw = load_bvh_files([shared_data_dir() / "bandai-namco-1" / "data" / f"{name}.bvh"], scale=0.01)
    f = ms.clip_frames(0)
    # the bones below Hips move by at most 0.4 mm (the reference OFFSETs); the placement is exact
    assert np.abs(ms.global_pos[f][:, 1:] - raw.global_pos[:, 1:]).max() < 2e-3
    assert np.abs(ms.global_pos[f][:, 1] - raw.global_pos[:, 1]).max() < 1e-9


def test_bad_arguments(shared_data):
    from posekit.bench.ae_scale import run_scale, scale_motions

    with pytest.raises(ValueError, match="protocol"):
        scale_motions("nope", data_dir=shared_data)
    with pytest.raises(ValueError, match="limit"):
        scale_motions("full", data_dir=shared_data, limit=2)
    with pytest.raises(ValueError, match="training setting"):
        run_scale("full", data_dir=shared_data, limit=3, out=False, epochs=3)


def test_run_scale_rows(shared_data, tmp_path):
    from posekit.bench.ae_scale import run_scale

    out = tmp_path / "r" / "ae_scale_cross.json"
    res = run_scale("cross", n_cases=20, data_dir=shared_data, limit=3, out=out, progress=False, **TINY)
    assert json.loads(out.read_text())["protocol"] == "cross"
    assert res["data"]["frames_per_split"]["test"] == res["data"]["split_datasets"]["test"]["1"]
    assert res["settings"]["ae_epochs"] == 1 and res["train_seconds"] > 0
    rows = res["rows"]
    methods = {r["method"] for r in rows}
    assert "fabrik" in methods and NEURAL <= methods
    assert {r["start"] for r in rows} | set(res["skipped_starts"]) == {"rest", "same-clip", "other-clip"}
    assert "rest" in res["starts"]  # local_pos None: the rest start is not refused
    for r in rows:
        assert r["protocol"] == "cross" and r["cases"] == 20
        for k in ("effector_error_mm_median", "mpjpe_mm_median", "bone_length_error_mm_max", "latency_ms_median"):
            assert math.isfinite(r[k]), (r["method"], k)
    # chained rows only where the chain has several stages (5 effectors)
    assert {r["effectors"] for r in rows if r["method"].startswith("neural-chained")} == {"5"}
    fab = [r for r in rows if r["method"] == "neural-fabrik"]
    raw = {(r["start"], r["effectors"]): r for r in rows if r["method"] == "neural-raw"}
    assert all(r["effector_error_mm_median"] <= raw[(r["start"], r["effectors"])]["effector_error_mm_median"]
               for r in fab)


def test_benchmark_registered_and_skipped_start(shared_data, monkeypatch, tmp_path):
    """Importing the module registers ``ae-scale``; a start refused for the data is skipped and recorded."""
    import posekit.bench.ae_scale as mod
    from posekit.bench.plugin import get_benchmark

    b = get_benchmark("ae-scale")
    args = b.namespace(limit=3, cases=20, out=str(tmp_path / "a.json"))
    assert args.protocol == "full" and args.seed == 0
    real = mod.run_scale
    monkeypatch.setattr(mod, "run_scale", lambda *a, **kw: real(*a, data_dir=shared_data, **{**kw, **TINY}))
    rows = b.run(args)
    res = json.loads((tmp_path / "a.json").read_text())
    # full with limit=3 keeps one test clip: other-clip needs two, so it is skipped with the reason
    assert "other-clip" in res["skipped_starts"] and "two held-out clips" in res["skipped_starts"]["other-clip"]
    assert {r["start"] for r in rows} == {"rest", "same-clip"}
    text = b.render(rows, args)
    assert "Start: rest" in text and "neural-fabrik" in text and "other-clip skipped" in text
    assert max(len(line) for line in text.splitlines()) <= 100


def test_out_argument_writes_the_default_file_unless_told_not_to():
    from posekit.bench.ae_scale import out_argument

    assert out_argument(None) is None  # run_scale: the default data_samples/results file
    assert out_argument("none") is False and out_argument("False") is False and out_argument("-") is False
    assert out_argument("x.json") == "x.json"
