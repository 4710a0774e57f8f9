"""The posing session without a browser or a widget (``posekit.studio``): what an edit, a selection, undo and redo,
a setup, a refusal and the timeline do to the one list of effectors, and what the status says with none."""

from __future__ import annotations

import numpy as np
import pytest

from posekit.data import load_bandai_mini
from posekit.data.cases import build_cases
from posekit.ik import Effector, effector_set, make_solver
from posekit.studio import NO_EFFECTORS, NO_EFFECTORS_SUMMARY, PosingSession, honoured, solve_honoured


class Clock:
    """A clock the test moves by hand (no timed test: the coalescing window is crossed by setting the time)."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


@pytest.fixture(scope="module")
def bandai():
    m = load_bandai_mini()
    return m.skeleton, build_cases(m, 2, seed=0, start="same-clip")


@pytest.fixture
def session(bandai):
    s, cases = bandai
    clock = Clock()
    solvers = {n: make_solver(n, s) for n in ("fabrik", "dls")}
    out = PosingSession(s, cases.pose(0), solvers, effector_set(s, "2", cases.target_pos[0]), clock=clock)
    out.test_clock = clock
    return out


def test_selecting_never_adds_an_effector_an_edit_does(session):
    before, updates = session.setup(), session.updates
    seen = []
    session.on_change(lambda what, i: seen.append(what))
    for joint in ("Head", "Spine", "Hand_R", "Foot_L"):  # passing over joints (arrow keys in the list)
        session.select(joint)
    assert session.setup() == before and session.updates == updates and session.position == 0
    assert session.selected == "Foot_L" and seen == ["select"] * 4
    i = session.move("Foot_L", [0.1, 0.05, 0.2])
    assert session.effectors[i].joint == "Foot_L" and session.effectors[i].kind == "position"
    assert len(session.effectors) == len(before) + 1 and session.position == 1 and seen[-1] == "add"
    np.testing.assert_allclose(session.effectors[i].target, [0.1, 0.05, 0.2])


def test_move_updates_the_one_stored_target_and_solves(session):
    hand = session.effectors[0].joint
    goal = session.effectors[0].target + [0.0, 0.05, 0.0]
    n, updates = len(session.effectors), session.updates
    assert session.move(hand, goal) == 0
    assert len(session.effectors) == n and session.updates == updates + 1
    np.testing.assert_allclose(session.markers()[0][hand], goal)  # what the views draw is the stored target
    assert session.markers()[0][hand] is session.effectors[0].target
    for name in session.solvers:
        assert session.results[name].converged
        assert "reached" in session.view_status(name)


def test_undo_redo_steps_and_coalesced_moves(session):
    clock, hand = session.test_clock, session.effectors[0].joint
    p0 = session.effectors[0].target.copy()
    for k in range(5):  # a drag: five moves close in time are one step
        clock.now += 0.1
        session.move(hand, p0 + [0.0, 0.01 * (k + 1), 0.0])
    assert session.position == 1 and len(session.history) == 2
    clock.now += 5.0  # a pause: the next move is a step of its own
    session.move(hand, p0 + [0.0, 0.1, 0.0])
    session.set_tolerance(1, 0.5)
    session.add("Head", "look_at")
    assert session.position == 4 and session.can_undo and not session.can_redo
    assert session.undo() and len(session.effectors) == 2  # the look-at goes
    assert session.undo() and session.effectors[1].lam == 0.0
    assert session.undo()
    np.testing.assert_allclose(session.effectors[0].target, p0 + [0.0, 0.05, 0.0])
    assert session.undo() and not session.can_undo and not session.undo()
    np.testing.assert_allclose(session.effectors[0].target, p0)
    assert session.redo() and session.redo() and session.redo() and session.redo() and not session.redo()
    assert [e.kind for e in session.effectors] == ["position", "position", "look_at"]
    session.undo()
    session.remove(0)  # a new step after an undo drops the redo steps
    assert not session.can_redo and [e.joint for e in session.effectors] == [session.history[-1][0]["joint"]]


def test_a_drag_is_one_step_however_slow_its_moves(session):
    """A drag (press to release) is one undo step even when its moves come more than ``coalesce_s`` apart (a slow
    machine solving every view between them, or a hand held still); the change after it is a step of its own."""
    clock, hand = session.test_clock, session.effectors[0].joint
    p0 = session.effectors[0].target.copy()
    session.begin_drag()
    for k in range(4):
        clock.now += 3.0  # far beyond the coalescing window
        session.move(hand, p0 + [0.0, 0.02 * (k + 1), 0.0])
    session.end_drag()
    assert session.position == 1 and len(session.history) == 2
    clock.now += 0.1  # a slider press right after the release: not part of the drag
    session.move(hand, p0 + [0.0, 0.081, 0.0])
    assert session.position == 2
    session.undo()
    np.testing.assert_allclose(session.effectors[0].target, p0 + [0.0, 0.08, 0.0])
    session.undo()
    np.testing.assert_allclose(session.effectors[0].target, p0)
    # a drag that creates its target (an add, then moves) is one step too
    n = len(session.effectors)
    session.begin_drag()
    for k in range(3):
        clock.now += 2.0
        session.move("Head", [0.0, 1.6 + 0.01 * k, 0.1])
    session.end_drag()
    assert session.position == 1 and len(session.effectors) == n + 1
    session.undo()
    assert len(session.effectors) == n and not session.can_undo


def test_an_undo_during_a_drag_leaves_the_rest_of_it_a_new_step(session):
    clock, hand = session.test_clock, session.effectors[0].joint
    p0 = session.effectors[0].target.copy()
    session.begin_drag()
    session.move(hand, p0 + [0.0, 0.01, 0.0])
    session.undo()  # Ctrl+Z with the mouse still down
    clock.now += 0.1
    session.move(hand, p0 + [0.0, 0.02, 0.0])
    session.end_drag()
    assert session.position == 1 and len(session.history) == 2
    np.testing.assert_allclose(session.history[0][0]["target"], p0)


def test_notes_follow_the_steps(session):
    session.on_before_change(lambda what, i: session.notes[session.position].update(seen=session.position))
    session.add("Head", "rotation")
    assert session.notes[0] == {"seen": 0} and len(session.notes) == len(session.history) == 2
    session.undo()
    session.remove(0)
    assert len(session.notes) == len(session.history) == 2


def test_setup_round_trip_and_refusals_change_nothing(session, bandai):
    s, cases = bandai
    session.add("Head", "look_at", lam=0.3)
    k = session.add("Spine", "rotation")
    session.set_rotation(k, 30, -10, 5)
    doc = session.to_dict()
    assert doc["solvers"] == ["fabrik", "dls"] and [r["kind"] for r in doc["effectors"]][-2:] == ["look_at", "rotation"]
    other = PosingSession(s, cases.pose(0), {"dls": make_solver("dls", s)})
    other.from_dict(doc)
    assert other.setup() == session.setup()
    np.testing.assert_allclose(other.effectors[-1].rotation, session.effectors[-1].rotation, atol=1e-12)
    before, position = session.setup(), session.position
    bad = [({"joint": "Nope", "kind": "position", "target": [0, 0, 0]}, "effector 2: unknown joint"),
           ({"joint": "Head", "kind": "spin"}, "unknown kind"),
           ({"joint": "Head", "kind": "position"}, "needs 'target'"),
           ({"joint": "Head", "kind": "position", "target": [0, np.nan, 0]}, "finite"),
           ({"joint": "Head", "kind": "position", "target": [0, 0, 0], "lam": 2}, "tolerance"),
           ({"joint": "Head", "kind": "rotation", "base": np.diag([1, 1, -1.0]).tolist()}, "not a rotation"),
           ({"joint": "Head", "kind": "look_at", "target": [0, 0, 1], "axis": [0, 0, 0]}, "must not be zero")]
    for row, says in bad:
        with pytest.raises(ValueError, match=says):
            session.from_dict({"effectors": [doc["effectors"][0], row]})
        assert session.setup() == before and session.position == position
    with pytest.raises(ValueError, match="already has a look-at"):
        session.from_dict([{"joint": "Head", "kind": "look_at", "target": [0, 0, 1], "axis": [0, 0, 1]},
                           {"joint": "Head", "kind": "rotation", "base": np.eye(3).tolist()}])
    assert session.setup() == before


def test_edits_refuse_bad_input_with_a_sentence(session):
    before = session.setup()
    hand = session.effectors[0].joint
    for call, says in ((lambda: session.move(hand, [0, np.inf, 0]), "NaN or inf"),
                       (lambda: session.move("Head", [0, 1, 0], "look_at"), "no look-at effector"),
                       (lambda: session.add(hand, "position"), "already has a position"),
                       (lambda: session.add("Head", "wave"), "unknown effector kind"),
                       (lambda: session.add(session.skeleton.names[0], "position"), "helper joint"),
                       (lambda: session.set_tolerance(0, 1.5), r"\[0, 1\]"),
                       (lambda: session.set_tolerance(9, 0.5), "no effector 9"),
                       (lambda: session.set_rotation(0, 10), "not a rotation"),
                       (lambda: session.remove(7), "no effector 7")):
        with pytest.raises(ValueError, match=says):
            call()
    assert session.setup() == before and session.position == 0


def test_with_no_effectors_the_status_and_summary_say_so(session):
    assert all(not isinstance(r, Exception) and r.converged for r in session.results.values())
    while session.effectors:
        session.remove(0)
    assert session.results == {} and session.times == {}  # no result of an earlier solve is kept
    for name in session.solvers:
        assert session.view_status(name) == NO_EFFECTORS
    rows = session.summary_rows()
    assert [r[0] for r in rows] == ["fabrik", "dls"] and all(r[1:] == (NO_EFFECTORS_SUMMARY,) for r in rows)
    assert not any("reached" in str(c) for r in rows for c in r)
    session.undo()
    assert len(session.results) == 2 and all("reached" in session.view_status(n) for n in session.solvers)


def test_timeline_keys_need_the_same_effectors(session):
    assert session.add_key() == 1
    session.move(session.effectors[0].joint, session.effectors[0].target + 0.05)
    assert session.add_key() == 2
    assert [len(k) for k in session.key_effectors("fabrik")] == [2, 2]
    session.add("Head", "look_at")
    with pytest.raises(ValueError, match="same effectors as the first"):
        session.add_key()
    assert len(session.keys) == 2 and [len(k) for k in session.key_effectors("fabrik")] == [2, 2]
    session.clear_keys()
    while session.effectors:
        session.remove(0)
    with pytest.raises(ValueError, match="add an effector before adding a key"):
        session.add_key()


def test_one_solve_with_the_kinds_a_solver_honours(bandai):
    s, cases = bandai
    fabrik = make_solver("fabrik", s)
    P = cases.pose(0).global_pos
    effs = [Effector("Hand_L", P[s.index("Hand_L")]), Effector("Head", P[s.index("Head")] + [0, 0, 1], "look_at",
                                                                     axis=[0, 0, 1])]
    used, ignored = honoured(fabrik, effs)
    assert used == [0] and [e.kind for e in ignored] == ["look_at"]
    done = solve_honoured(fabrik, cases.pose(0), effs)
    assert done.result.kinds == ("position",) and done.used == [0] and done.ms > 0
    assert solve_honoured(fabrik, cases.pose(0), effs[1:]).result is None  # nothing it honours: nothing solved

    class Refuses:
        kinds, needs_start = ("position",), True

        def solve(self, start, effectors):
            raise ValueError("not trained for this joint set")

    assert isinstance(solve_honoured(Refuses(), cases.pose(0), effs).result, ValueError)
