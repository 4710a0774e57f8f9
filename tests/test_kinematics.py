import numpy as np
import pytest

from posekit import Skeleton, bone_lengths_of, fk, rest_pose
from posekit.rotations import axis_angle_to_quat, quat_to_matrix, random_rotations


@pytest.fixture
def arm():
    # shoulder at origin, elbow 0.3 m along +X, wrist 0.25 m further, a finger off the wrist
    return Skeleton(["shoulder", "elbow", "wrist", "finger"], [-1, 0, 1, 2],
                    [[0, 0, 0], [0.3, 0, 0], [0.25, 0, 0], [0, 0.1, 0]])


def test_rest_pose_is_sum_of_offsets(arm):
    np.testing.assert_allclose(rest_pose(arm), [[0, 0, 0], [0.3, 0, 0], [0.55, 0, 0], [0.55, 0.1, 0]])


def test_fk_hand_computed_elbow_bend(arm):
    # 90 deg about +Z at the elbow turns the forearm from +X to +Y; the finger (+Y in the wrist
    # frame) then points to -X
    q = np.tile([0.0, 0, 0, 1], (4, 1))
    q[1] = axis_angle_to_quat([0, 0, 1], np.pi / 2)
    pos, rot = fk(arm, q, root_pos=np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(pos, [[1, 2, 3], [1.3, 2, 3], [1.3, 2.25, 3], [1.2, 2.25, 3]], atol=1e-12)
    np.testing.assert_allclose(rot[3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)


def test_fk_root_rotation_turns_everything(arm):
    q = np.tile([0.0, 0, 0, 1], (4, 1))
    q[0] = axis_angle_to_quat([0, 1, 0], -np.pi / 2)  # +X -> +Z
    pos, _ = fk(arm, q)
    np.testing.assert_allclose(pos[2], [0, 0, 0.55], atol=1e-12)


def test_fk_batch_dims_and_quat_vs_matrix(skel, rng):
    q = random_rotations((2, 3, skel.n_joints), rng)
    root = rng.normal(size=(2, 3, 3))
    p1, r1 = fk(skel, q, root)
    p2, r2 = fk(skel, quat_to_matrix(q), root)
    assert p1.shape == (2, 3, skel.n_joints, 3) and r1.shape == (2, 3, skel.n_joints, 3, 3)
    np.testing.assert_allclose(p1, p2, atol=1e-12)
    np.testing.assert_allclose(p1[1, 2], fk(skel, q[1, 2], root[1, 2])[0], atol=1e-12)


def test_fk_chunking_is_invisible(skel, rng):
    from posekit import kinematics

    q = random_rotations((kinematics._CHUNK * 2 + 17, skel.n_joints), rng)
    full = fk(skel, q)[0]
    np.testing.assert_allclose(full[-5:], fk(skel, q[-5:])[0], atol=1e-12)


def test_every_fk_path_gives_the_same_bits(skel, rng, monkeypatch):
    """The compiled kernel (every batch with numba; up to a few poses without), the numpy broadcasts (a few hundred
    poses without numba) and the chunked layout (thousands): the same sums in the same order, the same bits, for
    one pose, a few, and batches spanning several chunks of each path."""
    from posekit import kinematics

    n = max(kinematics._CHUNK, kinematics._COMPILED_CHUNK) + 17
    q = random_rotations((n, skel.n_joints), rng)
    root = rng.normal(size=(n, 3))
    lp = np.asarray(skel.offsets) * (1 + 0.1 * rng.random((n, skel.n_joints, 1)))
    for kw in ({}, {"root_pos": root}, {"local_pos": lp}, {"root_pos": root, "local_pos": lp}):
        got = fk(skel, q, **kw)
        monkeypatch.setattr(kinematics, "HAVE_NUMBA", False)
        chunked = fk(skel, q, **kw)
        mid = fk(skel, q[:40], **{k: v[:40] for k, v in kw.items()})  # numpy broadcasts
        assert n >= kinematics._SMALL and kinematics._ONE < 40 < kinematics._SMALL
        for i in (0, 7, 39):
            one = fk(skel, q[i], **{k: v[i] for k, v in kw.items()})  # the kernel, one pose
            for a, b in zip(one, (mid[0][i], mid[1][i])):
                assert np.array_equal(a, b)
        monkeypatch.undo()
        for a, b in zip(got, chunked):
            assert np.array_equal(a, b)
        assert np.array_equal(got[0][:40], mid[0]) and np.array_equal(got[1][:40], mid[1])


def test_fk_reproduces_shipped_positions(sample):
    pos = fk(sample.skeleton, sample.local_rot, sample.root_pos)[0]
    np.testing.assert_allclose(pos, sample.global_pos, atol=1e-5)


def test_numpy_fk_equals_torch_fk_and_is_differentiable(skel, rng):
    torch = pytest.importorskip("torch")
    q = random_rotations((5, skel.n_joints), rng)
    root = rng.normal(size=(5, 3))
    p_np, r_np = fk(skel, q, root)
    qt = torch.tensor(q, requires_grad=True)
    p_t, r_t = fk(skel, qt, torch.tensor(root))
    np.testing.assert_allclose(p_t.detach().numpy(), p_np, atol=1e-10)
    np.testing.assert_allclose(r_t.detach().numpy(), r_np, atol=1e-10)
    p_t[..., skel.index("left_hand"), :].sum().backward()
    assert qt.grad is not None and torch.isfinite(qt.grad).all() and qt.grad.abs().sum() > 0


def test_local_pos_overrides_offsets(arm):
    q = np.tile([0.0, 0, 0, 1], (2, 4, 1))
    lp = np.broadcast_to(arm.offsets, (2, 4, 3)).copy()
    lp[1, 2] = [0.5, 0, 0]  # stretch the forearm in frame 1
    pos = fk(arm, q, local_pos=lp)[0]
    assert pos[0, 2, 0] == pytest.approx(0.55) and pos[1, 2, 0] == pytest.approx(0.8)


def test_bone_lengths_are_preserved_by_fk(sample, rng):
    q = rng.normal(size=(50, sample.skeleton.n_joints, 4))  # any rotations: FK must keep every bone's length
    pos = fk(sample.skeleton, q / np.linalg.norm(q, axis=-1, keepdims=True), rng.normal(size=(50, 3)))[0]
    lengths = bone_lengths_of(sample.skeleton, pos)
    np.testing.assert_allclose(lengths, np.broadcast_to(sample.skeleton.bone_lengths(), lengths.shape), atol=1e-9)


@pytest.mark.parametrize("bad, msg", [
    (np.zeros((4, 3)), r"expected quaternions of shape \(\.\.\., 4, 4\)"),
    (np.zeros((5, 4)), r"for a 4-joint skeleton"),
])
def test_fk_wrong_shape(arm, bad, msg):
    with pytest.raises(ValueError, match=msg):
        fk(arm, bad)


def test_fk_nan_is_refused(arm):
    q = np.tile([0.0, 0, 0, 1], (4, 1))
    q[2, 0] = np.nan
    with pytest.raises(ValueError, match="local_rot contains NaN"):
        fk(arm, q)
    with pytest.raises(ValueError, match="root_pos contains NaN"):
        fk(arm, np.tile([0.0, 0, 0, 1], (4, 1)), root_pos=np.array([0, np.inf, 0]))
    with pytest.raises(ValueError, match=r"root_pos: expected shape \(\.\.\., 3\)"):
        fk(arm, np.tile([0.0, 0, 0, 1], (4, 1)), root_pos=np.zeros(2))
