"""The shipped Bandai mini set (data_samples/bandai_mini/) and the command that builds it."""

import shutil
import time

import numpy as np
import pytest

from posekit.cli import build_parser, main
from posekit.data import bandai_mini_split, build_bandai_mini, load_bandai_mini, open_dataset
from posekit.data.bandai_mini import JOINTS, MINI_FILE, MULTI_STYLE_1, held_out_split, mini_path, parse_clip_name
from posekit.kinematics import bone_lengths_of, fk


@pytest.fixture(scope="module")
def raw():
    with np.load(mini_path(), allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_shipped_file_loads_fast_and_small(mini):
    path = mini_path()
    assert path.name == MINI_FILE and path.stat().st_size < 12e6
    assert (path.parent / "LICENSE").read_text().startswith("Attribution-NonCommercial 4.0 International")
    t = time.perf_counter()
    load_bandai_mini()
    assert time.perf_counter() - t < 3.0  # about 0.5 s on a laptop core; slack for loaded CI machines
    assert 30_000 <= mini.n_frames <= 50_000
    assert mini.skeleton.n_joints == 22 and mini.skeleton.names == JOINTS
    assert mini.local_pos is None and mini.skeleton.index("pelvis") == 1
    assert mini.n_clips == 174 + 2902
    for name in ("local_rot", "root_pos", "global_pos"):
        assert np.all(np.isfinite(getattr(mini, name))), name
    np.testing.assert_allclose(np.linalg.norm(mini.local_rot, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(mini.local_rot[:, 0], [[0, 0, 0, 1]] * mini.n_frames)  # joint_Root only translates
    ds = mini.split.clip_dataset
    np.testing.assert_allclose(mini.frame_time[ds == 1], 2 / 30)
    np.testing.assert_allclose(mini.frame_time[ds == 2], 16 / 30)


def test_open_dataset_by_name(mini):
    ms = open_dataset("bandai-mini")
    assert ms.n_frames == mini.n_frames and ms.clip_names == mini.clip_names


def test_positions_are_fk_with_constant_bone_lengths(mini):
    np.testing.assert_allclose(fk(mini.skeleton, mini.local_rot, mini.root_pos, mini.local_pos)[0], mini.global_pos,
                               atol=1e-9)
    lengths = bone_lengths_of(mini.skeleton, mini.global_pos)
    np.testing.assert_allclose(lengths, np.broadcast_to(mini.skeleton.bone_lengths(), lengths.shape), atol=1e-9)
    # the Hips sit ROOT_TO_HIPS above joint_Root, in world axes
    np.testing.assert_allclose(mini.global_pos[:, 1] - mini.global_pos[:, 0], [[0, 0.94, 0]] * mini.n_frames,
                               atol=1e-9)


def test_split_is_clip_level_disjoint_and_covers_every_frame(mini):
    sp = mini.split
    assert sp is bandai_mini_split(mini)
    sets = {s: sp.frames(s) for s in ("train", "val", "test")}
    allf = np.concatenate(list(sets.values()))
    assert len(allf) == mini.n_frames and len(np.unique(allf)) == mini.n_frames
    clips = {s: set(np.unique(mini.clip_id[f]).tolist()) for s, f in sets.items()}
    assert not clips["train"] & clips["val"] and not clips["train"] & clips["test"] and not clips["val"] & clips["test"]
    for s in sets:  # whole clips: every frame of a clip of the set is in the set
        assert sum(len(mini.clip_frames(c)) for c in clips[s]) == len(sets[s])
        assert clips[s] == set(sp.clips(s).tolist())
    # a file-only read gives the same split
    other = bandai_mini_split()
    for s in sets:
        np.testing.assert_array_equal(other.frames(s), sets[s])
    assert len(sets["val"]) > 500 and len(sets["test"]) > 500


def test_held_out_clips_are_dataset_1_and_their_contents_are_trained(mini):
    sp = mini.split
    held = np.isin(sp.clip_split, ["val", "test"])
    assert np.all(sp.clip_dataset[held] == 1) and np.all(sp.clip_split[sp.clip_dataset == 2] == "train")
    train_contents = set(sp.clip_content[sp.clip_split == "train"])
    train_d1_contents = set(sp.clip_content[(sp.clip_split == "train") & (sp.clip_dataset == 1)])
    for s in ("val", "test"):
        contents = set(sp.clip_content[sp.clip_split == s])
        assert contents <= train_contents and contents <= train_d1_contents, s
    test_contents = set(sp.clip_content[sp.clip_split == "test"])
    assert {"walk", "run", "bow", "punch", "slash", "call"} <= test_contents
    assert len(test_contents) == 13
    # every dataset-1 content is in train; single-take contents only there
    assert set(sp.clip_content[sp.clip_dataset == 1]) == train_d1_contents
    for c in ("kick", "respond", "dance-short"):
        assert set(sp.clip_split[sp.clip_content == c]) == {"train"}
    # test and val styles differ, per content and overall among the 15-style contents; normal stays in train
    multi = np.isin(sp.clip_content, MULTI_STYLE_1) & (sp.clip_dataset == 1)
    test_styles = set(sp.clip_style[multi & (sp.clip_split == "test")])
    val_styles = set(sp.clip_style[multi & (sp.clip_split == "val")])
    assert len(test_styles) == len(val_styles) == 7 and not test_styles & val_styles and "normal" not in test_styles
    assert set(sp.clip_split[(sp.clip_style == "normal") & (sp.clip_take == 1)]) == {"train"}
    # the stored split is the documented rule, and the labels are the clip names'
    for name, s, d, c, st, tk in zip(mini.clip_names, sp.clip_split, sp.clip_dataset, sp.clip_content,
                                     sp.clip_style, sp.clip_take):
        assert held_out_split(name) == s
        assert parse_clip_name(name) == (d, c, st, tk)
    assert held_out_split("dataset-1_walk_happy_002") == "test" and held_out_split("dataset-1_walk_sad_001") == "val"


def test_facing_units_and_floor(mini):
    sk, g = mini.skeleton, mini.global_pos
    left = g[:, sk.index("left_hip")] - g[:, sk.index("right_hip")]
    facing = np.cross(left, [0.0, 1.0, 0.0])
    facing[:, 1] = 0
    facing /= np.linalg.norm(facing, axis=-1, keepdims=True)
    for name in ("dataset-1_walk_normal_001", "dataset-1_run_normal_001", "dataset-2_walk_normal_001"):
        f = mini.clip_frames(name)
        disp = g[f[-1], 1] - g[f[0], 1]
        speed = np.hypot(disp[0], disp[2]) / (len(f) * mini.frame_time[mini.clip_names.index(name)])
        assert disp[2] > 0.8 * np.hypot(disp[0], disp[2]) and 0.7 < speed < 4.0, name  # travels along +Z
        assert facing[f, 2].mean() > 0.9, name  # faces +Z, left is +X
    f = mini.clip_frames("dataset-1_walk-back_normal_001")
    assert g[f[-1], 1, 2] < g[f[0], 1, 2] - 0.5 and facing[f, 2].mean() > 0.9  # walks backwards, facing +Z
    feet = sk.indices(["left_foot", "right_foot", "left_toe", "right_toe"])
    lowest = g[:, feet, 1].min(axis=1)
    assert 0.0 < np.median(lowest) < 0.1  # floor at y = 0
    # standing height: the Head joint (base of the skull) 1.3-1.6 m above the floor in upright
    # frames, so with the ~0.2 m of head above it the actor is 1.5-1.8 m tall
    upright = g[:, sk.index("head"), 1] - g[:, sk.index("pelvis"), 1] > 0.4
    assert upright.mean() > 0.8
    head = np.median(g[upright, sk.index("head"), 1])
    assert 1.3 < head < 1.6
    assert 0.85 < np.median(g[:, sk.index("pelvis"), 1]) < 1.0


def test_cli_build_sample_parses_and_needs_the_data(monkeypatch, tmp_path, capsys):
    p = build_parser()
    assert p.parse_args(["data", "build-sample"]).which == "deepmimic"
    assert p.parse_args(["data", "build-sample", "bandai"]).which == "bandai"
    monkeypatch.delenv("POSEKIT_DATA_DIR", raising=False)
    assert main(["data", "build-sample", "bandai", "--out", str(tmp_path / "m.npz")]) == 2
    assert "POSEKIT_DATA_DIR" in capsys.readouterr().err and not (tmp_path / "m.npz").exists()


# ------------------------------------------------------------------------------- rebuild from the data
def _subset_names(raw):
    """All dataset-1 clips (every held-out clip, the clips where joint_Root travels, the files with a
    different LowerLeg_R OFFSET) and every 50th dataset-2 clip."""
    names = [str(n) for n in raw["clip_names"]]
    d2 = [n for n in names if n.startswith("dataset-2")]
    return [n for n in names if n.startswith("dataset-1")] + d2[::50]


@pytest.mark.shared_data
def test_rebuild_from_shared_data_equals_the_shipped_clips(shared_data, raw, tmp_path):
    names = _subset_names(raw)
    out = tmp_path / "mini.npz"
    report = build_bandai_mini(shared_data, out=out, names=names, workers=2)
    assert report["clips"] == len(names) and report["bone_length_dev_max"] < 1e-6
    assert report["float16_pos_err_max"] < 2e-3
    with np.load(out, allow_pickle=False) as z:
        sub = {k: z[k] for k in z.files}
    assert set(sub) == set(raw)
    for k in ("skeleton_names", "skeleton_parents", "skeleton_offsets", "skeleton_roles", "skeleton_name",
              "format_version"):
        np.testing.assert_array_equal(sub[k], raw[k], err_msg=k)
    full_names = [str(n) for n in raw["clip_names"]]
    idx = np.array([full_names.index(n) for n in sub["clip_names"]])
    np.testing.assert_array_equal(sub["clip_names"], np.array(names))
    for k in ("clip_lengths", "frame_time", "clip_dataset", "clip_content", "clip_style", "clip_take",
              "clip_split", "source_step"):
        np.testing.assert_array_equal(sub[k], raw[k][idx], err_msg=k)
    starts = np.concatenate([[0], np.cumsum(raw["clip_lengths"])])
    frames = np.concatenate([np.arange(starts[c], starts[c + 1]) for c in idx])
    for k in ("local_rot", "root_pos"):
        assert sub[k].dtype == raw[k].dtype
        np.testing.assert_array_equal(sub[k], raw[k][frames], err_msg=k)


@pytest.mark.shared_data
def test_build_is_deterministic_and_rejects_a_changing_bone(shared_data, tmp_path):
    names = ["dataset-1_walk_normal_001", "dataset-1_punch_normal_002", "dataset-2_run_active_001"]
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    build_bandai_mini(shared_data, out=a, names=names, workers=1)
    build_bandai_mini(shared_data, out=b, names=names, workers=2)
    assert a.read_bytes() == b.read_bytes()
    # a copy of the data where one frame stretches the left forearm by 1 cm must be refused
    fake = tmp_path / "data"
    for folder in ("bandai-namco-1/data", "bandai-namco-2-every4th/data"):
        (fake / folder).mkdir(parents=True)
    src1 = shared_data / "bandai-namco-1/data/dataset-1_walk_normal_001.bvh"
    shutil.copy(src1, fake / "bandai-namco-1/data" / src1.name)
    shutil.copy(shared_data / "bandai-namco-2-every4th/data/dataset-2_run_active_001.bvh",
                fake / "bandai-namco-2-every4th/data")
    build_bandai_mini(fake, out=tmp_path / "ok.npz", workers=1)
    lines = src1.read_text().splitlines()
    row = lines.index("MOTION") + 3
    vals = lines[row].split()
    vals[8 * 6] = str(float(vals[8 * 6]) + 1.0)  # LowerArm_L Xposition (joint 8), centimetres
    lines[row] = " ".join(vals)
    (fake / "bandai-namco-1/data" / src1.name).write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match="dataset-1_walk_normal_001.*bone lengths"):
        build_bandai_mini(fake, out=tmp_path / "bad.npz", workers=1)
