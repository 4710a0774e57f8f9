"""Training past one process (posekit.learn.distributed): the device check, the batch share, per-rank seeds,
and real torchrun runs of 2 gloo processes on the CPU whose checkpoint the single-process code loads."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import torch

from posekit.learn.distributed import Run, check_device, current, start

NO_CUDA = not torch.cuda.is_available()


def test_cpu_is_the_default_and_a_run_outside_torchrun_is_one_process():
    assert check_device(None) == torch.device("cpu")
    with start("cpu") as run:
        assert current() is run and run.world == 1 and run.main and not run.distributed
    assert current().world == 1


@pytest.mark.skipif(not NO_CUDA, reason="this machine has a CUDA GPU")
def test_cuda_without_a_gpu_is_refused_with_a_sentence():
    with pytest.raises(ValueError, match="no CUDA GPU"):
        check_device("cuda")
    with pytest.raises(ValueError, match="expected cpu"):
        check_device("gpu0")
    with pytest.raises(ValueError, match="CPU or CUDA only"):
        check_device("meta")


def test_a_world_size_that_does_not_divide_the_batch_is_refused():
    run = Run(torch.device("cpu"), rank=1, world=2)
    assert run.share(256) == 128
    with pytest.raises(ValueError, match="255 does not divide among 2 processes.*256"):
        run.share(255)


def test_per_rank_seeds_rank_zero_keeps_the_seed_others_differ_and_repeat():
    seeds = [Run(rank=r, world=4).seed(7) for r in range(4)]
    assert seeds[0] == 7 and len(set(seeds)) == 4
    assert seeds == [Run(rank=r, world=4).seed(7) for r in range(4)]
    assert Run(rank=1, world=4).seed(8) != seeds[1]


def test_launcher_names_the_processes_per_node_and_the_nodes(monkeypatch):
    from posekit.learn.distributed import launcher

    monkeypatch.delenv("LOCAL_WORLD_SIZE", raising=False)
    assert launcher(2) == "torchrun --nproc-per-node 2 -m "
    monkeypatch.setenv("LOCAL_WORLD_SIZE", "4")
    assert launcher(8) == "torchrun --nnodes 2 --nproc-per-node 4 -m "


def _posekit(args, cwd, nproc=None, timeout=300):
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    pre = ([sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc-per-node", str(nproc),
            "-m", "posekit"] if nproc else [sys.executable, "-m", "posekit"])
    return subprocess.run(pre + args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.mark.skipif(not NO_CUDA, reason="this machine has a CUDA GPU")
def test_train_device_cuda_without_a_gpu_stops_before_training(tmp_path):
    r = _posekit(["train", "protores", "--steps", "5", "--device", "cuda", "--out", str(tmp_path / "p.pt")], tmp_path)
    assert r.returncode == 2 and "no CUDA GPU" in r.stderr and "train with --device cpu" in r.stderr
    assert not (tmp_path / "p.pt").exists() and "step" not in r.stdout


@pytest.mark.slow
def test_torchrun_refuses_a_batch_two_processes_cannot_share(tmp_path):
    r = _posekit(["train", "protores", "--steps", "5", "--batch", "63", "--out", str(tmp_path / "p.pt")], tmp_path,
                 nproc=2)
    assert r.returncode != 0 and "--batch 63 does not divide among 2 processes" in r.stderr
    assert not (tmp_path / "p.pt").exists()


@pytest.mark.slow
def test_protores_under_torchrun_two_gloo_processes(tmp_path):
    """2 processes, 32 poses each: the loss falls, one checkpoint, written by rank 0, one report printed, and
    the single-process code loads it and poses."""
    from posekit.evaluation.effector_cases import load_benchmark
    from posekit.models.protores.solver import ProtoResSolver, load_protores

    out = tmp_path / "protores.pt"
    r = _posekit(["train", "protores", "--steps", "120", "--batch", "64", "--width", "32", "--log-every", "40",
                  "--warmup", "20", "--out", str(out)], tmp_path, nproc=2)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.count("wrote ") == 1 and r.stdout.count("trained protores") == 1  # rank 1 prints nothing
    net = load_protores(weights=out)
    rep = net.checkpoint["extra"]["report"]
    assert rep["processes"] == 2 and rep["device"] == "cpu" and rep["steps"] == 120
    # the command that remakes it starts 2 processes again: one process would draw other batches
    assert net.checkpoint["command"].startswith("torchrun --nproc-per-node 2 -m posekit train protores "), \
        net.checkpoint["command"]
    total = rep["curves"]["total"]
    assert len(total) == 3 and total[-1] < 0.7 * total[0], total
    b = load_benchmark("random")
    solver = ProtoResSolver(net.skeleton, net=net)
    res = solver.solve(None, b.effectors(0))
    assert np.isfinite(res.effector_error).all() and np.isfinite(res.pose.local_rot).all()


@pytest.mark.slow
def test_fit_and_aegan_under_torchrun(tmp_path):
    """The shared fit loop (lesson 02's inverse-rig network) and AE-GAN's own loop, each with 2 processes."""
    from posekit.data import load_sample
    from posekit.invrig.humanoid import HumanoidRig
    from posekit.invrig.nn import load_inverse_net
    from posekit.models.aegan.networks import AEGAN

    rig = HumanoidRig(load_sample().skeleton)
    losses = {}
    for nproc in (2, None):  # 2048 samples, batches of 256: every batch shared equally by the 2 processes
        folder = tmp_path / f"invrig{nproc}"
        r = _posekit(["train", "invrig", "--methods", "uniform", "--samples", "2048", "--epochs", "6",
                      "--out", str(folder)], tmp_path, nproc=nproc)
        assert r.returncode == 0, r.stderr[-3000:]
        assert r.stdout.count("wrote ") == 1
        net = load_inverse_net(folder / "invrig_nn_uniform.pt", rig.names, rig.skeleton.names)
        losses[nproc] = net.meta["extra"]["train_loss"]
    assert len(losses[2]) == 6 and losses[2][-1] < 0.7 * losses[2][0], losses
    # the same permutation, each process half of every batch, DDP's mean of their gradients: the one-process
    # run's steps, to float rounding (a process training alone, or on the wrong share, is far off)
    np.testing.assert_allclose(losses[2], losses[None], rtol=1e-4)
    Y = rig.default()[None]
    assert np.isfinite(net.predict(rig.evaluate(Y))).all()

    out = tmp_path / "aegan.pt"
    r = _posekit(["train", "aegan", "--steps", "60", "--batch", "32", "--log-every", "20", "--out", str(out)],
                 tmp_path, nproc=2)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.count("wrote ") == 1
    model = AEGAN.load(out)
    rep = model.info["extra"]["report"]
    assert rep["processes"] == 2 and rep["steps"] == 60
    rec = rep["curves"]["rec_x"]
    assert len(rec) == 3 and rec[-1] < 0.8 * rec[0], rec
    x = np.zeros((3, model.generator(torch.zeros(1, model.config.latent)).shape[1]), np.float32)
    assert np.isfinite(model.decode(model.encode(x))).all()
