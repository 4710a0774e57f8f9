import numpy as np
import pytest

from posekit import Skeleton


def test_unknown_joint_lists_valid_names(skel):
    with pytest.raises(ValueError, match=r"unknown joint 'left_pinky'.*valid names: root, chest"):
        skel.index("left_pinky")


def test_roles_resolve_to_joints(skel):
    assert skel.names[skel.index("left_hand")] == "left_wrist"
    assert skel.chain("left_hand") == [0, 1, 7, 8, 9]


def test_mirror_indices_pair_sides(skel):
    m = skel.mirror_indices()
    assert skel.names[m[skel.index("left_knee")]] == "right_knee"
    assert m[skel.index("chest")] == skel.index("chest")
    np.testing.assert_array_equal(m[m], np.arange(skel.n_joints))
    assert skel.is_symmetric()


@pytest.mark.parametrize("kwargs, msg", [
    (dict(names=["a", "a"], parents=[-1, 0], offsets=np.zeros((2, 3))), "unique"),
    (dict(names=["a", "b"], parents=[-1, 1], offsets=np.zeros((2, 3))), "parent must come before"),
    (dict(names=["a", "b"], parents=[0, -1], offsets=np.zeros((2, 3))), "only root"),
    (dict(names=["a", "b"], parents=[-1, 0], offsets=np.zeros((3, 3))), r"offsets: expected shape \(2, 3\)"),
    (dict(names=["a", "b"], parents=[-1, 0], offsets=[[0, 0, 0], [np.nan, 0, 0]]), "NaN"),
    (dict(names=["a", "b"], parents=[-1, 0], offsets=np.zeros((2, 3)), roles={"head": "c"}), "unknown joint 'c'"),
])
def test_invalid_skeletons(kwargs, msg):
    with pytest.raises(ValueError, match=msg):
        Skeleton(**kwargs)


def test_round_trip_arrays(skel, tmp_path):
    np.savez(tmp_path / "s.npz", **skel.to_arrays())
    with np.load(tmp_path / "s.npz") as z:
        back = Skeleton.from_arrays(z)
    assert back.same_as(skel) and back.roles == skel.roles


def test_tree_text_shows_hierarchy(skel):
    lines = skel.tree().splitlines()
    assert lines[0].startswith(" 0 root") and len(lines) == skel.n_joints
    assert any("left_wrist" in l and "[left_hand]" in l for l in lines)
