"""The exercises' checkers refuse wrong answers, each for the reason a student would make it, and accept every
convention the exercise's text allows: a list of wrong answers per checker of lesson 01 (a wrong sign, the iteration
budget or tolerance ignored, the input changed in place, the compared-against function called, the planted joint
moved) and for lesson 03's pose vector (indices of one skeleton hard-coded); the machinery shared by all checkers
(``posekit.exercises._check``)."""

from __future__ import annotations

import inspect
import os
import sys
import time

import numpy as np
import pytest

from posekit.course.lessons import find_lesson
from posekit.course.solutions import solution_function
from posekit.exercises import check_fabrik_planted, check_pose_vector, check_two_bone_swivel
from posekit.exercises._check import Either, report
from posekit.exercises.nb01 import swivel_pole
from posekit.ik.single_chain import fabrik_chain
from posekit.ik.two_bone import two_bone_ik

PLANTED = solution_function(find_lesson("01"), "exercise_fabrik_planted")
SWIVEL = solution_function(find_lesson("01"), "exercise_two_bone_swivel")


def _own_two_bone(root, mid, end, target, swivel, margin=0.0, sign=1.0, from_up=False):
    """A student's own swivel two-bone IK, with the slips below as options."""
    l1, l2 = np.linalg.norm(mid - root), np.linalg.norm(end - mid)
    dist = np.linalg.norm(target - root)
    d = np.clip(dist, abs(l1 - l2) + margin, l1 + l2 - margin)
    u = (target - root) / dist
    ref = np.array([0.0, 1.0, 0.0]) if from_up else mid - root
    v0 = ref - (ref @ u) * u
    v0 /= np.linalg.norm(v0)
    v = np.cos(sign * swivel) * v0 + np.sin(sign * swivel) * np.cross(u, v0)
    ca = np.clip((l1**2 + d**2 - l2**2) / (2 * l1 * d), -1, 1)
    return root + l1 * (ca * u + np.sqrt(1 - ca**2) * v), root + d * u


def test_the_reference_solutions_and_a_students_own_conventions_pass(capsys):
    assert check_fabrik_planted(PLANTED) and check_two_bone_swivel(SWIVEL)
    # clamping the distance exactly, or with section 1's 1e-6 m margin: both are what the text allows
    assert check_two_bone_swivel(lambda *a: _own_two_bone(*a, margin=0.0))
    assert check_two_bone_swivel(lambda *a: _own_two_bone(*a, margin=1e-6))
    out = capsys.readouterr().out
    assert out.count("✓") == 4 and "✗" not in out


PLANTED_WRONG = {
    "max_iter ignored": (lambda p, t, tol, it: PLANTED(p, t, tol, 500), "case 5 differs"),
    "tolerance ignored": (lambda p, t, tol, it: PLANTED(p, t, 1e-9, it), "case 1 differs"),
    "input changed in place": (lambda p, t, tol, it: _in_place(p, PLANTED(p, t, tol, it)),
                               "changed its input `positions` in place"),
    "the base kept instead of the end": (lambda p, t, tol, it: _fabrik_by_hand(p, t, tol, it), "case 1 differs"),
    "posekit's FABRIK called": (lambda p, t, tol, it: fabrik_chain(p[::-1], t, tol, it)[0][::-1],
                                "calls posekit.ik.single_chain.fabrik_chain"),
    "not attempted": (lambda *a: (_ for _ in ()).throw(NotImplementedError), "not attempted yet"),
    "a bug that raises": (lambda p, t, tol, it: p[99], "case 1 raised IndexError"),
}


def _in_place(p, new):
    p[:] = new
    return p


def _fabrik_by_hand(p, t, tol, it):
    """Section 2's FABRIK, copied: the first joint kept, the last one reaching."""
    p = np.array(p, float)
    d = np.linalg.norm(np.diff(p, axis=0), axis=1)
    base = p[0].copy()
    for _ in range(it):
        if np.linalg.norm(p[-1] - t) <= tol:
            break
        p[-1] = t
        for i in range(len(d) - 1, -1, -1):
            p[i] = p[i + 1] + d[i] * (p[i] - p[i + 1]) / np.linalg.norm(p[i] - p[i + 1])
        p[0] = base
        for i in range(len(d)):
            p[i + 1] = p[i] + d[i] * (p[i + 1] - p[i]) / np.linalg.norm(p[i + 1] - p[i])
    return p


@pytest.mark.parametrize("slip", PLANTED_WRONG)
def test_check_fabrik_planted_refuses_each_wrong_answer_and_says_why(slip, capsys):
    answer, said = PLANTED_WRONG[slip]
    assert check_fabrik_planted(answer) is False
    out = capsys.readouterr().out
    assert said in out, out


def _moves_mid(root, mid, end, target, swivel):
    new_mid, new_end = _own_two_bone(root, mid, end, target, swivel)
    mid[:] = new_mid
    return mid, new_end


SWIVEL_WRONG = {
    "the wrong sign": (lambda *a: _own_two_bone(*a, sign=-1.0), "the middle one is"),
    "the angle measured from up, not from the bend": (lambda *a: _own_two_bone(*a, from_up=True), "the middle one is"),
    "the swivel ignored": (lambda r, m, e, t, s: _own_two_bone(r, m, e, t, 0.0), "case 1 differs"),
    "no clamping": (lambda r, m, e, t, s: (_own_two_bone(r, m, e, t, s)[0], t), "case 5 differs"),
    "input changed in place": (lambda *a: _moves_mid(*a), "changed its input `mid` in place"),
    "posekit's two-bone IK called": (lambda r, m, e, t, s: two_bone_ik(r, m, e, t, swivel_pole(r, m, t, s))[:2],
                                     "calls posekit.ik.two_bone.two_bone_ik"),
    "the checker's watch switched off": (lambda *a: (sys.setprofile(None), SWIVEL(*a))[1],
                                         "switched the checker's watch off"),
}


@pytest.mark.parametrize("slip", SWIVEL_WRONG)
def test_check_two_bone_swivel_refuses_each_wrong_answer_and_says_why(slip, capsys):
    answer, said = SWIVEL_WRONG[slip]
    assert check_two_bone_swivel(answer) is False
    out = capsys.readouterr().out
    assert said in out, out


def test_check_pose_vector_refuses_indices_of_one_skeleton(capsys):
    from posekit.data.bandai_mini import load_bandai_mini
    from posekit.data.metrics import body_joints

    bandai = load_bandai_mini().skeleton
    fixed = body_joints(bandai)  # Bandai's body joints, whatever skeleton comes in

    def hard_coded(skeleton, global_pos):
        local = _vector_own(skeleton, global_pos, helper=True).reshape(-1, 3)
        return local[[j for j in fixed if j < skeleton.n_joints]].ravel()
    assert check_pose_vector(hard_coded) is False
    assert "case 2 returned shape" in capsys.readouterr().out


def test_report_accepts_any_answer_of_an_either_and_names_the_nearest_when_none_matches(capsys):
    cases = [((), Either([0.0, 1.0], [0.0, 1.1]), lambda got, exp: f"nearest {exp.tolist()}")]
    assert report("demo", lambda: np.array([0.0, 1.1]), cases)
    assert not report("demo", lambda: np.array([0.0, 1.2]), cases)
    assert "nearest [0.0, 1.1]" in capsys.readouterr().out


def test_report_sees_a_forbidden_function_called_under_another_name(capsys):
    def reference(x):
        return x * 2

    alias = reference
    cases = [((np.ones(2),), np.full(2, 2.0), lambda g, e: "")]
    assert report("demo", lambda x: x * 2, cases, forbid=(reference,))
    assert not report("demo", lambda x: alias(x), cases, forbid=(reference,))
    assert "calls " in capsys.readouterr().out and sys.getprofile() is None


# -- the key out of the answer's reach (posekit.exercises._judge) ----------------------------------------------------

PEEK = '''
def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    """Walks the call stack to the checker's cases and returns the expected answer of the case in hand."""
    import sys
    import numpy as np
    frame = sys._getframe(1)
    while frame is not None:
        for value in list(frame.f_locals.values()):
            for case in (value if isinstance(value, list) else []):
                if isinstance(case, tuple) and len(case) == 3 and isinstance(case[0], tuple):
                    if np.array_equal(case[0][0], positions) and np.array_equal(case[0][1], target) \\
                            and case[0][2] == tolerance and case[0][3] == max_iter:
                        return case[1]
        frame = frame.f_back
    return positions
'''

IN_A_THREAD = '''
def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    import threading
    from posekit.ik.single_chain import fabrik_chain
    out = {}
    t = threading.Thread(target=lambda: out.update(r=fabrik_chain(positions[::-1], target, tolerance, max_iter)))
    t.start()
    t.join()
    return out["r"][0][::-1]
'''

HOOK_OFF = '''
def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    import sys
    from posekit.ik.single_chain import fabrik_chain
    hook = sys.getprofile()
    sys.setprofile(None)
    result = fabrik_chain(positions[::-1], target, tolerance, max_iter)[0][::-1]
    sys.setprofile(hook)
    return result
'''

RENAMED_COPY = '''
import types
from posekit.ik.single_chain import fabrik_chain as _f
_mine = types.FunctionType(_f.__code__.replace(co_name="my_own_fabrik"), _f.__globals__, "my_own_fabrik",
                           _f.__defaults__)

def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    return _mine(positions[::-1], target, tolerance, max_iter)[0][::-1]
'''


def _define(source):
    namespace = {}
    exec(compile(source, "<answer cell>", "exec"), namespace)  # noqa: S102 - the cheats under test
    return namespace["exercise_fabrik_planted"]


def test_an_answer_that_reads_the_checkers_frames_finds_no_key(capsys):
    assert check_fabrik_planted(_define(PEEK)) is False
    assert "differs" in capsys.readouterr().out
    from posekit.course.grading import fresh_check

    fresh = fresh_check("01", "check_fabrik_planted", "exercise_fabrik_planted", PEEK)
    assert not fresh.passed and "differs" in fresh.said, fresh.said


@pytest.mark.parametrize("cheat", ["IN_A_THREAD", "HOOK_OFF", "RENAMED_COPY"])
def test_calling_the_reference_is_seen_in_a_thread_with_the_hook_off_and_through_a_renamed_copy(cheat, capsys):
    source = globals()[cheat]
    assert check_fabrik_planted(_define(source)) is False
    out = capsys.readouterr().out
    assert "calls posekit.ik.single_chain.fabrik_chain" in out or "switched the checker's watch off" in out, out
    from posekit.course.grading import fresh_check

    fresh = fresh_check("01", "check_fabrik_planted", "exercise_fabrik_planted", source)
    assert not fresh.passed, fresh.said
    assert "calls posekit.ik.single_chain.fabrik_chain" in fresh.said or "watch off" in fresh.said, fresh.said


def test_rebinding_the_checkers_machinery_in_the_kernel_changes_no_verdict(capsys, monkeypatch):
    """What a student's kernel rebinds (the comparison, the report, the reference function) is not what the judge
    uses: a wrong answer stays wrong."""
    import posekit.exercises._check as check
    import posekit.exercises.nb01 as nb01
    import posekit.ik.single_chain as single_chain

    def wrong(positions, target, tolerance, max_iter):
        return positions.copy()

    monkeypatch.setattr(check, "_allclose", lambda *a, **k: True)
    monkeypatch.setattr(nb01, "report", lambda *a, **k: True)
    monkeypatch.setattr(single_chain, "fabrik_chain", lambda p, *a, **k: (p, 0))
    assert check_fabrik_planted(wrong) is False
    assert "differs" in capsys.readouterr().out


def test_a_kernels_judge_is_outside_its_process_group_and_ends_with_its_input():
    """The judge a check starts is not among the children a shutting-down kernel signals and waits for (ipykernel
    waits until no process of its group is left, and the judge, killed but not reaped, kept every shutdown after a
    check waiting 2.5 s); it still ends when the process that asked it goes (its input closes)."""
    import posekit.exercises._judge as judge

    assert check_fabrik_planted(PLANTED) is True
    proc = judge._WARM["proc"]
    assert proc is not None and proc.poll() is None
    assert os.getpgid(proc.pid) != os.getpgrp()
    proc.stdin.close()  # as when the kernel is gone
    assert proc.wait(timeout=30) == 0
    judge._drop_judge()
    assert check_fabrik_planted(PLANTED) is True  # the next check starts another


def test_the_fresh_check_passes_the_reference_solution():
    import inspect

    from posekit.course.grading import fresh_check

    fresh = fresh_check("01", "check_fabrik_planted", "exercise_fabrik_planted", inspect.getsource(PLANTED),
                        imports="import numpy as np")
    assert fresh.passed, fresh.said


# -- the wrong answers the issue found passing, each refused with its reason; the right variants accepted ----------

def _solutions(number):
    from posekit.course.solutions import _module

    return _module(find_lesson(number))


def _no_out_of_reach_branch(p, t, tol, it):
    """Planted FABRIK without the out-of-reach branch (section 2's loop, read from the planted end): only many
    iterations get it near a stretched chain."""
    return _fabrik_by_hand(np.asarray(p)[::-1], t, tol, it)[::-1]


def _tolerance_after_the_pass(p, t, tol, it):
    out = PLANTED(p, t, 0.0, 1)  # one pass first, the tolerance only tested afterwards
    return PLANTED(out, t, tol, it - 1) if it > 1 else out


def _slerp_without_guard(q0, q1, s):
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    if q0 @ q1 < 0:
        q1 = -q1
    with np.errstate(invalid="ignore", divide="ignore"):
        theta = np.arccos(np.clip(q0 @ q1, -1, 1))
        return (np.sin((1 - s) * theta) * q0 + np.sin(s * theta) * q1) / np.sin(theta)


WRONG = {
    "01 planted FABRIK without the out-of-reach branch": ("check_fabrik_planted", _no_out_of_reach_branch,
                                                           "case 7 differs"),
    "01 planted FABRIK testing the tolerance after a pass": ("check_fabrik_planted", _tolerance_after_the_pass,
                                                              "case 8 differs"),
    "06 slerp with no guard for nearly equal quaternions": ("check_slerp", _slerp_without_guard, "lerp"),
}


@pytest.mark.parametrize("slip", WRONG)
def test_each_checker_refuses_the_wrong_answers_that_used_to_pass(slip, capsys):
    import posekit.exercises

    checker, answer, said = WRONG[slip]
    assert getattr(posekit.exercises, checker)(answer) is False
    out = capsys.readouterr().out
    assert said in out, out


CALLS_POSEKIT = {  # checker: (lesson, the reference solution, the posekit function the answer calls, its name)
    "check_local_from_global": ("00", "exercise_local_from_global", "posekit.kinematics:fk"),
    "check_matrix_to_quat": ("00", "exercise_matrix_to_quat", "posekit.rotations:matrix_to_quat"),
    "check_bone_drift": ("00", "exercise_bone_drift", "posekit.kinematics:bone_lengths_of"),
    "check_gpr_loo": ("02", "exercise_gpr_loo", "posekit.invrig.gpr:cross_validate"),
    "check_dls_prior": ("02", "exercise_dls_prior", "posekit.invrig.jacobian:refine"),
    "check_pose_vector": ("03", "exercise_pose_vector", "posekit.transforms:to_root_space"),
    "check_pose_from_vector": ("03", "exercise_pose_from_vector", "posekit.data.pose_vectors:poses_from_vectors"),
    "check_authors_loss": ("03", "exercise_authors_loss", "posekit.models.pose_autoencoder.train:solver_loss"),
    "check_spl_all": ("04", "exercise_spl_all", "posekit.models.aegan.numpy_nets:tree_levels"),
    "check_latent_loss": ("04", "exercise_latent_loss", "posekit.models.aegan.latent_opt:Problem.loss"),
    "check_adversarial": ("04", "exercise_adversarial", "posekit.models.aegan.train:_bce"),
    "check_look_at_angle": ("05", "exercise_look_at_angle", "posekit.exercises.nb05:look_at_angle_reference"),
    "check_rotation_noise": ("05", "exercise_rotation_noise", "posekit.models.protores.data:axis_angle_matrix"),
    "check_effector_inputs": ("05", "exercise_effector_inputs", "posekit.models.protores.networks:centroid"),
    "check_drag_on_sphere": ("06", "exercise_drag_on_sphere", "posekit.exercises.nb06:sphere_drag_reference"),
    "check_slerp": ("06", "exercise_slerp", "posekit.ik.keyframes:slerp"),
}


@pytest.mark.parametrize("checker", CALLS_POSEKIT)
def test_each_checker_forbids_the_posekit_function_that_computes_its_answer(checker, capsys):
    """An answer that calls the function is refused, whatever it returns (here: the reference solution's answer,
    after the call; the call itself may fail on the answer's own arguments)."""
    import importlib

    import posekit.exercises

    lesson, solution, target = CALLS_POSEKIT[checker]
    module, _, path = target.partition(":")
    function = importlib.import_module(module)
    for part in path.split("."):
        function = getattr(function, part)
    right = solution_function(find_lesson(lesson), solution)

    def calls(*args):
        try:
            function(*args)
        except Exception:  # noqa: BLE001 - the call is what is watched, not what it returns
            pass
        return right(*args)

    assert getattr(posekit.exercises, checker)(calls) is False
    out = capsys.readouterr().out
    assert "calls posekit." in out and f".{path.split('.')[-1]}, the function it is compared against" in out, out


def test_float32_answers_and_tuples_of_rows_are_accepted(capsys):
    def in_float32(root, mid, end, target, swivel):
        m, e = SWIVEL(*(np.asarray(a, np.float32) for a in (root, mid, end, target)), np.float32(swivel))
        return np.asarray(m, np.float32), np.asarray(e, np.float32)

    assert check_two_bone_swivel(in_float32)
    assert check_fabrik_planted(lambda *a: tuple(PLANTED(*a)))  # the joints as a tuple of rows
    out = capsys.readouterr().out
    assert out.count("✓") == 2, out


# -- every checker: its wrong answers, each refused with its reason; its right variants, each accepted ---------------
# (lesson: {checker: ({wrong answer: (function, what the verdict must say)}, {right variant: function})}), filled in
# below lesson by lesson; two tests read it.

BY_CHECKER: dict = {}


def _checker(name):
    import posekit.exercises

    return getattr(posekit.exercises, name)


def _all_wrong():
    return [(checker, slip) for checker, (wrong, _) in BY_CHECKER.items() for slip in wrong]


def _all_right():
    return [(checker, variant) for checker, (_, right) in BY_CHECKER.items() for variant in right]


# lesson 04, exercise 1: the dense SPL

SPL_ALL = solution_function(find_lesson("04"), "exercise_spl_all")


def _chains(parents):
    out = []
    for j in range(len(parents)):
        chain, k = [], int(parents[j])
        while k >= 0:
            chain.append(k)
            k = int(parents[k])
        out.append(chain)
    return out


def _spl_own(h, parents, U, c, A, V, d, order="depth", ancestors="all", relu=True, out_bias=True, dtype=float):
    """A student's own dense SPL, with the slips below as options."""
    h = np.asarray(h, dtype)
    J = len(parents)
    chains = _chains(parents)
    o = V[0].shape[0]
    outs = [np.zeros((len(h), o), dtype) for _ in range(J)]
    if order == "depth":
        visit = sorted(range(J), key=lambda j: len(chains[j]))
    elif order == "index":
        visit = range(J)
    else:  # breadth first from the first root only
        root = list(parents).index(-1)
        visit, queue = [], [root]
        while queue:
            j = queue.pop(0)
            visit.append(j)
            queue += [k for k in range(J) if parents[k] == j]
    for j in visit:
        pre = h @ np.asarray(U[j], dtype).T + np.asarray(c[j], dtype)
        chain = chains[j]
        if chain:
            if ancestors == "parent":
                pre = pre + outs[chain[0]] @ np.asarray(A[j], dtype)[:, :o].T
            else:
                row = chain if ancestors == "all" else chain[::-1]
                pre = pre + np.concatenate([outs[a] for a in row], axis=1) @ np.asarray(A[j], dtype).T
        act = np.maximum(pre, 0) if relu else pre
        outs[j] = act @ np.asarray(V[j], dtype).T + (np.asarray(d[j], dtype) if out_bias else 0)
    return np.stack(outs, axis=1)


def _spl_recursive(h, parents, U, c, A, V, d):
    """Each joint's output on demand, its parent's first (memoised): no ordering needed."""
    memo = {}

    def o(j):
        if j not in memo:
            chain = _chains(parents)[j]
            pre = h @ U[j].T + c[j]
            if chain:
                pre = pre + np.concatenate([o(a) for a in chain], axis=1) @ A[j].T
            memo[j] = np.maximum(pre, 0) @ V[j].T + d[j]
        return memo[j]
    return np.stack([o(j) for j in range(len(parents))], axis=1)


def _sorts_parents(h, parents, *rest):
    out = SPL_ALL(h, list(parents), *rest)
    if isinstance(parents, list):
        parents.sort()
    return out


def _pops_a(h, parents, U, c, A, V, d):
    out = SPL_ALL(h, parents, U, c, list(A), V, d)
    A.pop()
    return out


def _centres_h(h, parents, *rest):
    out = SPL_ALL(h, parents, *rest)
    h -= h.mean(axis=0)
    return out


def _calls_tree_levels(h, parents, *rest):
    from posekit.models.aegan.spl import tree_levels

    tree_levels(parents, "all")
    return SPL_ALL(h, parents, *rest)


BY_CHECKER["check_spl_all"] = ({
    "the parent only (the sparse variant)": (lambda *a: _spl_own(*a, ancestors="parent"),
                                             "ancestors' outputs side by side, nearest first"),
    "the ancestors root first": (lambda *a: _spl_own(*a, ancestors="root first"), "nearest first"),
    "the joints visited by index": (lambda *a: _spl_own(*a, order="index"), "case 2 differs"),
    "one root assumed": (lambda *a: _spl_own(*a, order="first root"), "never computed"),
    "no relu": (lambda *a: _spl_own(*a, relu=False), "relu before V_j"),
    "no output bias": (lambda *a: _spl_own(*a, out_bias=False), "both biases"),
    "the caller's parents sorted": (_sorts_parents, "changed its input `parents` in place"),
    "an item popped off the caller's A": (_pops_a, "changed its input `A` in place"),
    "the caller's h centred in place": (_centres_h, "changed its input `h` in place"),
    "posekit's tree_levels called": (_calls_tree_levels, "calls posekit.models.aegan.numpy_nets.tree_levels"),
    "the joints' axis first": (lambda *a: np.swapaxes(SPL_ALL(*a), 0, 1), "returned shape"),
}, {
    "the reference solution": SPL_ALL,
    "in float32": lambda *a: _spl_own(*a, dtype=np.float32),
    "(N, J * out), posekit's layout": lambda *a: SPL_ALL(*a).reshape(len(a[0]), -1),
    "recursive, memoised": _spl_recursive,
})


def test_the_dense_spl_reference_is_posekits_layer_with_every_ancestor():
    """The checker's expected answers are posekit's ``StructuredPrediction(ancestors="all")``, weights mapped."""
    import torch

    from posekit.exercises.nb04 import spl_all_reference
    from posekit.models.aegan.spl import StructuredPrediction

    parents = [2, -1, 1, 2, 3, -1, 5]
    torch.manual_seed(0)
    layer = StructuredPrediction(5, parents, out=3, hidden=4, ancestors="all")
    J, k, H, o = len(parents), 4, 5, 3
    U = layer.shared.weight.detach().double().numpy().reshape(J, k, H)
    c = layer.shared.bias.detach().double().numpy().reshape(J, k)
    A, V, d = [None] * J, np.zeros((J, o, k)), np.zeros((J, o))
    for lv, (js, _) in enumerate(layer.levels):
        for r, j in enumerate(js):
            A[j] = layer.anc[lv][r].detach().double().numpy().T
            V[j] = layer.w_out[lv][r].detach().double().numpy().T
            d[j] = layer.b_out[lv][r].detach().double().numpy()
    h = torch.randn(6, H)
    with torch.no_grad():
        theirs = layer(h).double().numpy().reshape(6, J, o)
    assert np.allclose(spl_all_reference(h.double().numpy(), parents, U, c, A, V, d), theirs, atol=1e-5)


# lesson 04, exercise 2: Eq. (6) and its gradient

LATENT = solution_function(find_lesson("04"), "exercise_latent_loss")


def _latent_own(x, t, cols, sc, scale=True, mean=False, two=True, one_scale=False, zero_elsewhere=True,
                dtype=float):
    x, t, sc = (np.asarray(a, dtype) for a in (x, t, sc))
    s = np.full_like(sc, sc[0]) if one_scale else sc
    diff = (x[cols] - t) * (s if scale else 1)
    loss = np.mean(diff ** 2) if mean else np.sum(diff ** 2)
    g = np.zeros_like(x) if zero_elsewhere else np.ones_like(x)
    g[cols] = (2 if two else 1) * diff * (s if scale else 1)
    return loss, g


def _latent_in_place(x, t, cols, sc):
    x[cols] -= t  # the difference, in the caller's pose
    diff = x[cols] * sc
    g = np.zeros(len(x))
    g[cols] = 2 * diff * sc
    return np.sum(diff ** 2), g


BY_CHECKER["check_latent_loss"] = ({
    "the scale ignored (z-scored units, not metres)": (lambda *a: _latent_own(*a, scale=False), "the loss is"),
    "a mean, not a sum": (lambda *a: _latent_own(*a, mean=True), "not a mean"),
    "one scale for every column": (lambda *a: _latent_own(*a, one_scale=True), "the loss is"),
    "the gradient without its factor 2": (lambda *a: _latent_own(*a, two=False), "the gradient differs"),
    "a gradient outside the target columns": (lambda *a: _latent_own(*a, zero_elsewhere=False),
                                             "0 elsewhere"),
    "the caller's pose changed in place": (_latent_in_place, "changed its input `x` in place"),
}, {
    "the reference solution": LATENT,
    "in float32": lambda *a: _latent_own(*a, dtype=np.float32),
    "the loss as a 0-d array": lambda *a: (np.asarray(LATENT(*a)[0]), LATENT(*a)[1]),
})


# lesson 04, exercise 3: the adversarial losses and their gradients

ADVERSARIAL = solution_function(find_lesson("04"), "exercise_adversarial")


def _sig(x):
    with np.errstate(over="ignore"):
        return 1.0 / (1.0 + np.exp(-x))


def _adv_own(real, fake, s, naive=False, sigmoid_ratio=False, saturating=False, no_smoothing=False, pooled=False,
             not_mean_grad=False, sign=1.0, wrt_d=False, smooth_fake=False, log1p=False, dtype=float):
    """A student's own adversarial losses, with the slips below as options."""
    r, f = np.asarray(real, dtype), np.asarray(fake, dtype)
    s = 1.0 if no_smoothing else s
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        if naive:
            sp = lambda x: -np.log(_sig(-x))  # noqa: E731 - softplus(x) = -log sigmoid(-x), overflowing
        elif log1p:
            sp = lambda x: np.maximum(x, 0) + np.log1p(np.exp(-np.abs(x)))  # noqa: E731
        else:
            sp = lambda x: np.logaddexp(0, x)  # noqa: E731
        if sigmoid_ratio:
            sig = lambda x: np.exp(x) / (1 + np.exp(x))  # noqa: E731
        else:
            sig = lambda x: np.asarray(_sig(x), dtype)  # noqa: E731
        yf = (1 - s) if smooth_fake else 0.0
        terms_r = s * sp(-r) + (1 - s) * sp(r)
        terms_f = yf * sp(-f) + (1 - yf) * sp(f)
        loss_d = (terms_r.sum() + terms_f.sum()) if pooled else terms_r.mean() + terms_f.mean()
        loss_g = -np.mean(sp(f)) if saturating else np.mean(sp(-f))
        nr, nf = (1, 1) if not_mean_grad else (len(r), len(f))
        dr, df, dg = sig(r) - s, sig(f) - yf, sig(f) - 1
        if wrt_d:  # d BCE / d D instead of d BCE / d logit
            dr, df, dg = (x / (sig(v) * (1 - sig(v))) for x, v in ((dr, r), (df, f), (dg, f)))
        return loss_d, sign * dr / nr, sign * df / nf, loss_g, sign * dg / nf


def _clips_in_place(real, fake, s):
    np.clip(real, -50, 50, out=real)
    return ADVERSARIAL(real, fake, s)


def _calls_torch_bce(real, fake, s):
    import torch
    import torch.nn.functional as F

    F.binary_cross_entropy_with_logits(torch.as_tensor(fake), torch.ones(len(fake), dtype=torch.float64))
    return ADVERSARIAL(real, fake, s)


BY_CHECKER["check_adversarial"] = ({
    "-log(sigmoid(l)) written naively": (lambda *a: _adv_own(*a, naive=True), "not finite"),
    "sigmoid as exp(l) / (1 + exp(l))": (lambda *a: _adv_own(*a, sigmoid_ratio=True), "not finite"),
    "the saturating generator loss": (lambda *a: _adv_own(*a, saturating=True), "the saturating form"),
    "the smoothing ignored": (lambda *a: _adv_own(*a, no_smoothing=True), "the smoothing ignored"),
    "the smoothing put on the fake labels too": (lambda *a: _adv_own(*a, smooth_fake=True),
                                                 "case 1 differs: the discriminator's loss"),
    "one sum over real and fake": (lambda *a: _adv_own(*a, pooled=True), "not one sum or mean"),
    "gradients not divided by N": (lambda *a: _adv_own(*a, not_mean_grad=True), "divided by N"),
    "gradients of the wrong sign": (lambda *a: _adv_own(*a, sign=-1.0), "the sign"),
    "gradients with respect to D, not the logit": (lambda *a: _adv_own(*a, wrt_d=True), "not to D"),
    "the caller's logits clipped in place": (_clips_in_place, "changed its input `real_logits` in place"),
    "torch's binary cross-entropy called": (_calls_torch_bce,
                                            "calls torch.nn.functional.binary_cross_entropy_with_logits"),
}, {
    "the reference solution": ADVERSARIAL,
    "its own softplus and sigmoid": _adv_own,
    "in float32": lambda *a: _adv_own(*a, dtype=np.float32),
    "softplus as max(x, 0) + log1p(exp(-|x|))": lambda *a: _adv_own(*a, log1p=True),
})


# lesson 06, exercise 1: a drag on the bone's sphere

SPHERE = solution_function(find_lesson("06"), "exercise_drag_on_sphere")


def _sphere_own(c, q, centre, r, far=False, unit_d=False, miss="nearest", in_front=True, clamp=True,
                radius=None, dtype=float):
    """A student's own sphere drag, with the slips below as options."""
    c, q, centre = (np.asarray(a, dtype) for a in (c, q, centre))
    r = r if radius is None else radius
    d = q - c
    a = 1.0 if unit_d else d @ d
    b = 2 * d @ (c - centre)
    disc = b * b - 4 * a * ((c - centre) @ (c - centre) - r * r)
    if disc >= 0:
        roots = ((-b + np.sqrt(disc)) / (2 * a), (-b - np.sqrt(disc)) / (2 * a))
        roots = sorted(roots, reverse=far)
        for t in roots:
            if t > 0 or not in_front:
                return c + t * d
    if miss == "none":
        return None
    if miss == "nan":
        return np.full(3, np.nan)
    if miss == "near q":
        v = q - centre
    else:
        t = ((centre - c) @ d) / (d @ d)
        v = c + (max(t, 0.0) if clamp else t) * d - centre
    return centre + r * v / np.linalg.norm(v)


def _sphere_moves_q(c, q, centre, r):
    q -= c  # the ray's direction, in the caller's array
    return SPHERE(c, q + c, centre, r)


def _plane_drag(c, q, centre, r):
    """Section 3's drag, on the plane through the joint facing the camera: the bone's length is lost."""
    n = c - (centre + [0.0, r, 0.0])
    d = q - c
    t = ((centre + [0.0, r, 0.0] - c) @ n) / (d @ n)
    return c + t * d


BY_CHECKER["check_drag_on_sphere"] = ({
    "the far intersection": (lambda *a: _sphere_own(*a, far=True), "case 1 differs"),
    "d taken as a unit vector": (lambda *a: _sphere_own(*a, unit_d=True), "not of unit length"),
    "None when the ray misses": (lambda *a: _sphere_own(*a, miss="none"), "got None"),
    "nan when the ray misses": (lambda *a: _sphere_own(*a, miss="nan"), "not finite"),
    "an intersection behind the camera": (lambda *a: _sphere_own(*a, in_front=False), "where the ray leaves"),
    "the line's nearest point, not the ray's": (lambda *a: _sphere_own(*a, clamp=False), "the camera itself"),
    "the sphere's point nearest q": (lambda *a: _sphere_own(*a, miss="near q"), "the sphere's point nearest the ray"),
    "the radius ignored": (lambda *a: _sphere_own(*a, radius=1.0), "not on the sphere"),
    "section 3's plane drag": (_plane_drag, "not on the sphere"),
    "the caller's q changed in place": (_sphere_moves_q, "changed its input `q` in place"),
}, {
    "the reference solution": SPHERE,
    "the quadratic's coefficients": _sphere_own,
    "in float32": lambda *a: _sphere_own(*a, dtype=np.float32),
    "a list": lambda *a: list(SPHERE(*a)),
})


# lesson 06, exercise 2: slerp

SLERP = solution_function(find_lesson("06"), "exercise_slerp")


def _slerp_own(q0, q1, s, flip=True, lerp_above=1 - 1e-12, in_place=False, swap=False, dtype=float):
    q0, q1 = np.asarray(q0, dtype), (q1 if in_place else np.asarray(q1, dtype))
    if flip and q0 @ q1 < 0:
        if in_place:
            q1 *= -1
        else:
            q1 = -q1
    d = float(np.clip(q0 @ q1, -1, 1))
    if swap:
        s = 1 - s
    if abs(d) > lerp_above:
        q = (1 - s) * q0 + s * q1
        return (q / np.linalg.norm(q)).astype(dtype)
    theta = np.arccos(d)
    return ((np.sin((1 - s) * theta) * q0 + np.sin(s * theta) * q1) / np.sin(theta)).astype(dtype)


BY_CHECKER["check_slerp"] = ({
    "no guard for nearly equal quaternions": (_slerp_without_guard, "lerp"),
    "the long way round": (lambda *a: _slerp_own(*a, flip=False), "the shorter way round"),
    "the lerp fallback far from equal": (lambda *a: _slerp_own(*a, lerp_above=0.99), "taken too early"),
    "s and 1 - s swapped": (lambda *a: _slerp_own(*a, swap=True), "case 1 differs"),
    "the caller's q1 flipped in place": (lambda *a: _slerp_own(*a, in_place=True), "changed its input `q1` in place"),
}, {
    "the reference solution": SLERP,
    "posekit's threshold (lerp above q0 . q1 = 0.9995)": lambda *a: _slerp_own(*a, lerp_above=0.9995),
    "in float32": lambda *a: _slerp_own(*a, dtype=np.float32),
    "the other sign": lambda *a: -SLERP(*a),
    "a list": lambda *a: list(SLERP(*a)),
})


# lessons 00, 02, 03 and 05: the usual wrong answers of their kind (an argument ignored, a convention slipped, an
# input changed in place), each refused; float32 and other right variants, each accepted

def _sol(lesson, name):
    return solution_function(find_lesson(lesson), name)


LOCAL, TO_QUAT, BONES = (_sol("00", "exercise_local_from_global"), _sol("00", "exercise_matrix_to_quat"),
                         _sol("00", "exercise_bone_drift"))


def _local_own(parents, global_rot, global_pos, order="parent first", offsets="parent frame", root="kept",
               one_pose=False, in_place=False, dtype=float):
    """A student's own FK undone, with the slips below as options."""
    Rg, Pg = (global_rot, global_pos) if in_place else (np.array(global_rot, dtype), np.array(global_pos, dtype))
    if one_pose:  # written for (J, 3, 3): the first axis taken for the joints
        L, O = Rg.copy(), Pg.copy()
        for j, p in enumerate(parents):
            if p >= 0:
                L[j], O[j] = Rg[p].T @ Rg[j], Rg[p].T @ (Pg[j] - Pg[p])
        return L, O
    L, O = (Rg, Pg) if in_place else (Rg.copy(), Pg.copy())
    for j in sorted(range(len(parents)), key=lambda j: -j if in_place else j):
        p = parents[j]
        if p < 0:
            if root == "zeroed":
                O[..., j, :] = 0.0
            continue
        Rp = Rg[..., p, :, :]
        RpT = np.swapaxes(Rp, -1, -2)
        Rj = Rg[..., j, :, :]
        L[..., j, :, :] = {"parent first": RpT @ Rj, "child first": Rj @ RpT,
                           "transposed": np.swapaxes(Rj, -1, -2) @ Rp}[order]
        d = Pg[..., j, :] - Pg[..., p, :]
        O[..., j, :] = {"parent frame": np.einsum("...ba,...b->...a", Rp, d), "world": d,
                        "own frame": np.einsum("...ba,...b->...a", Rj, d)}[offsets]
    return L, O


def _quat_own(R, method="largest", order="xyzw", transposed=False, keep_sign=False, flattened=False,
              in_place=False, dtype=float):
    """A student's own matrix-to-quaternion, with the slips below as options. ``method``: "largest" divides by the
    largest of the four components (Shepperd), "trace" by w always, "copysign" takes every component from its
    square root and the sign of an off-diagonal difference, "eigen" the top eigenvector of a symmetric 4 x 4 matrix
    built from ``R``. ``keep_sign``: the largest component made positive, as Shepperd's branches leave it, not w."""
    if in_place:  # "cleans" the caller's matrices first
        R[...] = np.round(R, 15)
    R = np.array(R, dtype)
    if transposed:
        R = np.swapaxes(R, -1, -2)
    m = R.reshape(-1, 3, 3)
    out = np.empty((len(m), 4), dtype)
    for i, r in enumerate(m):
        tr = np.trace(r)
        d = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
        if method == "trace":
            w = np.sqrt(max(1 + tr, 0.0)) / 2
            with np.errstate(divide="ignore", invalid="ignore"):
                q = np.append(d / (4 * w), w)
        elif method == "copysign":
            sq = np.sqrt(np.maximum([1 + 2 * r[0, 0] - tr, 1 + 2 * r[1, 1] - tr, 1 + 2 * r[2, 2] - tr, 1 + tr], 0)) / 2
            q = np.append(np.copysign(sq[:3], d), sq[3])
        elif method == "eigen":
            K = np.array([[r[0, 0] - r[1, 1] - r[2, 2], r[1, 0] + r[0, 1], r[2, 0] + r[0, 2], d[0]],
                          [r[1, 0] + r[0, 1], r[1, 1] - r[0, 0] - r[2, 2], r[2, 1] + r[1, 2], d[1]],
                          [r[2, 0] + r[0, 2], r[2, 1] + r[1, 2], r[2, 2] - r[0, 0] - r[1, 1], d[2]],
                          [d[0], d[1], d[2], tr]]) / 3
            q = np.linalg.eigh(K.astype(float))[1][:, -1]
        else:
            q = np.asarray(TO_QUAT(r), float)
        big = q[int(np.argmax(np.abs(q)))]
        if (big if keep_sign else q[3]) < 0:
            q = -q
        out[i] = q
    if order == "wxyz":
        out = out[:, [3, 0, 1, 2]]
    return out if flattened else out.reshape(R.shape[:-2] + (4,))


def _drift_own(parents, clip, root="skipped", signed=False, steps=False, reduce="max", in_place=False, dtype=float):
    """A student's own bone drift, with the slips below as options (``root="indexed"``: ``clip[:, parents]`` with
    the -1 of a root read as the last joint)."""
    if in_place:  # the caller's clip moved to its first frame's root
        clip -= clip[:1, :1]
    P = np.asarray(clip, dtype)
    par = np.asarray(parents)
    if root == "indexed":
        L = np.linalg.norm(P - P[:, par], axis=-1)
    else:
        L = np.where(par >= 0, np.linalg.norm(P - P[:, np.maximum(par, 0)], axis=-1), 0.0)
    d = np.diff(L, axis=0, prepend=L[:1]) if steps else L - L[:1]
    d = d if signed else np.abs(d)
    return (d.max(axis=0) if reduce == "max" else d.mean(axis=0)).astype(dtype)


BY_CHECKER["check_local_from_global"] = ({
    "rotations undone on the wrong side": (lambda *a: _local_own(*a, order="child first"),
                                           "R_loc = R_p^T R_j (the parent's inverse on the left)"),
    "the transposed local rotation": (lambda *a: _local_own(*a, order="transposed"), "is the transpose"),
    "the offset left in the world's frame": (lambda *a: _local_own(*a, offsets="world"),
                                             "offset is R_p^T (x_j - x_p), in the parent's frame"),
    "the offset turned by the joint's own rotation": (lambda *a: _local_own(*a, offsets="own frame"),
                                                      "case 1 differs: local_pos of joint"),
    "the root's position zeroed": (lambda *a: _local_own(*a, root="zeroed"), "a root keeps its global position"),
    "written for one pose": (lambda *a: _local_own(*a, one_pose=True), "case 2 "),
    "the caller's arrays overwritten": (lambda *a: _local_own(*a, in_place=True),
                                        "changed its input `global_rot` in place"),
}, {
    "the reference solution": LOCAL,
    "its own loop": _local_own,
    "in float32": lambda *a: _local_own(*a, dtype=np.float32),
    "one pose at a time": lambda par, G, P: tuple(np.stack(x) for x in zip(*(
        _local_own(par, g, p, one_pose=True) for g, p in zip(np.reshape(G, (-1,) + np.shape(G)[-3:]),
                                                              np.reshape(P, (-1,) + np.shape(P)[-2:]))))),
})
BY_CHECKER["check_matrix_to_quat"] = ({
    "the textbook formula, divided by w": (lambda R: _quat_own(R, method="trace"), "near a half-turn"),
    "every component from its own square root, signs copied": (lambda R: _quat_own(R, method="copysign"),
                                                                "w from its square root"),
    "scalar first, (w, x, y, z)": (lambda R: _quat_own(R, order="wxyz"), "the order is (x, y, z, w), scalar last"),
    "the inverse rotation's": (lambda R: _quat_own(R, transposed=True), "(x, y, z) has the wrong sign"),
    "w left negative": (lambda R: _quat_own(R, keep_sign=True), "w is negative"),
    "the batch axes not given back": (lambda R: _quat_own(R, flattened=True), "case 2 returned shape (1, 4)"),
    "the caller's R rounded in place": (lambda R: _quat_own(R, in_place=True), "changed its input `R` in place"),
}, {
    "the reference solution": TO_QUAT,
    "its own Shepperd": _quat_own,
    "the top eigenvector of a 4 x 4 matrix": lambda R: _quat_own(R, method="eigen"),
    "in float32": lambda R: _quat_own(R, dtype=np.float32),
})
BY_CHECKER["check_bone_drift"] = ({
    "the root's parent -1 used as an index": (lambda *a: _drift_own(*a, root="indexed"), "a root has no bone"),
    "growth only": (lambda *a: _drift_own(*a, signed=True), "a bone that shrinks drifts too"),
    "from one frame to the next": (lambda *a: _drift_own(*a, steps=True), "the drift is against the first frame"),
    "the mean over the clip": (lambda *a: _drift_own(*a, reduce="mean"), "case 1 differs"),
    "the caller's clip moved in place": (lambda *a: _drift_own(*a, in_place=True), "changed its input `clip` in place"),
}, {
    "the reference solution": BONES,
    "its own, vectorised": _drift_own,
    "in float32": lambda *a: _drift_own(*a, dtype=np.float32),
})

LOO, DLS_PRIOR = _sol("02", "exercise_gpr_loo"), _sol("02", "exercise_dls_prior")


def _loo_own(X, Y, theta0, theta1, leave_out=True, divide=True, square_theta0=True, reg=True, brute=False,
             centre_y=False, dtype=float):
    """A student's own leave-one-out, with the slips below as options (``dtype=None``: the inputs' own)."""
    if centre_y:
        Y -= Y.mean(axis=0)  # in the caller's array
    X, Y = np.asarray(X, dtype), np.asarray(Y, dtype)
    dtype = X.dtype
    t0 = theta0**2 if square_theta0 else theta0
    k = lambda A, B: np.sqrt(((A[:, None, :] - B[None, :, :]) ** 2).sum(-1) + t0)  # noqa: E731
    if brute:  # N fits: the same numbers, slower
        out = np.zeros_like(Y)
        for i in range(len(X)):
            r = np.arange(len(X)) != i
            out[i] = k(X[i:i + 1], X[r]) @ np.linalg.solve(k(X[r], X[r]) + theta1 * np.eye(len(X) - 1, dtype=dtype),
                                                         Y[r])
        return out
    G = k(X, X) + (theta1 * np.eye(len(X), dtype=dtype) if reg else 0)
    Gi = np.linalg.inv(G)
    alpha = Gi @ Y
    if not leave_out:
        return k(X, X) @ alpha
    return Y - (alpha / np.diag(Gi)[:, None] if divide else alpha)


def _prior_own(J, dx, y, yp, lam, w, square_w=True, pull=1.0, square_lam=True, use_w=True, lstsq=False,
               in_place=False, dtype=float):
    """A student's own damped step with a prior, with the slips below as options."""
    if in_place:
        y -= yp  # "work relative to the prior", in the caller's array
        y, yp = y, np.zeros_like(yp)
    J, dx, y, yp, w = (np.asarray(a, dtype) for a in (J, dx, y, yp, w))
    w = w if use_w else np.ones_like(w)
    lam2 = lam**2 if square_lam else lam
    if lstsq:  # one stacked least-squares problem: [J; lam W] dy = [dx; lam W (yp - y)]
        A = np.vstack([J, lam * np.diag(w)])
        return np.linalg.lstsq(A, np.concatenate([dx, lam * w * (yp - y)]), rcond=None)[0]
    W2 = w**2 if square_w else w
    return np.linalg.solve(J.T @ J + lam2 * np.diag(W2), J.T @ dx + pull * lam2 * W2 * (yp - y))


BY_CHECKER["check_gpr_loo"] = ({
    "the left-out pose kept in the fit": (lambda *a: _loo_own(*a, leave_out=False), "the left-out one included"),
    "alpha_i not divided by (G^-1)_ii": (lambda *a: _loo_own(*a, divide=False), "the residual is alpha_i / (G^-1)_ii"),
    "theta0 not squared": (lambda *a: _loo_own(*a, square_theta0=False), "theta0 = 0.5"),
    "theta1 left off": (lambda *a: _loo_own(*a, reg=False), "theta1 left off G"),
    "the caller's Y centred in place": (lambda *a: _loo_own(*a, centre_y=True), "changed its input `Y` in place"),
}, {
    "the reference solution": LOO,
    "its own closed form": _loo_own,
    "N fits": lambda *a: _loo_own(*a, brute=True),
    "in the inputs' own dtype (float32 in, float32 out)": lambda *a: _loo_own(*a, dtype=None),
})
BY_CHECKER["check_dls_prior"] = ({
    "the weights not squared": (lambda *a: _prior_own(*a, square_w=False), "the weights not squared"),
    "no pull towards the prior": (lambda *a: _prior_own(*a, pull=0.0), "the pull towards y_prior missing"),
    "the pull reversed": (lambda *a: _prior_own(*a, pull=-1.0), "the pull points away from y_prior"),
    "the damping not squared": (lambda *a: _prior_own(*a, square_lam=False), "the damping not squared"),
    "the weights ignored": (lambda *a: _prior_own(*a, use_w=False), "the weights ignored"),
    "the caller's y moved in place": (lambda *a: _prior_own(*a, in_place=True), "changed its input `y` in place"),
}, {
    "the reference solution": DLS_PRIOR,
    "the normal equations": _prior_own,
    "one stacked least-squares problem": lambda *a: _prior_own(*a, lstsq=True),
    "in float32": lambda *a: _prior_own(*a, dtype=np.float32),
})

POSE_VECTOR, FROM_VECTOR, AUTHORS_LOSS = (_sol("03", "exercise_pose_vector"), _sol("03", "exercise_pose_from_vector"),
                                         _sol("03", "exercise_authors_loss"))


def _vector_own(skeleton, global_pos, turn=-1.0, keep_height=True, helper=False, in_place=False, dtype=float):
    """A student's own pose vector, with the slips below as options."""
    from posekit.data.metrics import body_joints
    from posekit.transforms import facing_angle

    P = global_pos if in_place else np.array(global_pos, dtype)
    P -= P[skeleton.index("pelvis")] * (np.array([1.0, 0.0, 1.0], dtype) if keep_height else 1.0)
    a = turn * float(facing_angle(skeleton, P))
    c, s = np.cos(a), np.sin(a)
    local = P @ np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]], dtype)  # rows turned by Ry(a)
    joints = np.arange(skeleton.n_joints) if helper else body_joints(skeleton)
    return local[joints].ravel().astype(dtype)


def _from_vector_own(skeleton, x, origin, angle, sign=1.0, add_origin=True, helper="rest", shift_first=False,
                     in_place=False):
    """A student's own vector -> world pose (posekit's rotate_y convention), with the slips below as options."""
    pel = int(skeleton.pelvis())
    above = [] if pel == 0 else [0]  # the helper root of the two skeletons here is joint 0
    body = [j for j in range(skeleton.n_joints) if j not in above]
    if in_place:
        x *= 1.0
        x.shape = (len(body), 3)  # reshaped in the caller's array
    local = np.zeros((skeleton.n_joints, 3))
    local[body] = np.reshape(x, (len(body), 3))
    if above and helper == "rest":
        local[0] = local[pel] - skeleton.offsets[pel]
    a = sign * float(angle)
    c, s_ = np.cos(a), np.sin(a)
    turn = np.array([[c, 0.0, s_], [0.0, 1.0, 0.0], [-s_, 0.0, c]])
    if shift_first:
        return (local + origin) @ turn.T
    return local @ turn.T + (np.asarray(origin, float) if add_origin else 0.0)


def _authors_own(decoded, target, columns, w, weight_others=False, two=True, mean=True, k_form="right",
                 in_place=False, dtype=float):
    """A student's own weighted loss, with the slips below as options."""
    d = decoded if in_place else np.asarray(decoded, dtype)
    t = np.asarray(target, dtype)
    N, F = d.shape
    m = np.ones(F, dtype)
    if weight_others:
        m[:] = w
        m[list(columns)] = 1.0
    else:
        m[list(columns)] = w
    if in_place:
        d -= t
        diff = d
    else:
        diff = d - t
    T = len(columns)
    loss = np.mean(m * diff**2) if mean else np.sum(m * diff**2)
    grad = (2.0 if two else 1.0) * m * diff / (N * F if mean else 1)
    k = {"right": (F - T) / (w * T), "1/w": 1.0 / w}[k_form]
    return loss, grad.astype(dtype), k


BY_CHECKER["check_pose_vector"] = ({
    "turned by plus the facing angle": (lambda *a: _vector_own(*a, turn=1.0), "turned the wrong way"),
    "not turned": (lambda *a: _vector_own(*a, turn=0.0), "not turned: the root frame faces +Z"),
    "the pelvis's height taken off": (lambda *a: _vector_own(*a, keep_height=False), "so heights are kept"),
    "the helper root kept": (lambda *a: _vector_own(*a, helper=True), "case 1 returned shape (66,), expected (63,)"),
    "the caller's pose moved in place": (lambda *a: _vector_own(*a, in_place=True),
                                         "changed its input `global_pos` in place"),
}, {
    "the reference solution": POSE_VECTOR,
    "its own": _vector_own,
    "in float32": lambda *a: _vector_own(*a, dtype=np.float32),
})
BY_CHECKER["check_pose_from_vector"] = ({
    "turned the wrong way": (lambda *a: _from_vector_own(*a, sign=-1.0), "turned the wrong way"),
    "origin not added": (lambda *a: _from_vector_own(*a, add_origin=False), "not moved to origin"),
    "moved before turning": (lambda *a: _from_vector_own(*a, shift_first=True), "moved before turning"),
    "the helper root left at the origin": (lambda *a: _from_vector_own(*a, helper="zero"),
                                           "put it back at its rest offset from the pelvis"),
    "the caller's x reshaped in place": (lambda *a: _from_vector_own(*a, in_place=True),
                                         "changed its input `x` in place"),
}, {
    "the reference solution": FROM_VECTOR,
    "its own": _from_vector_own,
    "in float32": lambda *a: _from_vector_own(*a).astype(np.float32),
})
BY_CHECKER["check_authors_loss"] = ({
    "the weight on the other columns": (lambda *a: _authors_own(*a, weight_others=True), "the loss is"),
    "a sum, not a mean": (lambda *a: _authors_own(*a, mean=False), "one mean over all N x F squared errors"),
    "the gradient without its 2": (lambda *a: _authors_own(*a, two=False), "d(u^2)/du = 2u"),
    "k = 1 / w": (lambda *a: _authors_own(*a, k_form="1/w"), "read k off"),
    "the caller's decoded poses changed in place": (lambda *a: _authors_own(*a, in_place=True),
                                                     "changed its input `decoded` in place"),
}, {
    "the reference solution": AUTHORS_LOSS,
    "its own": _authors_own,
    "in float32": lambda *a: _authors_own(*a, dtype=np.float32),
})

LOOK_AT, ROT_NOISE, INPUTS = (_sol("05", "exercise_look_at_angle"), _sol("05", "exercise_rotation_noise"),
                              _sol("05", "exercise_effector_inputs"))


def _look_own(R, v, t, p, form="atan2", transpose=False, from_origin=False, degrees=False, in_place=False,
              dtype=float):
    """A student's own look-at angle, with the slips below as options."""
    if in_place:
        v /= np.linalg.norm(v, axis=-1, keepdims=True)  # normalised in the caller's array
    R, v, t, p = (np.asarray(x, dtype) for x in (R, v, t, p))
    a = np.einsum("nji,nj->ni" if transpose else "nij,nj->ni", R, v)
    b = t if from_origin else t - p
    if form == "atan2":
        ang = np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("ni,ni->n", a, b))
    elif form == "kahan":  # 2 atan2(|a^ - b^|, |a^ + b^|)
        a_, b_ = a / np.linalg.norm(a, axis=-1, keepdims=True), b / np.linalg.norm(b, axis=-1, keepdims=True)
        ang = 2 * np.arctan2(np.linalg.norm(a_ - b_, axis=-1), np.linalg.norm(a_ + b_, axis=-1))
    else:
        c = np.einsum("ni,ni->n", a, b) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
        with np.errstate(invalid="ignore"):  # a cosine rounded past 1: NaN, the slip the checker names
            ang = np.arccos(np.clip(c, -1, 1) if form == "arccos clipped" else c)
    return np.degrees(ang) if degrees else ang


def _noise_own(R, n, lam, side="left", sign=1.0, eta=13, scale=True, guard=True, in_place=False, dtype=float):
    """A student's own rotation noise, with the slips below as options."""
    if in_place:
        n *= 0.1 * np.asarray(lam)[:, None] ** 13  # scaled in the caller's array
        lam = np.ones_like(lam)
    R, n, lam = (np.asarray(x, dtype) for x in (R, n, lam))
    w = sign * (0.1 * lam[:, None] ** eta if scale else 1.0) * n
    out = []
    for r, wi in zip(R, w):
        theta = np.linalg.norm(wi)
        if guard and theta == 0:
            out.append(r)
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            k = wi / theta
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]], dtype)
        E = np.eye(3, dtype=dtype) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K
        out.append(E @ r if side == "left" else r @ E)
    return np.stack(out)


def _inputs_own(kind, value, lam, weight="1 - lam", counted=(0,), moved=(0, 2), columns=3, per_request=True,
                guard=True, torch_style=False, in_place=False, dtype=float):
    """A student's own centroid and inputs, with the slips below as options (``torch_style``: the library's
    branch-free form, ``sum / max(s, 1e-9) * (s > 0)``)."""
    kind = np.asarray(kind)
    lam = np.asarray(lam, dtype)
    val = value if in_place else np.array(value, dtype)
    w = np.isin(kind, counted) * {"1 - lam": 1 - lam + dtype(1e-3), "lam": lam, "no 1e-3": 1 - lam}[weight]
    if per_request:
        s = w.sum(axis=1)[:, None]
        total = (w[..., None] * val[..., :3]).sum(axis=1)
    else:
        s = np.full((len(kind), 1), w.sum())
        total = np.broadcast_to((w[..., None] * val[..., :3]).sum(axis=(0, 1)), (len(kind), 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        if torch_style:
            c = total / np.maximum(s, 1e-9) * (s > 0)
        else:
            c = np.where(s > 0, total / s, 0.0) if guard else total / s
    out = val
    out[..., :columns] -= np.isin(kind, moved)[..., None] * np.tile(c, 2)[:, None, :columns]
    return c.astype(dtype), out


BY_CHECKER["check_look_at_angle"] = ({
    "arccos of the clipped cosine": (lambda *a: _look_own(*a, form="arccos clipped"), "arccos loses digits"),
    "arccos unclipped": (lambda *a: _look_own(*a, form="arccos"), "case 2 differs"),
    "R^T v": (lambda *a: _look_own(*a, transpose=True), "R turns it into the world's (R v)"),
    "the target, not t - p": (lambda *a: _look_own(*a, from_origin=True), "the direction from the joint to it"),
    "degrees": (lambda *a: _look_own(*a, degrees=True), "the loss is in radians"),
    "the caller's v normalised in place": (lambda *a: _look_own(*a, in_place=True), "changed its input `v` in place"),
}, {
    "the reference solution": LOOK_AT,
    "atan2 of the cross and dot products": _look_own,
    "Kahan's 2 atan2(|a - b|, |a + b|)": lambda *a: _look_own(*a, form="kahan"),
    "in float32": lambda *a: _look_own(*a, dtype=np.float32),
})
BY_CHECKER["check_rotation_noise"] = ({
    "turned in the joint's frame": (lambda *a: _noise_own(*a, side="right"), "the noise turns the world rotation"),
    "turned the other way": (lambda *a: _noise_own(*a, sign=-1.0), "turned the other way"),
    "eta forgotten": (lambda *a: _noise_own(*a, eta=1), "the power eta = 13 forgotten"),
    "n not scaled": (lambda *a: _noise_own(*a, scale=False), "n not scaled by sigma"),
    "no guard at sigma = 0": (lambda *a: _noise_own(*a, guard=False), "there is no axis"),
    "the caller's n scaled in place": (lambda *a: _noise_own(*a, in_place=True), "changed its input `n` in place"),
}, {
    "the reference solution": ROT_NOISE,
    "its own Rodrigues": _noise_own,
    "in float32": lambda *a: _noise_own(*a, dtype=np.float32),
})
BY_CHECKER["check_effector_inputs"] = ({
    "weighted by lam": (lambda *a: _inputs_own(*a, weight="lam"), "not Lambda"),
    "without the 1e-3": (lambda *a: _inputs_own(*a, weight="no 1e-3"), "without the 1e-3 a loose effector"),
    "look-at targets in the centroid": (lambda *a: _inputs_own(*a, counted=(0, 2)), "look-at targets counted"),
    "one centroid for the batch": (lambda *a: _inputs_own(*a, per_request=False), "each request has its own"),
    "rotations moved": (lambda *a: _inputs_own(*a, moved=(0, 1, 2)), "a rotation's 6D moved"),
    "look-at targets left": (lambda *a: _inputs_own(*a, moved=(0,)), "a look-at target left where it was"),
    "all six values moved": (lambda *a: _inputs_own(*a, columns=6), "the last three values moved too"),
    "no guard for a request without positions": (lambda *a: _inputs_own(*a, guard=False),
                                                 "it has no position effector: its centroid is the origin"),
    "the caller's values moved in place": (lambda *a: _inputs_own(*a, in_place=True),
                                           "changed its input `value` in place"),
}, {
    "the reference solution": INPUTS,
    "its own": _inputs_own,
    "the library's branch-free form": lambda *a: _inputs_own(*a, torch_style=True),
    "in float32": lambda *a: _inputs_own(*a, dtype=np.float32),
})


@pytest.mark.parametrize("checker,slip", _all_wrong())
def test_each_checker_refuses_each_wrong_answer_and_says_why(checker, slip, capsys):
    answer, said = BY_CHECKER[checker][0][slip]
    assert _checker(checker)(answer) is False
    out = capsys.readouterr().out
    assert said in out, out


@pytest.mark.parametrize("checker,variant", _all_right())
def test_each_checker_accepts_each_right_variant(checker, variant, capsys):
    assert _checker(checker)(BY_CHECKER[checker][1][variant]) is True, capsys.readouterr().out


# -- the fresh check's executors: forked from a template that ran the lesson's imports once -------------------------

KILLS_ITS_TEMPLATE = '''
import os, signal
os.kill(os.getppid(), signal.SIGKILL)          # the process it was forked from: the next answers' template
def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    raise NotImplementedError
'''

PRINTS_A_LOT = '''
print("x" * 300_000)                           # more than a pipe holds: nothing may wait on it
''' + inspect.getsource(PLANTED)

LOOPS = '''
def exercise_fabrik_planted(positions, target, tolerance, max_iter):
    import time
    while True:                                  # asleep: the timeout ends it, without a busy core meanwhile
        time.sleep(1)
'''

LEAVES_A_DAEMON = '''
import os, time
if os.fork() == 0:                              # a child that outlives the answer, in the answer's session
    time.sleep(600)
    os._exit(0)
''' + inspect.getsource(PLANTED)


def test_each_answer_runs_in_a_fresh_fork_and_a_killed_template_costs_no_one_a_point():
    """One judge checks a lesson's answers one after another, each in an executor forked from a template that ran the
    lesson's imports once: an answer that kills the template, prints more than a pipe holds, loops or leaves a
    process behind fails or passes on its own merit, and the answers after it are checked as before (spawned,
    once the template is gone)."""
    from posekit.course.grading import fresh_checks

    right = inspect.getsource(PLANTED)
    job = lambda source: {"lesson": "01", "checker": "check_fabrik_planted", "function": "exercise_fabrik_planted",
                          "source": source, "imports": "import numpy as np"}
    t0 = time.perf_counter()
    got = fresh_checks([job(s) for s in (right, LEAVES_A_DAEMON, right, KILLS_ITS_TEMPLATE, right, PRINTS_A_LOT,
                                         LOOPS, right)], timeout_s=8)
    assert [f.passed for f in got] == [True, True, True, False, True, True, False, True], [f.said for f in got]
    assert "not attempted" in got[3].said and "ran past 8 s" in got[6].said
    assert "x" * 1000 in got[5].said
    assert time.perf_counter() - t0 < 120          # the daemon's sleep was not waited for


def test_an_answer_cannot_reach_the_template_nor_another_answer():
    """The template is not dumpable (its forks inherit that: an executor reads its own flag), so no process of the
    same user may trace it or read its memory -- checked directly where the tests do not run as root, whom nothing
    stops; and what one answer defines is not in the next answer's namespace."""
    from posekit.course.grading import fresh_checks

    reads_template = '''
import ctypes, os
if ctypes.CDLL(None).prctl(3, 0, 0, 0, 0) != 0:         # PR_GET_DUMPABLE: as the template was when it forked
    raise SystemExit("the template is dumpable")
if os.geteuid() != 0:
    try:
        with open(f"/proc/{os.getppid()}/mem", "rb"):
            raise SystemExit("opened the template's memory")
    except PermissionError:
        pass
LEFT_BEHIND = 1
''' + inspect.getsource(PLANTED)
    looks_for_it = '''
assert "LEFT_BEHIND" not in globals(), "another answer's name is here"
''' + inspect.getsource(PLANTED)
    job = lambda source: {"lesson": "01", "checker": "check_fabrik_planted", "function": "exercise_fabrik_planted",
                          "source": source, "imports": "import numpy as np"}
    got = fresh_checks([job(reads_template), job(looks_for_it)], timeout_s=60)
    assert [f.passed for f in got] == [True, True], [f.said for f in got]


OWN_HELPERS = {  # checker: a helper of the checker's own module that gives the right answer with its defaults
    "check_bone_drift": ("posekit.exercises.nb00", "_drift_with"),
    "check_pose_vector": ("posekit.exercises.nb03", "_pose_vector_with"),
    "check_effector_inputs": ("posekit.exercises.nb05", "_inputs_with"),
}


@pytest.mark.parametrize("checker", OWN_HELPERS)
def test_an_answer_that_calls_its_checkers_own_helpers_is_refused(checker, capsys):
    """Each checker's module holds the variants its messages compare with; with their defaults some give the right
    answer. The judge forbids every function of that module, not only the posekit function compared against."""
    import importlib

    module, name = OWN_HELPERS[checker]
    helper = getattr(importlib.import_module(module), name)
    assert _checker(checker)(lambda *a: helper(*a)) is False
    assert f"calls {helper.__module__}.{helper.__name__}" in capsys.readouterr().out
