import numpy as np
import pytest

from posekit import fk
from posekit.data import (MotionSet, NormStats, augment_positions, load_bandai, sample_pairs, split_by_clip)
from posekit.data.sources import open_dataset
from posekit.kinematics import bone_lengths_of
from posekit.transforms import (facing_angle, from_root_space, mirror_positions, mirror_rotations,
                                rotate_y_rotations, to_root_space)


def test_sample_contents(sample):
    assert sample.n_clips == 15 and sample.n_frames == 1620 and sample.skeleton.n_joints == 18
    assert "backflip" in sample.clip_names and sample.clip_lengths().sum() == sample.n_frames
    walk = sample.global_pos[sample.clip_frames("walk")]
    pelvis = walk[:, sample.skeleton.index("pelvis")]
    assert pelvis[-1, 2] - pelvis[0, 2] > 1.0  # walks along +Z ...
    assert abs(np.degrees(facing_angle(sample.skeleton, walk)).mean()) < 10  # ... facing +Z
    toe = walk[:, sample.skeleton.index("left_toe"), 1]
    assert -0.02 < toe.min() < 0.05  # on the floor, metres


def test_split_never_mixes_clips(sample):
    sets = split_by_clip(sample, (0.7, 0.15, 0.15), seed=1)
    clip_sets = [set(sample.clip_id[s]) for s in sets]
    assert all(len(c) > 0 for c in clip_sets)
    assert not (clip_sets[0] & clip_sets[1] or clip_sets[0] & clip_sets[2] or clip_sets[1] & clip_sets[2])
    assert sorted(np.concatenate(sets)) == list(range(sample.n_frames))
    for s in sets:  # every clip in a set is there whole
        for c in set(sample.clip_id[s]):
            assert set(sample.clip_frames(c)) <= set(s)
    assert np.array_equal(split_by_clip(sample, seed=1)[0], split_by_clip(sample, seed=1)[0])


def test_norm_stats(rng):
    x = rng.normal(3, 2, size=(500, 4))
    x[:, 3] = 7.0  # a constant feature
    st = NormStats.fit(x)
    z = st.normalize(x)
    np.testing.assert_allclose(z[:, :3].mean(0), 0, atol=1e-12)
    np.testing.assert_allclose(z[:, :3].std(0), 1, atol=1e-12)
    assert np.all(np.isfinite(z)) and np.allclose(st.denormalize(z), x)
    with pytest.raises(ValueError, match="NaN"):
        NormStats.fit(np.array([[np.nan]]))


def test_mirror_twice_is_identity(sample):
    s = sample.skeleton
    np.testing.assert_allclose(mirror_positions(s, mirror_positions(s, sample.global_pos)), sample.global_pos)
    q, r = mirror_rotations(s, *mirror_rotations(s, sample.local_rot, sample.root_pos))
    np.testing.assert_allclose(q, sample.local_rot)
    np.testing.assert_allclose(r, sample.root_pos)


def test_mirrored_rotations_give_mirrored_positions(sample):
    s = sample.skeleton
    q, r = mirror_rotations(s, sample.local_rot, sample.root_pos)
    np.testing.assert_allclose(fk(s, q, r)[0], mirror_positions(s, sample.global_pos), atol=1e-6)


def test_rotate_y_rotations_turns_fk(sample):
    s = sample.skeleton
    q, r = rotate_y_rotations(sample.local_rot[:50], sample.root_pos[:50], 0.7)
    before = facing_angle(s, fk(s, sample.local_rot[:50], sample.root_pos[:50])[0])
    after = facing_angle(s, fk(s, q, r)[0])
    np.testing.assert_allclose(np.angle(np.exp(1j * (after - before))), 0.7, atol=1e-9)


def test_root_space_round_trip_and_facing(sample):
    s = sample.skeleton
    local, origin, angle = to_root_space(s, sample.global_pos)
    np.testing.assert_allclose(from_root_space(local, origin, angle), sample.global_pos, atol=1e-12)
    np.testing.assert_allclose(facing_angle(s, local), 0, atol=1e-9)
    pelvis = local[:, s.index("pelvis")]
    np.testing.assert_allclose(pelvis[:, [0, 2]], 0, atol=1e-12)
    np.testing.assert_allclose(origin[:, 1], 0)


def test_augmentation_keeps_bone_lengths(sample):
    s = sample.skeleton
    aug = augment_positions(s, sample.global_pos[:200], rng=3)
    np.testing.assert_allclose(bone_lengths_of(s, aug), bone_lengths_of(s, sample.global_pos[:200]), atol=1e-6)
    assert not np.allclose(aug, sample.global_pos[:200])


def test_pairs_stay_in_one_clip(sample):
    train = split_by_clip(sample, seed=0)[0]
    a, b = sample_pairs(sample, 2000, rng=0, frames=train, max_gap=10)
    assert np.all(sample.clip_id[a] == sample.clip_id[b])
    assert np.all(np.abs(a - b) <= 10)
    assert set(a) | set(b) <= set(train)
    assert np.mean(a != b) > 0.8


def test_select_and_save_load(sample, tmp_path):
    sub = sample.select(sample.clip_frames("kick"))
    assert sub.clip_names == ["kick"] and sub.n_frames == len(sample.clip_frames("kick"))
    sub.save(tmp_path / "k.npz")
    back = MotionSet.load(tmp_path / "k.npz")
    np.testing.assert_allclose(back.global_pos, sub.global_pos)
    assert back.skeleton.same_as(sub.skeleton)


def test_open_dataset_reports_bad_specs(tmp_path):
    with pytest.raises(FileNotFoundError, match="neither a dataset name"):
        open_dataset(tmp_path / "missing")
    with pytest.raises(FileNotFoundError, match="holds no .bvh"):
        open_dataset(tmp_path)


def test_bandai_needs_its_folder(monkeypatch):
    monkeypatch.delenv("POSEKIT_DATA_DIR", raising=False)
    with pytest.raises(FileNotFoundError, match="POSEKIT_DATA_DIR"):
        load_bandai(1)


@pytest.mark.shared_data
def test_bandai_dataset_1(shared_data):
    ms = load_bandai(1, data_dir=shared_data, progress=False)
    assert ms.n_clips == 174 and ms.n_frames == 31914 and ms.skeleton.n_joints == 22
    np.testing.assert_allclose(ms.frame_time, 1 / 30, rtol=1e-4)
    head = ms.global_pos[:, ms.skeleton.index("head"), 1]
    assert 1.3 < np.median(head) < 2.0
    sets = split_by_clip(ms, seed=0)
    assert not set(ms.clip_id[sets[0]]) & set(ms.clip_id[sets[2]])
    local, _, _ = to_root_space(ms.skeleton, ms.global_pos[::50])
    assert np.all(np.isfinite(local))


@pytest.mark.shared_data
def test_bandai_dataset_2_subset(shared_data):
    ms = load_bandai(2, data_dir=shared_data, limit=40, progress=False)
    assert ms.n_clips == 40 and ms.skeleton.n_joints == 22
    np.testing.assert_allclose(ms.frame_time, 0.133333, rtol=1e-4)


# ------------------------------------------------------------------ BVH folders in the wild
def _folder(tmp_path, name, n, rig=None, frames=30):
    from ..io.test_rigs import mixamo_rig, write_rig

    folder = tmp_path / name
    folder.mkdir()
    rng = np.random.default_rng(n)
    for i in range(n):  # subjects of different sizes
        write_rig(folder / f"take_{i}.bvh", rig or mixamo_rig(), rng, k=1 + 0.08 * i, frames=frames)
    return folder


def test_folder_with_other_hierarchy_says_what_differs(tmp_path):
    from ..io.test_rigs import mixamo_rig, write_rig

    folder = _folder(tmp_path, "mixed", 1)
    rename = lambda n: n and n.replace("LeftToeBase", "LeftToe")
    rig = [(rename(n), rename(p), o) for n, p, o in mixamo_rig()]
    write_rig(folder / "take_9.bvh", rig, np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"take_9.bvh: its joint hierarchy differs from .*take_0.bvh's: 1 joint "
                                         r"name\(s\) differ, the first is joint \d+: 'mixamorig:LeftToe' here, "
                                         r"'mixamorig:LeftToeBase' in the first file"):
        open_dataset(folder, scale=0.01)
    write_rig(folder / "take_9.bvh", [r for r in mixamo_rig() if "Toe_End" not in r[0]], np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"25 joints instead of 27; lacks: mixamorig:LeftToe_End, mixamorig:RightToe"):
        open_dataset(folder, scale=0.01)


def test_scale_argument_wins_over_detection(tmp_path):
    import warnings

    folder = _folder(tmp_path, "two", 2, frames=5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an explicit scale never warns about units
        ms = open_dataset(folder, scale=0.02)
    assert ms.units.unit == "given" and ms.units.detected == "cm" and ms.units.scale == 0.02
    assert 3.0 < ms.units.height < 3.5


def test_split_falls_back_to_time_with_too_few_clips(tmp_path):
    with pytest.warns(UserWarning):
        ms = open_dataset(_folder(tmp_path, "one", 1, frames=40))
    assert [len(s) for s in split_by_clip(ms)] == [40, 0, 0]  # clip-level: nothing held out
    with pytest.warns(UserWarning, match=r"only 1 clip\(s\) for 3 non-empty sets.*splitting each clip in time"):
        train, val, test = split_by_clip(ms, fallback=True)
    assert list(train) == list(range(32)) and list(val) == list(range(32, 36)) and list(test) == list(range(36, 40))
    with pytest.raises(ValueError, match="needs at least two frames.*got 0.*1 clip.*fallback=True"):
        sample_pairs(ms, 5, frames=split_by_clip(ms)[2])


@pytest.mark.parametrize("clips", [1, 2])
def test_bench_ik_on_one_or_two_clips(tmp_path, clips):
    from posekit.bench.ik import run
    from posekit.data.cases import build_cases

    with pytest.warns(UserWarning, match="cm"):
        ms = open_dataset(_folder(tmp_path, f"c{clips}", clips))
    with pytest.warns(UserWarning, match="too few for a clip-level split"):
        cases = build_cases(ms, n_cases=8)
    assert len(cases) == 8
    held_out = set(np.concatenate([ms.clip_frames(c)[-3:] for c in range(clips)]))  # last 10 % of 30 frames
    local_truth = to_root_space(ms.skeleton, ms.global_pos[sorted(held_out)])[0]
    for t in cases.target_pos:  # every target is a held-out frame
        assert np.min(np.abs(local_truth - t).max(axis=(1, 2))) < 1e-9
    with pytest.warns(UserWarning, match="too few for a clip-level split"):
        rows = run(ms, solvers=("fabrik", "dls"), effector_sets=("2",), n_cases=6, peers=False, baseline=False,
                   batched=False, methods="none")
    assert {r["method"] for r in rows} == {"fabrik", "dls"}
    assert all(r["cases"] == 6 and r["effector_error_mm_median"] < 5 for r in rows)


def test_bench_ik_cli_on_a_single_bvh_file(tmp_path, capsys):
    import json

    from posekit.cli import main

    folder = _folder(tmp_path, "single", 1)
    with pytest.warns(UserWarning):
        code = main(["bench", "ik", "--data", str(folder / "take_0.bvh"), "--solvers", "dls", "--effectors", "2",
                     "--cases", "5", "--no-peers", "--json"])
    assert code == 0
    rows = json.loads(capsys.readouterr().out)
    assert rows[0]["method"] == "dls" and rows[0]["cases"] == 5
