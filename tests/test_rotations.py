import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from posekit import rotations as rot


def test_quat_matrix_round_trip(rng):
    q = rot.random_rotations((10, 3), rng)
    np.testing.assert_allclose(rot.matrix_to_quat(rot.quat_to_matrix(q)), q, atol=1e-12)


def test_sixd_round_trip(rng):
    R = rot.quat_to_matrix(rot.random_rotations((50,), rng))
    np.testing.assert_allclose(rot.sixd_to_matrix(rot.matrix_to_sixd(R)), R, atol=1e-12)


def test_sixd_maps_any_vector_to_a_rotation(rng):
    R = rot.sixd_to_matrix(rng.normal(size=(100, 6)))
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)


def test_geodesic_distance_is_the_rotation_angle(rng):
    a = rot.quat_to_matrix(rot.random_rotations((20,), rng))
    angles = np.linspace(0, np.pi, 20)
    b = a @ Rotation.from_rotvec(np.c_[angles, 0 * angles, 0 * angles]).as_matrix()
    np.testing.assert_allclose(rot.geodesic_distance(a, b), angles, atol=1e-7)


def test_torch_matches_numpy(rng):
    torch = pytest.importorskip("torch")
    x = rng.normal(size=(8, 6))
    np.testing.assert_allclose(rot.sixd_to_matrix(torch.tensor(x)).numpy(), rot.sixd_to_matrix(x), atol=1e-12)
    R = rot.sixd_to_matrix(x)
    np.testing.assert_allclose(rot.matrix_to_sixd(torch.tensor(R)).numpy(), rot.matrix_to_sixd(R), atol=1e-12)
    R2 = rot.quat_to_matrix(rot.random_rotations(8, rng))
    np.testing.assert_allclose(rot.geodesic_distance(torch.tensor(R), torch.tensor(R2)).numpy(),
                               rot.geodesic_distance(R, R2), atol=1e-6)
    q = rot.random_rotations(8, rng)
    np.testing.assert_allclose(rot.quat_to_matrix(torch.tensor(q)).numpy(), rot.quat_to_matrix(q), atol=1e-12)
    np.testing.assert_allclose(rot.matrix_to_quat(torch.tensor(R2)).numpy(), rot.matrix_to_quat(R2), atol=1e-9)


def test_euler_follows_bvh_intrinsic_order():
    q = rot.euler_to_quat(np.array([30.0, 40.0, 50.0]), "ZXY", degrees=True)
    Rz, Rx, Ry = (Rotation.from_euler(a, d, degrees=True).as_matrix() for a, d in zip("zxy", (30, 40, 50)))
    np.testing.assert_allclose(rot.quat_to_matrix(q), Rz @ Rx @ Ry, atol=1e-12)
    np.testing.assert_allclose(rot.quat_to_euler(q, "ZXY", degrees=True), [30, 40, 50], atol=1e-9)


def test_quat_multiply_matches_matrices(rng):
    a, b = rot.random_rotations((2, 5), rng)
    np.testing.assert_allclose(rot.quat_to_matrix(rot.quat_multiply(a, b)),
                               rot.quat_to_matrix(a) @ rot.quat_to_matrix(b), atol=1e-12)
    np.testing.assert_allclose(rot.quat_to_matrix(rot.quat_multiply(a, rot.quat_inverse(a))),
                               np.broadcast_to(np.eye(3), (5, 3, 3)), atol=1e-12)


def test_wrong_shapes_are_refused():
    with pytest.raises(ValueError, match=r"expected shape \(\.\.\., 6\)"):
        rot.sixd_to_matrix(np.zeros((3, 5)))
    with pytest.raises(ValueError, match=r"expected shape \(\.\.\., 3, 3\)"):
        rot.geodesic_distance(np.zeros((3, 3)), np.zeros((3, 4)))


@pytest.mark.parametrize("order", ["ZXY", "XYZ", "zyx"])
def test_euler_and_axis_angle_accept_torch(order):
    # the module promises numpy *or* torch for every function: the torch path must agree
    torch = pytest.importorskip("torch")
    rng = np.random.default_rng(4)
    angles = rng.uniform(-3, 3, (6, 3))
    q_np = rot.euler_to_quat(angles, order)
    q_t = rot.euler_to_quat(torch.tensor(angles, requires_grad=True), order)
    assert torch.is_tensor(q_t)
    np.testing.assert_allclose(rot.quat_to_matrix(q_t.detach().numpy()), rot.quat_to_matrix(q_np), atol=1e-12)
    back = rot.quat_to_euler(torch.tensor(q_np), order)
    np.testing.assert_allclose(rot.quat_to_matrix(rot.euler_to_quat(back.numpy(), order)), rot.quat_to_matrix(q_np),
                               atol=1e-12)
    axis, angle = rng.normal(size=(6, 3)), rng.uniform(0, 3, 6)
    np.testing.assert_allclose(rot.axis_angle_to_quat(torch.tensor(axis), torch.tensor(angle)).numpy(),
                               rot.axis_angle_to_quat(axis, angle), atol=1e-12)
